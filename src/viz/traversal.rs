//! What an accelerator did for one ray: the grid cells the 3DDDA walked
//! (with the face each was entered through), the octree leaves, or the BVH
//! nodes whose boxes were tested and which of them the ray entered. Recorded
//! through the accelerators' own `intersect_visiting`, the search the
//! renderer runs, so the picture cannot drift from the code.
//!
//! Colours: grid cells and octree leaves grey, the face a cell was entered
//! through red, green or blue for an x, y or z face, the cell or leaf where
//! the hit was accepted yellow; BVH boxes tested but missed dark red, inner
//! boxes entered cyan, leaves entered yellow; the ray white.

use super::draw::Canvas;
use crate::accel::bvh::{Bvh, NodeVisit};
use crate::accel::grid::Face;
use crate::accel::{AccelKind, Grid, HierarchyBvh, NestedGrid, Octree, PrimHit, Query, Storage};
use crate::math::{Aabb, Ray, Vec2, Vec3};
use crate::render::{pixel_of_screen, CameraModel};
use crate::stats::Counters;
use crate::world::World;
use std::fmt::Write as _;

/// One box the search looked at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Visit {
    /// The box (a grid cell, an octree leaf, a BVH node).
    pub bounds: Aabb,
    /// Whether the ray entered it (always, for cells and leaves).
    pub entered: bool,
    /// Whether it is a leaf (cells are leaves).
    pub leaf: bool,
    /// The face the ray came in through, when it started outside the box.
    pub face: Option<Face>,
}

/// An accelerator built over a world's bounded primitives, as the renderer
/// builds it, kept concrete so that its walk can be recorded.
pub enum Structure {
    /// A uniform grid.
    Grid(Grid),
    /// An octree.
    Octree(Octree),
    /// A binary BVH.
    Bvh(Bvh),
    /// Nested grids (every level's cells; those holding a finer grid are
    /// drawn as inner boxes).
    NestedGrid(NestedGrid),
    /// The BVH of the scene's groups and transforms.
    Hierarchy(HierarchyBvh),
}

impl Structure {
    /// Builds the structure `kind` names over `world`'s bounded primitives;
    /// `None` for brute force, which walks nothing, and for the 8-wide BVH,
    /// whose loops record no walk (drawing its binary SAH twin under its
    /// name would show another tree).
    pub fn build(world: &World, kind: AccelKind) -> Option<Structure> {
        let ids: Vec<u32> = (0..world.prims().len() as u32)
            .filter(|i| !world.unbounded().contains(i))
            .collect();
        Some(match kind {
            AccelKind::None => return None,
            AccelKind::Grid { res } => Structure::Grid(Grid::new(world.prims(), ids, res)),
            AccelKind::Octree => Structure::Octree(Octree::new(world.prims(), ids)),
            AccelKind::OctreeInner => {
                Structure::Octree(Octree::with_storage(world.prims(), ids, Storage::Inner))
            }
            AccelKind::Bvh(split) => Structure::Bvh(Bvh::new(world.prims(), ids, split)),
            AccelKind::NestedGrid { threshold, depth } => {
                Structure::NestedGrid(NestedGrid::new(world.prims(), ids, threshold, depth))
            }
            AccelKind::BvhHierarchy => {
                // Built from the world's recorded scene tree, as the renderer's.
                Structure::Hierarchy(HierarchyBvh::new(world.prims(), ids, world.scene_tree()))
            }
            AccelKind::Bvh8 => return None,
        })
    }

    /// The closest hit of `ray` with `t > tmin`, and every box its search
    /// looked at, in order.
    pub fn trace(&self, world: &World, ray: &Ray, tmin: f32) -> (Option<PrimHit>, Vec<Visit>) {
        let mut visits = Vec::new();
        let c = &mut Counters::default();
        let prims = world.prims();
        let hit = match self {
            Structure::Grid(g) => {
                g.intersect_visiting(Query::new(prims, ray, tmin, f32::INFINITY), c, |cell| {
                    visits.push(Visit {
                        bounds: g.lattice().cell_bounds(cell.index),
                        entered: true,
                        leaf: true,
                        face: cell.entered,
                    })
                })
            }
            Structure::Octree(o) => {
                o.intersect_visiting(Query::new(prims, ray, tmin, f32::INFINITY), c, |leaf| {
                    visits.push(Visit {
                        bounds: leaf.bounds,
                        entered: true,
                        // With `octree-inner`, inner nodes holding primitives too.
                        leaf: leaf.is_leaf,
                        face: entry_face(&leaf.bounds, ray, leaf.t_enter),
                    })
                })
            }
            Structure::NestedGrid(g) => {
                g.intersect_visiting(Query::new(prims, ray, tmin, f32::INFINITY), c, |v| {
                    visits.push(Visit {
                        bounds: v.bounds,
                        entered: true,
                        leaf: !v.finer,
                        face: v.entered,
                    })
                })
            }
            Structure::Hierarchy(h) => {
                h.intersect_visiting(Query::new(prims, ray, tmin, f32::INFINITY), c, |v| {
                    visits.push(Visit {
                        bounds: v.bounds,
                        entered: v.entered,
                        leaf: v.leaf,
                        face: None,
                    })
                })
            }
            Structure::Bvh(b) => b.intersect_visiting(
                Query::new(prims, ray, tmin, f32::INFINITY),
                c,
                |v: NodeVisit| {
                    let n = &b.nodes()[v.node as usize];
                    visits.push(Visit {
                        bounds: n.bounds,
                        entered: v.entered,
                        leaf: n.is_leaf(),
                        face: None,
                    })
                },
            ),
        };
        (hit, visits)
    }
}

