//! Grid voxelization (`-visualize_grid`): the occupied cells are exactly the
//! cells an independent brute-force overlap test finds, and every course
//! command line that asks for the view renders it.

use crate::common::*;
use glint::accel::grid::Lattice;
use glint::math::{Aabb, Vec3};
use glint::shape::Shape;
use glint::viz::grid::{cells, voxelize};
use glint::world::{BuildOptions, World};
use std::collections::BTreeSet;

/// Whether triangle `v` meets box `b`, by clipping the triangle polygon
/// against the box's six planes (Sutherland–Hodgman) and asking whether
/// anything is left: a different algorithm from the grid's separating-axis
/// test, so the two can check each other.
fn triangle_meets_box(v: [Vec3; 3], b: &Aabb) -> bool {
    let mut poly: Vec<Vec3> = v.to_vec();
    for axis in 0..3 {
        for (bound, keep_below) in [(b.max[axis], true), (b.min[axis], false)] {
            let inside = |p: Vec3| {
                if keep_below {
                    p[axis] <= bound
                } else {
                    p[axis] >= bound
                }
            };
            let mut out = Vec::new();
            for i in 0..poly.len() {
                let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
                if inside(p) {
                    out.push(p);
                }
                if inside(p) != inside(q) {
                    let t = (bound - p[axis]) / (q[axis] - p[axis]);
                    let mut x = p + (q - p) * t;
                    x[axis] = bound;
                    out.push(x);
                }
            }
            poly = out;
            if poly.is_empty() {
                return false;
            }
        }
    }
    true
}

/// Brute force: every (cell, primitive) pair; a sphere counts as its solid
/// ball (the grid's rule: cells inside a sphere are occupied too), distance
/// summed axis by axis.
fn brute_occupied(world: &World, l: &Lattice, pad: f32) -> BTreeSet<[u32; 3]> {
    cells(l)
        .filter(|&c| {
            let cb = l.cell_bounds(c);
            let b = Aabb::new(cb.min - Vec3::splat(pad), cb.max + Vec3::splat(pad));
            world.prims().iter().any(|p| match &p.shape {
                Shape::Triangle(t) => triangle_meets_box(t.vertices(), &b),
                Shape::Sphere(s) => {
                    let d2: f32 = (0..3)
                        .map(|a| {
                            let d = (b.min[a] - s.center[a])
                                .max(s.center[a] - b.max[a])
                                .max(0.0);
                            d * d
                        })
                        .sum();
                    d2 <= s.radius * s.radius
                }
                Shape::Plane(_) => false,
                other => {
                    let pb = other.bounds();
                    pb.min.cmple(b.max).all() && b.min.cmple(pb.max).all()
                }
            })
        })
        .collect()
}

/// The grid's occupied set lies between the brute-force sets of the exact
/// cells and of cells padded by twice the grid's margin: it has every cell a
/// primitive truly meets, and none farther than the padding from one.
fn check_scene(path: &std::path::Path, res: [u32; 3]) -> usize {
    let scene = glint::format::load_scene(path).unwrap();
    let world = World::build(&scene, BuildOptions::default());
    let v = voxelize(&world, Some(res));
    let grid: BTreeSet<[u32; 3]> = v.occupied().into_iter().collect();
    let l = v.lattice;
    let scale = l.bounds.min.abs().max(l.bounds.max.abs()).max_element();
    let pad = 2e-5 * scale;
    let exact = brute_occupied(&world, &l, -pad);
    let loose = brute_occupied(&world, &l, pad);
    let missing: Vec<_> = exact.difference(&grid).collect();
    let extra: Vec<_> = grid.difference(&loose).collect();
    assert!(
        missing.is_empty(),
        "{}: cells the grid misses: {missing:?}",
        path.display()
    );
    assert!(
        extra.is_empty(),
        "{}: cells no primitive meets: {extra:?}",
        path.display()
    );
    assert!(!grid.is_empty());
    grid.len()
}

#[test]
fn occupied_cells_equal_a_brute_force_overlap_test() {
    let mut checked = 0;
    checked += check_scene(&own_scene("whitted.txt"), [9, 7, 11]);
    checked += check_scene(&own_scene("mesh_knot_1k.txt"), [15, 15, 6]);
    if let Some(dir) = scenes("occupied_cells_equal_a_brute_force_overlap_test (course scenes)") {
        for (name, res) in [
            ("scene5_02_spheres.txt", [15, 15, 3]),
            ("scene5_05_sphere_triangles.txt", [20, 20, 10]),
            ("scene5_06_bunny_mesh_200.txt", [10, 10, 7]),
            ("scene5_11_rotated_triangles.txt", [15, 15, 9]),
            ("scene5_12_nested_transformations.txt", [30, 30, 30]),
        ] {
            checked += check_scene(&dir.join(name), res);
        }
    }
    assert!(checked > 100, "{checked} cells");
}

/// Every A5 and A6 line that asks for the grid view runs; the view's
/// silhouette (pixels that are not background) matches the reference's,
/// whose cells have random colours but the same shapes.
#[test]
fn every_course_visualize_grid_line_renders() {
    let Some(data) = course_data("every_course_visualize_grid_line_renders") else {
        return;
    };
    let dir = scratch("viz-grid");
    let mut failures = Vec::new();
    let mut n = 0;
    for file in ["A5_cmd.txt", "A6_cmd.txt"] {
        for line in command_lines(&data.scenes, file) {
            if !line.args.iter().any(|a| a == "-visualize_grid") {
                continue;
            }
            n += 1;
            if let Err(e) = run_raytracer(&data.scenes, &line.args, &dir) {
                failures.push(format!("{}: {e}", line.text));
                continue;
            }
            let out = &line.outputs[0];
            let (w, h, ours) = load_rgb8(&dir.join(out)).unwrap();
            let (rw, rh, reference) = load_rgb8(&reference_for(&data.refs, out)).unwrap();
            assert_eq!((w, h), (rw, rh), "{out}");
            let (bg, rbg) = (ours[0], reference[0]);
            let frac = |f: &dyn Fn(bool, bool) -> bool| {
                let k = ours
                    .iter()
                    .zip(&reference)
                    .filter(|(a, b)| f(**a != bg, **b != rbg))
                    .count();
                k as f64 / ours.len() as f64
            };
            // Cells the reference shows and we do not, and the reverse.
            let missing = frac(&|o, r| r && !o);
            let extra = frac(&|o, r| o && !r);
            eprintln!(
                "{out}: reference cells we leave empty {:.2}%, our cells the reference leaves empty {:.2}%",
                100.0 * missing,
                100.0 * extra
            );
            // The reference squashes 400x200 images vertically (see tests/textures.rs).
            if out != "output6_18b.tga" && extra > SUBSET_MAX {
                failures.push(format!(
                    "{out}: {:.2}% of pixels show our cells where the reference has none",
                    100.0 * extra
                ));
            }
        }
    }
    assert!(n >= 20, "only {n} lines");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The reference and glint fill cells by different rules: the reference
/// marks every cell of an object's bounding box (spheres and triangles
/// alike), glint only the cells the object meets (the exact test the
/// renderer's grid uses, `accel/overlap.rs`). So glint's cells are a subset
/// of the reference's, seen from the same camera: where glint shows a cell,
/// the reference must too, up to edge pixels. Measured worst case 1.09%
/// (scene5_05, a sphere between two large triangles); all others <= 0.12%.
/// The reverse differs by up to 25% (scene6_12's gem: the reference fills
/// the gem's whole box) and is not a defect.
const SUBSET_MAX: f64 = 0.015;
