use super::Summary;
use crate::math::{Aabb, Motion, Vec3};
use glam::{DMat4, DVec3};
use std::sync::Arc;

/// A triangle mesh: shared vertices, triangles by index.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// Unit vertex normals for smooth shading, one per position, or empty
    /// (flat shading). A zero normal marks a vertex without one.
    pub normals: Vec<Vec3>,
    /// Vertex colours (linear RGB, 0 to 1), one per position, or empty.
    /// Read from files that have them; not yet used in shading.
    pub colors: Vec<Vec3>,
}

impl Mesh {
    /// This mesh with angle-weighted vertex normals (each triangle adds its
    /// unit normal times its angle at the vertex; Thürmer and Wüthrich
    /// 1998), computed in f64 and normalised; a vertex of degenerate
    /// triangles only gets a zero normal (flat shading there).
    pub fn with_computed_normals(&self) -> Mesh {
        let mut acc = vec![glam::DVec3::ZERO; self.positions.len()];
        for t in &self.triangles {
            let p = t.map(|i| self.positions[i as usize].as_dvec3());
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            let Some(n) = n.try_normalize() else {
                continue;
            };
            for k in 0..3 {
                let e1 = p[(k + 1) % 3] - p[k];
                let e2 = p[(k + 2) % 3] - p[k];
                let angle = e1.angle_between(e2);
                if angle.is_finite() {
                    acc[t[k] as usize] += n * angle;
                }
            }
        }
        Mesh {
            normals: acc
                .iter()
                .map(|n| n.try_normalize().map_or(Vec3::ZERO, |n| n.as_vec3()))
                .collect(),
            ..self.clone()
        }
    }
}

/// A geometric shape in its own (object) space, as the scene describes it;
/// `world::build` turns it into the renderable [`crate::shape::Shape`].
/// Positions (centres, vertices, a plane's offset) are in double precision,
/// as the file gave them, until `world::build` moves them into rendering
/// space and rounds them once; directions, radii and mesh-file vertices are
/// single precision.
#[derive(Clone, Debug, PartialEq)]
pub enum ShapeDesc {
    /// Sphere.
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f32,
    },
    /// The plane `normal · p = offset` (normal need not be unit).
    Plane {
        /// Normal.
        normal: Vec3,
        /// Offset along the normal, in units of `|normal|`.
        offset: f64,
    },
    /// A single triangle (counter-clockwise front).
    Triangle([DVec3; 3]),
    /// A mesh, shared between all places that use the same file.
    Mesh(Arc<Mesh>),
}

/// A node of the object tree.
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    /// A list of children.
    Group(Vec<Node>),
    /// A child seen through an object-to-parent matrix.
    Transform {
        /// Maps the child's space into the parent's; in double precision, as
        /// the file gave it (`crate::world` composes the transforms in f64
        /// and rounds each vertex once, in rendering space).
        matrix: DMat4,
        /// The transformed subtree.
        child: Box<Node>,
    },
    /// A child moving by a keyframed transform (motion blur): at instant `t`
    /// its object-to-parent matrix is `motion.matrix(t)`.
    Moving {
        /// The keyframes.
        motion: Arc<Motion>,
        /// The moving subtree.
        child: Box<Node>,
    },
    /// A shape with its (already resolved) material index; `None` when the
    /// file gave no `MaterialIndex` before it.
    Shape {
        /// The geometry.
        shape: ShapeDesc,
        /// Index into [`super::Scene::materials`].
        material: Option<usize>,
    },
}

impl Node {
    /// World bounds of this subtree seen through `m` (object-to-world),
    /// composed and applied in f64, each point rounded once.
    ///
    /// A group is the union of its children. Under a transform, triangles and
    /// meshes transform their vertices (the tightest box); a sphere transforms
    /// the 8 corners of its box (a rotated sphere's box grows by up to √3);
    /// planes are unbounded unless axis-aligned (see `shape::Plane::bounds`).
    /// The world never needs these (it flattens first); they are what the
    /// tree looks like to a ray before flattening, for `glint info`.
    pub fn bounds(&self, m: &DMat4) -> Aabb {
        let point = |p: DVec3| m.transform_point3(p).as_vec3();
        match self {
            Node::Group(children) => children
                .iter()
                .fold(Aabb::EMPTY, |b, c| b.union(&c.bounds(m))),
            Node::Transform { matrix, child } => child.bounds(&(*m * *matrix)),
            Node::Moving { motion, child } => {
                motion.swept_bounds(&child.bounds(&DMat4::IDENTITY), &m.as_mat4())
            }
            Node::Shape { shape, .. } => match shape {
                ShapeDesc::Sphere { center, radius } => {
                    let r = *radius as f64;
                    Aabb::from_points((0..8).map(|i| {
                        let corner = |bit: usize| if i & bit == 0 { -r } else { r };
                        point(*center + DVec3::new(corner(1), corner(2), corner(4)))
                    }))
                }
                ShapeDesc::Plane { normal, offset } => {
                    crate::shape::Plane::from_f64(*normal, *offset, m)
                        .map_or(Aabb::EMPTY, |p| p.bounds())
                }
                ShapeDesc::Triangle(v) => Aabb::from_points(v.iter().map(|&p| point(p))),
                ShapeDesc::Mesh(mesh) => {
                    Aabb::from_points(mesh.positions.iter().map(|&p| point(p.as_dvec3())))
                }
            },
        }
    }

