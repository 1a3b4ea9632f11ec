//! Building the hierarchy BVH: the scene tree → an owned tree of boxes
//! (dropping what holds nothing, skipping single-child nodes, splitting
//! meshes and wide groups) → the flat node array.

use super::{HierarchyBvh, Kind, Node, SceneTree, MAX_CHILDREN, MAX_LEAF, NO_SPACE};
use crate::accel::overlap::{bounds_of, margin, padded};
use crate::math::{Aabb, Mat4, Vec3};
use crate::primitive::Primitive;
use crate::shape::Shape;

/// The owned tree, before flattening.
enum Draft {
    Inner {
        bounds: Aabb,
        children: Vec<Draft>,
        /// Object-to-world and world-to-object matrices of a transform node
        /// that carries the ray.
        space: Option<(Mat4, Mat4)>,
    },
    Leaf {
        bounds: Aabb,
        ids: Vec<u32>,
        object_space: bool,
    },
}

impl Draft {
    fn bounds(&self) -> Aabb {
        match self {
            Draft::Inner { bounds, .. } | Draft::Leaf { bounds, .. } => *bounds,
        }
    }

    /// Whether a leaf below, before any other carrying transform, tests in
    /// the nearest transform's space.
    fn uses_space(&self) -> bool {
        match self {
            Draft::Leaf { object_space, .. } => *object_space,
            Draft::Inner { space: Some(_), .. } => false,
            Draft::Inner { children, .. } => children.iter().any(Draft::uses_space),
        }
    }
}

fn inner(children: Vec<Draft>, space: Option<(Mat4, Mat4)>) -> Draft {
    let bounds = children
        .iter()
        .fold(Aabb::EMPTY, |b, c| b.union(&c.bounds()));
    Draft::Inner {
        bounds,
        children,
        space,
    }
}

/// Splits `items` into two halves at the median of their box centres along
/// the longest axis of the centres (a partial sort: `select_nth`, O(n)).
fn halve<T>(mut items: Vec<T>, centre: impl Fn(&T) -> Vec3) -> (Vec<T>, Vec<T>) {
    let spread = items
        .iter()
        .fold(Aabb::EMPTY, |b, x| b.grow(centre(x)))
        .extent();
    let axis = if spread.x >= spread.y && spread.x >= spread.z {
        0
    } else if spread.y >= spread.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| centre(a)[axis].total_cmp(&centre(b)[axis]));
    let right = items.split_off(mid);
    (items, right)
}

/// One node over `kids`: a wide list is halved until each node has at most
/// [`MAX_CHILDREN`].
fn bundle(mut kids: Vec<Draft>) -> Draft {
    if kids.len() == 1 {
        return kids.pop().expect("one child");
    }
    if kids.len() <= MAX_CHILDREN {
        return inner(kids, None);
    }
    let (a, b) = halve(kids, |d| d.bounds().center());
    inner(vec![bundle(a), bundle(b)], None)
}

struct Builder<'a> {
    prims: &'a [Primitive],
    /// Ids still to place (bounded, and not yet met in the tree).
    wanted: Vec<bool>,
    /// Centre of each primitive's box (computed once: the median splits
    /// compare them many times).
    centres: Vec<Vec3>,
    margin: f32,
}

