//! Does a primitive touch a box? Used to put primitives into grid cells and
//! octree children, and the padding margin every accelerator applies.

use crate::math::{Aabb, Vec3};
use crate::primitive::Primitive;
use crate::shape::{Shape, Sphere};

/// The padding, in world units, added around primitive boxes and cells.
///
/// Why: intersection routines round. A triangle lying exactly in a cell's
/// face, or a ray grazing the edge two triangles share, can report a hit a
/// few ulps outside the triangle's exact box; an unpadded cell or node would
/// then not contain the hit and the accelerator would miss what brute force
/// finds. The errors are a few ulps of the coordinates involved, so the
/// margin is relative to the scene's magnitude (`1e-5` ≈ 80 ulps); it is
/// never zero, so a flat scene still gets a box with volume.
pub(crate) fn margin(bounds: &Aabb) -> f32 {
    if bounds.is_empty() {
        return 0.0;
    }
    let scale = bounds.min.abs().max(bounds.max.abs()).max_element();
    (scale * 1e-5).max(1e-30)
}

/// `b` grown by `m` on every side.
pub(crate) fn padded(b: &Aabb, m: f32) -> Aabb {
    Aabb::new(b.min - Vec3::splat(m), b.max + Vec3::splat(m))
}

/// The union of the boxes of the primitives `ids` of `prims`.
pub(crate) fn bounds_of(prims: &[Primitive], ids: &[u32]) -> Aabb {
    ids.iter()
        .fold(Aabb::EMPTY, |b, &i| b.union(&prims[i as usize].bounds()))
}

/// What a cell structure over primitives whose union box is `bounds`
/// covers: `bounds` padded by its [`margin`] (an empty box stays empty);
/// and the margin.
pub(crate) fn covering(bounds: &Aabb) -> (Aabb, f32) {
    let m = margin(bounds);
    if bounds.is_empty() {
        (*bounds, m)
    } else {
        (padded(bounds, m), m)
    }
}

/// Whether two (closed) boxes share a point.
pub(crate) fn boxes_overlap(a: &Aabb, b: &Aabb) -> bool {
    a.min.cmple(b.max).all() && b.min.cmple(a.max).all()
}

/// Whether `shape` may have a surface point in the closed box `b`.
/// Conservative: false only when the shape certainly misses the box.
/// Triangles use the separating-axis test and spheres the distance to the
/// box, which keep a long diagonal triangle or a big sphere out of the cells
/// its box covers but it does not (a transformed triangle by its transformed
/// vertices); anything else uses its bounding box.
/// Callers pad `b` by [`margin`], which absorbs the rounding of these tests.
pub(crate) fn shape_overlaps(shape: &Shape, b: &Aabb) -> bool {
    match shape {
        Shape::Triangle(t) => triangle_box(t.vertices(), b),
        Shape::Sphere(s) => sphere_box(s, b),
        // An unflattened triangle is still a triangle in world space: its
        // transformed vertices give the exact test, as for a baked one.
        Shape::Transformed(x) => match &x.shape {
            Shape::Triangle(t) => {
                triangle_box(t.vertices().map(|p| x.to_world.transform_point3(p)), b)
            }
            _ => boxes_overlap(&x.bounds(), b),
        },
        other => boxes_overlap(&other.bounds(), b),
    }
}

/// A sphere meets a box when the box point nearest the centre is within the
/// radius (Arvo). The sphere's surface, not its volume, is what rays hit, but
/// a cell wholly inside a sphere holds no surface and is rare enough to ignore.
fn sphere_box(s: &Sphere, b: &Aabb) -> bool {
    let nearest = s.center.clamp(b.min, b.max);
    (nearest - s.center).length_squared() <= s.radius * s.radius
}

