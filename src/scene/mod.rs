//! The format-independent description of a scene: what a parser produces and
//! what tests build by hand. Nothing here knows how to render; `crate::world`
//! turns a [`Scene`] into something rays can be shot at.

mod camera;
mod effects;
mod light;
mod material;
mod node;

pub use camera::Camera;
pub use effects::{AmbientOcclusion, EffectSamples, Effects, Lens};
pub use light::{AreaShape, Light, RenderAreaShape, RenderLight};
pub use material::{Material, Phong, TextureKind};
pub use node::{Mesh, Node, ShapeDesc};

use crate::math::{Aabb, Vec3};
use std::sync::Arc;

/// Background colour and the ambient light that every surface receives.
#[derive(Clone, Debug, PartialEq)]
pub struct Background {
    /// Colour of rays that hit nothing.
    pub color: Vec3,
    /// Ambient light, multiplied by each material's diffuse colour.
    pub ambient: Vec3,
}

impl Default for Background {
    /// The course's defaults: grey background, no ambient light.
    fn default() -> Self {
        Self {
            color: Vec3::splat(0.5),
            ambient: Vec3::ZERO,
        }
    }
}

/// A whole scene: one camera, lights, background, a material table and the
/// object tree. Materials are referenced by index from the tree.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// The light sources.
    pub lights: Vec<Light>,
    /// Background colour and ambient light.
    pub background: Background,
    /// Material table; textures refer to earlier entries by index.
    pub materials: Vec<Material>,
    /// The object tree (a group at the top).
    pub root: Node,
    /// Lens, shutter, ray counts and ambient occlusion (all off by default).
    pub effects: Effects,
}

impl Scene {
    /// A scene showing `mesh` alone: a perspective camera (45°) looking at
    /// the mesh's bounding sphere from above and to the right, one white
    /// directional light, a warm grey material. Used for bare mesh input.
    pub fn for_mesh(mesh: Mesh) -> Scene {
        let mut s = Scene::for_bounds(Aabb::from_points(mesh.positions.iter().copied()));
        s.root = Node::Shape {
            shape: ShapeDesc::Mesh(Arc::new(mesh)),
            material: Some(0),
        };
        s
    }

    /// [`Scene::for_mesh`]'s camera, light, background and material for
    /// anything within `b`, with an empty tree.
    pub fn for_bounds(b: Aabb) -> Scene {
        let (c, r) = if b.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            (b.center(), (0.5 * b.extent().length()).max(1e-6))
        };
        let view = Vec3::new(0.3, 0.4, 1.0).normalize();
        Scene {
            camera: Camera::Perspective {
                center: (c + view * r * 2.6).as_dvec3(),
                direction: -view,
                up: Vec3::Y,
                angle_deg: 45.0,
            },
            lights: vec![Light::Directional {
                direction: Vec3::new(-0.5, -1.0, -0.4),
                color: Vec3::splat(0.9),
            }],
            background: Background {
                color: Vec3::splat(0.2),
                ambient: Vec3::splat(0.1),
            },
            materials: vec![Material::Phong(Phong {
                diffuse: Vec3::new(0.8, 0.7, 0.6),
                ..Phong::default()
            })],
            root: Node::Group(Vec::new()),
            effects: Effects::default(),
        }
    }

    /// Gives every mesh without vertex normals angle-weighted ones
    /// ([`Mesh::with_computed_normals`]), so all meshes are shaded smooth;
    /// a mesh shared by several nodes is computed once and stays shared.
    pub fn smooth_meshes(&mut self) {
        // (original, smooth) pairs; the originals are kept alive so that
        // pointer comparison stays meaningful.
        let mut done: Vec<(Arc<Mesh>, Arc<Mesh>)> = Vec::new();
        self.root.for_each_mesh(&mut |mesh: &mut Arc<Mesh>| {
            if !mesh.normals.is_empty() {
                return;
            }
            let smooth = match done.iter().find(|(k, _)| Arc::ptr_eq(k, mesh)) {
                Some((_, m)) => Arc::clone(m),
                None => {
                    let m = Arc::new(mesh.with_computed_normals());
                    done.push((Arc::clone(mesh), Arc::clone(&m)));
                    m
                }
            };
            *mesh = smooth;
        });
    }

    /// Counts of what the scene holds, for `glint info` and statistics.
    pub fn summary(&self) -> Summary {
        let mut s = Summary {
            lights: self.lights.len(),
            materials: self.materials.len(),
            ..Summary::default()
        };
        self.root.count(&mut s);
        s
    }
}

/// Counts of the objects in a scene.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Spheres.
    pub spheres: usize,
    /// Planes.
    pub planes: usize,
    /// Single triangles plus mesh triangles.
    pub triangles: usize,
    /// Mesh references (a mesh used twice counts twice).
    pub meshes: usize,
    /// Groups.
    pub groups: usize,
    /// Transforms.
    pub transforms: usize,
    /// Lights.
    pub lights: usize,
    /// Materials (textures included).
    pub materials: usize,
}