/// The face of `b` through which `ray` enters at `t_enter`: the slab whose
/// near plane the ray crosses last (none when the ray starts inside).
fn entry_face(b: &Aabb, ray: &Ray, t_enter: f32) -> Option<Face> {
    let mut best: Option<(f32, Face)> = None;
    for axis in 0..3 {
        let d = ray.dir[axis];
        if d == 0.0 {
            continue;
        }
        let plane = if d > 0.0 { b.min[axis] } else { b.max[axis] };
        let t = (plane - ray.origin[axis]) / d;
        if best.is_none_or(|(bt, _)| t > bt) {
            best = Some((
                t,
                Face {
                    axis,
                    min_side: d > 0.0,
                },
            ));
        }
    }
    best.filter(|(t, _)| *t >= t_enter - 1e-4 * t_enter.abs().max(1.0) && *t > 0.0)
        .map(|(_, f)| f)
}

/// The colour of a face perpendicular to `axis`.
pub fn axis_color(axis: usize) -> Vec3 {
    [
        Vec3::new(0.9, 0.15, 0.1),
        Vec3::new(0.1, 0.85, 0.1),
        Vec3::new(0.15, 0.35, 1.0),
    ][axis]
}

/// The colour a visit is drawn in (see the module's documentation).
fn visit_color(v: &Visit, last: bool, hit: bool, bvh: bool) -> Vec3 {
    match (bvh, v.entered, v.leaf) {
        (true, false, _) => Vec3::new(0.45, 0.08, 0.08),
        (true, true, false) => Vec3::new(0.1, 0.8, 0.85),
        (true, true, true) => Vec3::new(0.95, 0.85, 0.1),
        (false, ..) if last && hit => Vec3::new(0.95, 0.85, 0.1),
        _ => Vec3::splat(0.6),
    }
}

/// The 12 edges of a box.
pub fn box_edges(b: &Aabb) -> Vec<(Vec3, Vec3)> {
    let corner = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        )
    };
    let mut e = Vec::new();
    for i in 0..8 {
        for bit in [1, 2, 4] {
            if i & bit == 0 {
                e.push((corner(i), corner(i | bit)));
            }
        }
    }
    e
}

/// The 4 edges of the face `f` of box `b`.
fn face_edges(b: &Aabb, f: Face) -> Vec<(Vec3, Vec3)> {
    let plane = if f.min_side {
        b.min[f.axis]
    } else {
        b.max[f.axis]
    };
    box_edges(b)
        .into_iter()
        .filter(|(p, q)| p[f.axis] == plane && q[f.axis] == plane)
        .collect()
}

/// Everything to draw for one traced ray: (segment, colour).
pub fn segments(
    ray: &Ray,
    hit: Option<PrimHit>,
    visits: &[Visit],
    bvh: bool,
) -> Vec<((Vec3, Vec3), Vec3)> {
    let mut out = Vec::new();
    for (i, v) in visits.iter().enumerate() {
        let c = visit_color(v, i + 1 == visits.len(), hit.is_some(), bvh);
        out.extend(box_edges(&v.bounds).into_iter().map(|e| (e, c)));
    }
    // Entered faces on top of the boxes' edges.
    for v in visits {
        if let Some(f) = v.face {
            out.extend(
                face_edges(&v.bounds, f)
                    .into_iter()
                    .map(|e| (e, axis_color(f.axis))),
            );
        }
    }
    let t_end = hit.map_or(1e3, |h| h.t);
    out.push(((ray.origin, ray.at(t_end)), Vec3::ONE));
    out
}

/// Draws `segments` over `canvas` in the camera's projection.
pub fn draw(canvas: &mut Canvas, camera: &CameraModel, segments: &[((Vec3, Vec3), Vec3)]) {
    let (w, h) = (canvas.width, canvas.height);
    for (&(_, c), p) in segments.iter().zip(project(camera, segments, (w, h))) {
        if let Some((a, b)) = p {
            canvas.line(a, b, c, 0);
        }
    }
}

/// Where each segment appears in a `w`×`h` image seen through `camera`:
/// its end points in continuous pixel coordinates (y up from the bottom
/// edge), the part behind a perspective camera cut off, or `None` when none
/// of it is in front. What [`draw`] draws, and what `glint serve` sends.
pub fn project(
    camera: &CameraModel,
    segments: &[((Vec3, Vec3), Vec3)],
    (w, h): (u32, u32),
) -> Vec<Option<(Vec2, Vec2)>> {
    segments
        .iter()
        .map(|&((a, b), _)| {
            let (da, db) = (camera.depth_of(a), camera.depth_of(b));
            let (a, b) = if camera.is_perspective() {
                let near = 1e-4 * da.abs().max(db.abs()).max(1e-6);
                match (da >= near, db >= near) {
                    (true, true) => (a, b),
                    (false, false) => return None,
                    _ => {
                        let m = a + (b - a) * ((near - da) / (db - da));
                        if da >= near {
                            (a, m)
                        } else {
                            (m, b)
                        }
                    }
                }
            } else {
                (a, b)
            };
            let (sa, sb) = (camera.project(a)?, camera.project(b)?);
            Some((pixel_of_screen(sa, w, h), pixel_of_screen(sb, w, h)))
        })
        .collect()
}

/// Segments as OBJ lines with per-vertex colours.
pub fn to_obj(segments: &[((Vec3, Vec3), Vec3)]) -> String {
    let mut s = String::from("# glint traversal: boxes the accelerator looked at, and the ray\n");
    for (i, ((a, b), c)) in segments.iter().enumerate() {
        for p in [a, b] {
            let _ = writeln!(s, "v {} {} {} {} {} {}", p.x, p.y, p.z, c.x, c.y, c.z);
        }
        let _ = writeln!(s, "l {} {}", 2 * i + 1, 2 * i + 2);
    }
    s
}
