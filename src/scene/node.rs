use super::Summary;
use crate::math::{Mat4, Vec3};
use std::sync::Arc;

/// A triangle mesh: shared vertices, triangles by index.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

/// A geometric shape in its own (object) space.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Sphere.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
    /// The plane `normal · p = offset` (normal need not be unit).
    Plane {
        /// Normal.
        normal: Vec3,
        /// Offset along the normal, in units of `|normal|`.
        offset: f32,
    },
    /// A single triangle (counter-clockwise front).
    Triangle([Vec3; 3]),
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
        /// Maps the child's space into the parent's.
        matrix: Mat4,
        /// The transformed subtree.
        child: Box<Node>,
    },
    /// A shape with its (already resolved) material index; `None` when the
    /// file gave no `MaterialIndex` before it.
    Shape {
        /// The geometry.
        shape: Shape,
        /// Index into [`super::Scene::materials`].
        material: Option<usize>,
    },
}

impl Node {
    pub(super) fn count(&self, s: &mut Summary) {
        match self {
            Node::Group(children) => {
                s.groups += 1;
                children.iter().for_each(|c| c.count(s));
            }
            Node::Transform { child, .. } => {
                s.transforms += 1;
                child.count(s);
            }
            Node::Shape { shape, .. } => match shape {
                Shape::Sphere { .. } => s.spheres += 1,
                Shape::Plane { .. } => s.planes += 1,
                Shape::Triangle(_) => s.triangles += 1,
                Shape::Mesh(m) => {
                    s.meshes += 1;
                    s.triangles += m.triangles.len();
                }
            },
        }
    }
}
