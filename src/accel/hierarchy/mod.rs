//! A BVH from the modeling hierarchy (`--accel bvh-hierarchy`): the inner
//! nodes are the scene's own groups and transforms, each with the box of
//! what is under it, instead of boxes a builder chose.
//!
//! - [`SceneTree`]: the scene's tree over primitive ids, recorded by the
//!   world's flattener.
//! - `build.rs`: the tree → n-ary nodes, and the two places where the scene
//!   has no hierarchy to offer (below).
//! - `traverse.rs`: a stack walk, children in order of where the ray enters
//!   their boxes; a transform node carries the ray into its space once.
//!
//! **Where the scene says nothing, a simple rule splits.** A mesh has no
//! modeling hierarchy of its own: its triangles are halved at the median
//! centroid along the longest axis until at most [`MAX_LEAF`] remain. A group
//! with more than [`MAX_CHILDREN`] children is halved the same way (by its
//! children's box centres) until each node has at most that many, which
//! bounds the work per node. A group or transform of a single child adds no
//! box of its own and is skipped, unless it is a transform that carries the
//! ray (below).
//!
//! **Without flattening** (`--no-flatten`) the leaves are `Transformed`
//! wrappers, and a ray is carried into object space by each one it tests:
//! measuring that shows what flattening saves. This BVH does better: a
//! transform node whose leaves are all wrappers under that node's own matrix
//! carries the ray into its space *once per visit* (the same matrix product
//! each wrapper would do, so the hit `t` is bit-identical), and the leaves
//! test their object-space shapes with it. Node boxes stay in world space.

mod build;
mod traverse;

use super::{Aggregate, PrimHit, Query};
use crate::math::{Aabb, Mat4};
use crate::primitive::Primitive;
use crate::stats::Counters;
use std::ops::Range;

/// Most primitives in a leaf made by splitting a mesh.
pub const MAX_LEAF: usize = 4;
/// Most children of one node; wider groups are split (see the module docs).
pub const MAX_CHILDREN: usize = 8;

/// The scene's object tree over primitive ids, as the flattener saw it.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneTree {
    /// A group of subtrees (empty for what contributes no primitive, such
    /// as a singular transform's subtree).
    Group(Vec<SceneTree>),
    /// A transform node.
    Transform {
        /// Object-to-world matrix of the child: every transform above it
        /// composed (the matrix the flattener baked or wrapped with).
        to_world: Mat4,
        /// Its inverse, as the wrappers below use it (inverted in f64, then
        /// rounded: not the f32 inverse of `to_world`).
        to_object: Mat4,
        /// The transformed subtree.
        child: Box<SceneTree>,
    },
    /// The primitives one shape became: one, or a mesh's triangles.
    Shape(Range<u32>),
}

/// One node (inner nodes: up to [`MAX_CHILDREN`] children stored together).
#[derive(Clone, Copy, Debug)]
struct Node {
    /// Union of the padded boxes below.
    bounds: Aabb,
    kind: Kind,
}

/// No space: the node tests with the ray it was reached with.
const NO_SPACE: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
enum Kind {
    Inner {
        /// Children are `first..first + count`.
        first: u32,
        count: u32,
        /// Index into `HierarchyBvh::spaces` for a transform node that
        /// carries the ray, else [`NO_SPACE`].
        space: u32,
    },
    Leaf {
        /// Ids are `ids[start..start + count]`.
        start: u32,
        count: u32,
        /// All of them are wrappers under the nearest carrying transform
        /// node's matrix: test their object shapes with its ray.
        object_space: bool,
    },
}

/// A BVH whose inner nodes are the scene's groups and transforms.
pub struct HierarchyBvh {
    nodes: Vec<Node>,
    ids: Vec<u32>,
    /// World-to-object matrices of the transform nodes that carry the ray.
    spaces: Vec<Mat4>,
    bounds: Aabb,
    depth: usize,
}

impl HierarchyBvh {
    /// A BVH over the primitives `ids` of `prims`, shaped by `tree`.
    /// Primitives of the tree not in `ids` (the planes) are left out; ids the
    /// tree does not mention are added under the root.
    pub fn new(prims: &[Primitive], ids: Vec<u32>, tree: &SceneTree) -> Self {
        build::build(prims, &ids, tree)
    }

    /// Nodes, inner and leaves.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Transform nodes that carry the ray into their space.
    pub fn spaces(&self) -> usize {
        self.spaces.len()
    }

    /// Depth of the deepest leaf (a lone root is 0).
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// The closest hit, calling `visit` with every box the search tests, in
    /// order: the renderer's search itself ([`Aggregate::intersect`] passes
    /// a visitor that does nothing), which the traversal views record.
    pub fn intersect_visiting(
        &self,
        q: Query,
        c: &mut Counters,
        mut visit: impl FnMut(&BoxVisit),
    ) -> Option<PrimHit> {
        traverse::closest(self, q, c, |k, entered| {
            let n = &self.nodes[k as usize];
            visit(&BoxVisit {
                bounds: n.bounds,
                entered,
                leaf: matches!(n.kind, Kind::Leaf { .. }),
            })
        })
    }
}

/// A box the hierarchy BVH's search tested.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxVisit {
    /// The node's box.
    pub bounds: Aabb,
    /// Whether the ray entered it (within the current best hit).
    pub entered: bool,
    /// Whether it is a leaf.
    pub leaf: bool,
}

impl Aggregate for HierarchyBvh {
    fn intersect(&self, q: Query, c: &mut Counters) -> Option<PrimHit> {
        traverse::closest(self, q, c, |_, _| {})
    }

    fn occluded(&self, q: Query, c: &mut Counters) -> bool {
        traverse::any(self, q, c)
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn describe(&self) -> String {
        format!(
            "bvh-hierarchy {} nodes, depth {}, {} carrying transforms",
            self.nodes.len(),
            self.depth,
            self.spaces.len()
        )
    }

    fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
            + self.ids.len() * 4
            + self.spaces.len() * std::mem::size_of::<Mat4>()
    }
}

#[cfg(test)]
mod tests;