    /// Calls `f` on every mesh of the subtree.
    pub(super) fn for_each_mesh(&mut self, f: &mut impl FnMut(&mut Arc<Mesh>)) {
        match self {
            Node::Group(children) => children.iter_mut().for_each(|c| c.for_each_mesh(f)),
            Node::Transform { child, .. } | Node::Moving { child, .. } => child.for_each_mesh(f),
            Node::Shape {
                shape: ShapeDesc::Mesh(m),
                ..
            } => f(m),
            Node::Shape { .. } => {}
        }
    }

    pub(super) fn count(&self, s: &mut Summary) {
        match self {
            Node::Group(children) => {
                s.groups += 1;
                children.iter().for_each(|c| c.count(s));
            }
            Node::Transform { child, .. } | Node::Moving { child, .. } => {
                s.transforms += 1;
                child.count(s);
            }
            Node::Shape { shape, .. } => match shape {
                ShapeDesc::Sphere { .. } => s.spheres += 1,
                ShapeDesc::Plane { .. } => s.planes += 1,
                ShapeDesc::Triangle(_) => s.triangles += 1,
                ShapeDesc::Mesh(m) => {
                    s.meshes += 1;
                    s.triangles += m.triangles.len();
                }
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Mat4;

    fn xf(m: Mat4, child: Node) -> Node {
        Node::Transform {
            matrix: m.as_dmat4(),
            child: Box::new(child),
        }
    }

    fn tri() -> Node {
        Node::Shape {
            shape: ShapeDesc::Triangle([DVec3::ZERO, DVec3::X, DVec3::Y]),
            material: None,
        }
    }

    #[test]
    fn group_is_the_union() {
        let s = Node::Shape {
            shape: ShapeDesc::Sphere {
                center: Vec3::new(5.0, 0.0, 0.0).as_dvec3(),
                radius: 1.0,
            },
            material: None,
        };
        let b = Node::Group(vec![tri(), s]).bounds(&DMat4::IDENTITY);
        assert_eq!(b.min, Vec3::new(0.0, -1.0, -1.0));
        assert_eq!(b.max, Vec3::new(6.0, 1.0, 1.0));
    }

    #[test]
    fn transformed_triangle_uses_its_vertices_not_box_corners() {
        let m = Mat4::from_rotation_z(std::f32::consts::FRAC_PI_4);
        let tight = xf(m, tri()).bounds(&DMat4::IDENTITY);
        let corners = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)).transformed(&m);
        // The box of the rotated triangle is strictly smaller than the rotated box.
        assert!(tight.surface_area() < corners.surface_area());
        assert!((tight.max.y - 2f32.sqrt() / 2.0).abs() < 1e-6);
    }

    #[test]
    fn transformed_sphere_uses_the_8_corners() {
        let s = Node::Shape {
            shape: ShapeDesc::Sphere {
                center: Vec3::ZERO.as_dvec3(),
                radius: 1.0,
            },
            material: None,
        };
        let m =
            Mat4::from_translation(Vec3::X) * Mat4::from_rotation_z(std::f32::consts::FRAC_PI_4);
        let b = xf(m, s).bounds(&DMat4::IDENTITY);
        assert!((b.max.x - (1.0 + 2f32.sqrt())).abs() < 1e-5);
    }

    #[test]
    fn nested_transforms_compose() {
        let inner = xf(Mat4::from_scale(Vec3::splat(2.0)), tri());
        let b =
            xf(Mat4::from_translation(Vec3::new(0.0, 0.0, 3.0)), inner).bounds(&DMat4::IDENTITY);
        assert_eq!(b.max, Vec3::new(2.0, 2.0, 3.0));
    }
}