/// Akenine-Möller's triangle–box test: the triangle and the box are disjoint
/// exactly when one of 13 axes separates them (the box's 3 face normals, the
/// triangle's normal, and the 9 cross products of box and triangle edges).
fn triangle_box(v: [Vec3; 3], b: &Aabb) -> bool {
    let c = b.center();
    let h = 0.5 * b.extent();
    let v = v.map(|p| p - c);
    // Box face normals: the triangle's own bounds against the box.
    let lo = v[0].min(v[1]).min(v[2]);
    let hi = v[0].max(v[1]).max(v[2]);
    if lo.cmpgt(h).any() || hi.cmplt(-h).any() {
        return false;
    }
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    // Triangle normal: the box's projection radius against the plane distance.
    let n = edges[0].cross(edges[1]);
    if n.dot(v[0]).abs() > h.dot(n.abs()) {
        return false;
    }
    // Edge × box-axis directions. A zero axis (an edge along a box axis or a
    // degenerate edge) projects everything to 0 and separates nothing.
    for e in edges {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            let a = axis.cross(e);
            let p = [a.dot(v[0]), a.dot(v[1]), a.dot(v[2])];
            let r = h.dot(a.abs());
            if p[0].min(p[1]).min(p[2]) > r || p[0].max(p[1]).max(p[2]) < -r {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }

    /// Closed boxes: touching faces overlap; a gap along any one axis, on
    /// either side, separates them.
    #[test]
    fn boxes_overlap_when_they_share_a_point() {
        let a = unit_box();
        assert!(boxes_overlap(&a, &a));
        let inside = Aabb::new(Vec3::splat(0.25), Vec3::splat(0.5));
        assert!(boxes_overlap(&a, &inside) && boxes_overlap(&inside, &a));
        for axis in 0..3 {
            let mut step = Vec3::ZERO;
            step[axis] = 1.0;
            let touching = Aabb::new(a.min + step, a.max + step);
            assert!(boxes_overlap(&a, &touching) && boxes_overlap(&touching, &a));
            for s in [1.5, -1.5] {
                let apart = Aabb::new(a.min + step * s, a.max + step * s);
                assert!(!boxes_overlap(&a, &apart), "axis {axis}, {s}");
                assert!(!boxes_overlap(&apart, &a), "axis {axis}, {s}");
            }
        }
    }

    /// Triangles against the unit box, with whether they touch it.
    #[test]
    fn triangles_against_the_unit_box() {
        let v = |x, y, z| Vec3::new(x, y, z);
        let cases = [
            // Near the plane x + y = 4: its bounds span [0,4]², it misses [0,1]².
            (
                "diagonal",
                [v(4.0, 0.0, 0.0), v(0.0, 4.0, 0.0), v(0.0, 4.0, 1.0)],
                false,
            ),
            (
                "near the corner",
                [v(1.5, 0.0, 0.5), v(0.0, 1.5, 0.5), v(0.0, 0.0, 0.5)],
                true,
            ),
            (
                "in a face",
                [v(0.2, 0.2, 1.0), v(0.8, 0.2, 1.0), v(0.2, 0.8, 1.0)],
                true,
            ),
            // The plane x + y + z = 3.5 passes beyond the corner (1,1,1).
            (
                "separated by its plane",
                [v(3.5, 0.0, 0.0), v(0.0, 3.5, 0.0), v(0.0, 0.0, 3.5)],
                false,
            ),
        ];
        for (name, t, touches) in cases {
            assert_eq!(triangle_box(t, &unit_box()), touches, "{name}");
        }
    }

    #[test]
    fn transformed_triangle_uses_its_world_vertices() {
        use crate::math::Mat4;
        use crate::shape::{Transformed, Triangle};
        // The diagonal triangle of `triangles_against_the_unit_box`, as an
        // object triangle moved by a translation.
        let m = Mat4::from_translation(Vec3::new(1.0, 1.0, 0.0));
        let t = Triangle::new(
            Vec3::new(3.0, -1.0, -1.0),
            Vec3::new(-1.0, 3.0, -1.0),
            Vec3::new(-1.0, 3.0, 0.0),
        );
        let x = Shape::Transformed(Box::new(Transformed::new(Shape::Triangle(t), m).unwrap()));
        assert!(boxes_overlap(&x.bounds(), &unit_box()));
        assert!(!shape_overlaps(&x, &unit_box()));
    }

    #[test]
    fn sphere_box_uses_distance() {
        let s = Sphere {
            center: Vec3::new(2.0, 2.0, 0.5),
            radius: 1.2,
        };
        // Distance from (1,1,0.5) is √2 ≈ 1.41 > 1.2, although the boxes overlap.
        assert!(!sphere_box(&s, &unit_box()));
        assert!(boxes_overlap(&s.bounds(), &unit_box()));
        let s = Sphere { radius: 1.5, ..s };
        assert!(sphere_box(&s, &unit_box()));
    }

    #[test]
    fn margin_is_relative_and_never_zero_for_a_point() {
        let b = Aabb::new(Vec3::splat(100.0), Vec3::splat(200.0));
        assert!((margin(&b) - 2e-3).abs() < 1e-6);
        assert!(margin(&Aabb::new(Vec3::ZERO, Vec3::ZERO)) > 0.0);
    }
}