impl Builder<'_> {
    fn convert(&mut self, t: &SceneTree, space: Option<&Mat4>) -> Option<Draft> {
        match t {
            SceneTree::Group(children) => {
                let kids: Vec<Draft> = children
                    .iter()
                    .filter_map(|c| self.convert(c, space))
                    .collect();
                (!kids.is_empty()).then(|| bundle(kids))
            }
            SceneTree::Transform {
                to_world,
                to_object,
                child,
            } => {
                let c = self.convert(child, Some(to_world))?;
                if !c.uses_space() {
                    return Some(c); // a box like its child's: skip the node
                }
                let kids = match c {
                    Draft::Inner {
                        children,
                        space: None,
                        ..
                    } => children,
                    other => vec![other],
                };
                Some(inner(kids, Some((*to_world, *to_object))))
            }
            SceneTree::Shape(range) => {
                let ids: Vec<u32> = range
                    .clone()
                    .filter(|&i| {
                        let w = self.wanted.get(i as usize).copied().unwrap_or(false);
                        if w {
                            self.wanted[i as usize] = false;
                        }
                        w
                    })
                    .collect();
                (!ids.is_empty()).then(|| self.split(ids, space))
            }
        }
    }

    /// A mesh's (or a shape's) primitives: halved at the median centroid
    /// until leaves hold at most [`MAX_LEAF`].
    fn split(&self, ids: Vec<u32>, space: Option<&Mat4>) -> Draft {
        if ids.len() <= MAX_LEAF {
            let bounds = ids.iter().fold(Aabb::EMPTY, |b, &i| {
                b.union(&padded(&self.prims[i as usize].bounds(), self.margin))
            });
            let object_space = space.is_some_and(|m| {
                ids.iter().all(|&i| {
                    matches!(&self.prims[i as usize].shape,
                        Shape::Transformed(x) if x.to_world == *m)
                })
            });
            return Draft::Leaf {
                bounds,
                ids,
                object_space,
            };
        }
        let (a, b) = halve(ids, |&i| self.centres[i as usize]);
        inner(vec![self.split(a, space), self.split(b, space)], None)
    }
}

/// Writes `d` into slot `k` (children into fresh contiguous slots).
fn flatten(d: Draft, k: usize, depth: usize, out: &mut HierarchyBvh) {
    out.depth = out.depth.max(depth);
    match d {
        Draft::Leaf {
            bounds,
            ids,
            object_space,
        } => {
            out.nodes[k] = Node {
                bounds,
                kind: Kind::Leaf {
                    start: out.ids.len() as u32,
                    count: ids.len() as u32,
                    object_space,
                },
            };
            out.ids.extend(ids);
        }
        Draft::Inner {
            bounds,
            children,
            space,
        } => {
            let first = out.nodes.len();
            let space = space.map_or(NO_SPACE, |(_, to_object)| {
                // The matrix the wrappers below carry rays with (inverted in
                // f64 by the flattener, as `Transformed::from_f64` does), so
                // object rays (and hits) are bit-identical.
                out.spaces.push(to_object);
                out.spaces.len() as u32 - 1
            });
            out.nodes[k] = Node {
                bounds,
                kind: Kind::Inner {
                    first: first as u32,
                    count: children.len() as u32,
                    space,
                },
            };
            out.nodes.extend(children.iter().map(|c| Node {
                bounds: c.bounds(),
                kind: Kind::Leaf {
                    start: 0,
                    count: 0,
                    object_space: false,
                },
            }));
            for (i, c) in children.into_iter().enumerate() {
                flatten(c, first + i, depth + 1, out);
            }
        }
    }
}

pub(super) fn build(prims: &[Primitive], ids: &[u32], tree: &SceneTree) -> HierarchyBvh {
    let bounds = bounds_of(prims, ids);
    let mut wanted = vec![false; prims.len()];
    for &i in ids {
        wanted[i as usize] = true;
    }
    let mut b = Builder {
        prims,
        wanted,
        centres: prims.iter().map(|p| p.bounds().center()).collect(),
        margin: margin(&bounds),
    };
    let root = b.convert(tree, None);
    let rest: Vec<u32> = ids
        .iter()
        .copied()
        .filter(|&i| b.wanted[i as usize])
        .collect();
    let root = match (root, rest.is_empty()) {
        (root, true) => root,
        (None, false) => Some(b.split(rest, None)),
        (Some(r), false) => Some(inner(vec![r, b.split(rest, None)], None)),
    };
    let mut out = HierarchyBvh {
        nodes: Vec::new(),
        ids: Vec::with_capacity(ids.len()),
        spaces: Vec::new(),
        bounds,
        depth: 0,
    };
    if let Some(root) = root {
        out.nodes.push(Node {
            bounds: root.bounds(),
            kind: Kind::Leaf {
                start: 0,
                count: 0,
                object_space: false,
            },
        });
        flatten(root, 0, 0, &mut out);
    }
    out
}
