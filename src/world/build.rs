//! Scene → World: flattening the transform hierarchy into rendering space.
//!
//! Why flatten: a ray that meets a transform node has to be carried into the
//! child's space (two matrix products) before every test below it. Baking
//! triangles, similarity-transformed spheres and planes into world space once
//! at load removes that cost from every ray; only what cannot be baked (a
//! sphere under non-uniform scale) keeps a [`Transformed`] wrapper.
//!
//! Why f64: every matrix product, and the translation into rendering space
//! (camera at the origin, see [`crate::world`]), is done in f64 and rounded
//! to f32 once per vertex, centre or plane. A scene placed at `10⁵` and
//! translated back then lands on the same f32 values as the same scene
//! placed at the origin: translating in f32 would round every coordinate to
//! the ulp of `10⁵` (0.008) first.

use super::{Primitive, World};
use crate::accel::{
    AccelKind, Aggregate, Brute, Bvh, Bvh8, Grid, HierarchyBvh, NestedGrid, Octree, SceneTree,
    Storage,
};
use crate::light::LightSource;
use crate::math::Vec3;
use crate::scene::{Camera, Light, Material, Node, Phong, RenderLight, Scene, ShapeDesc as Desc};
use crate::shape::{Moving, Plane, Shape, Sphere, Transformed, Triangle};
use glam::{DMat4, DVec3};
use std::time::Instant;

/// How to build the world.
#[derive(Clone, Copy, Debug)]
pub struct BuildOptions {
    /// Which aggregate.
    pub accel: AccelKind,
    /// Bake transforms into world space (on by default; off to measure it).
    pub flatten: bool,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            accel: AccelKind::default(),
            flatten: true,
        }
    }
}

impl World {
    /// Flattens `scene` into rendering space (the camera's centre at the
    /// origin) and builds the aggregate.
    pub fn build(scene: &Scene, opts: BuildOptions) -> World {
        World::build_at(scene, opts, camera_center(&scene.camera))
    }

    /// [`World::build`] without the move into rendering space: everything
    /// stays in world coordinates. For tools whose output must line up with
    /// the scene file (visualisations exporting geometry, `glint info`'s
    /// bounds), where f32 precision far from the camera does not matter.
    pub fn build_world_space(scene: &Scene, opts: BuildOptions) -> World {
        World::build_at(scene, opts, DVec3::ZERO)
    }

    /// [`World::build`] with the rendering-space origin at the world-space
    /// point `origin` (`DVec3::ZERO`: render in world space, as glint did
    /// before rendering space; kept to measure what it brings).
    pub fn build_at(scene: &Scene, opts: BuildOptions, origin: DVec3) -> World {
        let mut object_materials = scene.materials.clone();
        let default_material = object_materials.len() as u32;
        object_materials.push(Material::Phong(Phong::default()));
        let materials = object_materials
            .iter()
            .map(|m| to_render_space(m, origin))
            .collect();
        let render_from_world = DMat4::from_translation(-origin);
        let mut f = Flattener {
            prims: Vec::new(),
            vertex_normals: Vec::new(),
            object_from_world: vec![DMat4::from_translation(origin).as_mat4()],
            default_material,
            flatten: opts.flatten,
        };
        let tree = f.node(&scene.root, render_from_world, 0);
        if !f.vertex_normals.is_empty() {
            f.vertex_normals.resize(f.prims.len(), [Vec3::ZERO; 3]);
        }
        let (bounded, unbounded): (Vec<u32>, Vec<u32>) =
            (0..f.prims.len() as u32).partition(|&i| f.prims[i as usize].bounds().is_finite());
        let start = Instant::now();
        let accel = build_aggregate(opts.accel, &f.prims, bounded, &tree);
        let lights: Vec<RenderLight> = (scene.lights.iter())
            .map(|l| light_to_render_space(l, origin))
            .collect();
        let sources: Vec<LightSource> = lights.iter().map(LightSource::from_scene).collect();
        let emitters = (0..sources.len() as u32)
            .filter(|&i| !sources[i as usize].is_delta())
            .collect();
        World {
            build_ms: start.elapsed().as_secs_f64() * 1e3,
            sources,
            emitters,
            lights,
            prims: f.prims,
            accel,
            unbounded,
            materials,
            object_materials,
            camera: camera_to_render_space(&scene.camera, origin),
            origin,
            background: scene.background.clone(),
            object_from_world: f.object_from_world,
            scene_tree: tree,
            vertex_normals: f.vertex_normals,
        }
    }
}

fn camera_center(c: &Camera) -> DVec3 {
    match c {
        Camera::Orthographic { center, .. } | Camera::Perspective { center, .. } => *center,
    }
}

/// A world-space point in rendering space: subtracted in f64, rounded once.
fn point_to_render(p: DVec3, origin: DVec3) -> Vec3 {
    (p - origin).as_vec3()
}

fn camera_to_render_space(c: &Camera, origin: DVec3) -> Camera {
    let mut c = c.clone();
    match &mut c {
        Camera::Orthographic { center, .. } | Camera::Perspective { center, .. } => {
            *center -= origin
        }
    }
    c
}

/// A light in rendering space: its position (a point light's, an area
/// light's corner or centre) moved and rounded by [`point_to_render`].
fn light_to_render_space(l: &Light, origin: DVec3) -> RenderLight {
    l.map_points(|p| point_to_render(p, origin))
}

/// The 6.837 textures' matrices map *world* points into texture space; a
/// lookup now gets a rendering-space point `p − origin`, so the translation
/// back to world space is folded into each matrix (in f64), which keeps the
/// texture exactly where it was.
fn to_render_space(m: &Material, origin: DVec3) -> Material {
    match m {
        Material::Phong(_) => m.clone(),
        Material::Texture {
            kind,
            transform,
            a,
            b,
        } => Material::Texture {
            kind: kind.clone(),
            transform: (transform.as_dmat4() * DMat4::from_translation(origin)).as_mat4(),
            a: *a,
            b: *b,
        },
    }
}

/// `tree` is the scene's hierarchy over the primitives, for `bvh-hierarchy`.
fn build_aggregate(
    kind: AccelKind,
    prims: &[Primitive],
    ids: Vec<u32>,
    tree: &SceneTree,
) -> Box<dyn Aggregate> {
    match kind {
        AccelKind::None => Box::new(Brute::new(prims, ids)),
        AccelKind::Grid { res } => Box::new(Grid::new(prims, ids, res)),
        AccelKind::Octree => Box::new(Octree::new(prims, ids)),
        AccelKind::Bvh(split) => Box::new(Bvh::new(prims, ids, split)),
        AccelKind::OctreeInner => Box::new(Octree::with_storage(prims, ids, Storage::Inner)),
        AccelKind::NestedGrid { threshold, depth } => {
            Box::new(NestedGrid::new(prims, ids, threshold, depth))
        }
        AccelKind::BvhHierarchy => Box::new(HierarchyBvh::new(prims, ids, tree)),
        AccelKind::Bvh8 => Box::new(Bvh8::new(prims, ids)),
    }
}

struct Flattener {
    prims: Vec<Primitive>,
    /// `World::vertex_normals` so far (shorter than `prims` until the end:
    /// missing entries are flat).
    vertex_normals: Vec<[Vec3; 3]>,
    object_from_world: Vec<glam::Mat4>,
    default_material: u32,
    flatten: bool,
}

impl Flattener {
    /// Flattens `node`, whose space `m` maps into rendering space, and
    /// returns its tree over the primitives it became (the modeling
    /// hierarchy `bvh-hierarchy` uses).
    fn node(&mut self, node: &Node, m: DMat4, instance: u32) -> SceneTree {
        match node {
            Node::Group(children) => {
                SceneTree::Group(children.iter().map(|c| self.node(c, m, instance)).collect())
            }
            Node::Transform { matrix, child } => {
                let m = m * *matrix;
                let inv = m.inverse();
                if !inv.is_finite() || m.determinant() == 0.0 {
                    // A singular transform squashes its subtree to nothing visible.
                    return SceneTree::Group(Vec::new());
                }
                self.object_from_world.push(inv.as_mat4());
                let instance = (self.object_from_world.len() - 1) as u32;
                SceneTree::Transform {
                    to_world: m.as_mat4(),
                    to_object: inv.as_mat4(),
                    child: Box::new(self.node(child, m, instance)),
                }
            }
            Node::Moving { motion, child } => {
                // The subtree is flattened in the motion's object space and
                // each of its primitives wrapped: the static transforms
                // inside are baked as usual, the motion and the static part
                // outside are applied per ray at the ray's time.
                let start = self.prims.len();
                self.node(child, DMat4::IDENTITY, instance);
                let inner: Vec<Primitive> = self.prims.drain(start..).collect();
                // Moving triangles are shaded flat.
                self.vertex_normals.truncate(start);
                let parent = m.as_mat4();
                for p in inner {
                    if let Some(mv) = Moving::new(p.shape, motion.clone(), parent) {
                        self.prims.push(Primitive {
                            shape: Shape::Moving(Box::new(mv)),
                            ..p
                        });
                    }
                }
                // The primitives share one swept path: to `bvh-hierarchy`
                // they are one shape, split like a mesh's triangles.
                SceneTree::Shape(start as u32..self.prims.len() as u32)
            }
            Node::Shape { shape, material } => {
                let start = self.prims.len() as u32;
                self.shape(shape, *material, m, instance);
                SceneTree::Shape(start..self.prims.len() as u32)
            }
        }
    }

    /// Pushes the primitives of one shape whose space `m` maps into
    /// rendering space.
    fn shape(&mut self, shape: &Desc, material: Option<usize>, m: DMat4, instance: u32) {
        let material = material.map_or(self.default_material, |i| i as u32);
        let mut push = |shape: Shape| {
            self.prims.push(Primitive {
                shape,
                material,
                instance,
            })
        };
        // Instance 0: under no scene transform, only the rendering-space
        // translation, which is always baked.
        if !self.flatten && instance != 0 {
            for s in object_shapes(shape) {
                if let Some(x) = Transformed::from_f64(s, m) {
                    push(Shape::Transformed(Box::new(x)));
                }
            }
            return;
        }
        let point = |p: Vec3| m.transform_point3(p.as_dvec3()).as_vec3();
        match shape {
            Desc::Sphere { center, radius } => push(bake_sphere(*center, *radius, m)),
            Desc::Plane { normal, offset } => {
                if let Some(p) = Plane::from_f64(*normal, *offset, &m) {
                    push(Shape::Plane(p));
                }
            }
            Desc::Triangle(v) => push(Shape::Triangle(bake_triangle(v, &m))),
            Desc::Mesh(mesh) => {
                let pos: Vec<Vec3> = mesh.positions.iter().map(|&p| point(p)).collect();
                let flip = m.determinant() < 0.0;
                let first = self.prims.len();
                for t in &mesh.triangles {
                    let [a, b, c] = t.map(|i| pos[i as usize]);
                    self.prims.push(Primitive {
                        shape: Shape::Triangle(oriented(a, b, c, flip)),
                        material,
                        instance,
                    });
                }
                if mesh.normals.len() == mesh.positions.len() {
                    self.smooth(mesh, m, flip, first);
                }
            }
        }
    }
}

impl Flattener {
    /// Records the vertex normals of `mesh`, whose triangles are the
    /// primitives from `first` on, carried by the inverse transpose of `m`
    /// (in f64) and put in the order `oriented` gave the vertices.
    fn smooth(&mut self, mesh: &crate::scene::Mesh, m: DMat4, flip: bool, first: usize) {
        let normal_matrix = glam::DMat3::from_mat4(m).inverse().transpose();
        if !normal_matrix.is_finite() {
            return;
        }
        let normals: Vec<Vec3> = (mesh.normals.iter())
            .map(|n| {
                (normal_matrix * n.as_dvec3())
                    .try_normalize()
                    .map_or(Vec3::ZERO, |n| n.as_vec3())
            })
            .collect();
        self.vertex_normals.resize(first, [Vec3::ZERO; 3]);
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| normals[i as usize]);
            // A vertex without a normal makes its triangles flat.
            let n = if a == Vec3::ZERO || b == Vec3::ZERO || c == Vec3::ZERO {
                [Vec3::ZERO; 3]
            } else if flip {
                [a, c, b]
            } else {
                [a, b, c]
            };
            self.vertex_normals.push(n);
        }
    }
}

/// The object-space shapes of a description (a mesh gives one per
/// triangle), rounded to f32 in object space.
fn object_shapes(d: &Desc) -> Vec<Shape> {
    match d {
        Desc::Sphere { center, radius } => vec![Shape::Sphere(Sphere {
            center: center.as_vec3(),
            radius: *radius,
        })],
        Desc::Plane { normal, offset } => Plane::new(*normal, *offset as f32)
            .map(Shape::Plane)
            .into_iter()
            .collect(),
        Desc::Triangle(v) => {
            let [a, b, c] = v.map(|p| p.as_vec3());
            vec![Shape::Triangle(Triangle::new(a, b, c))]
        }
        Desc::Mesh(mesh) => mesh
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                Shape::Triangle(Triangle::new(a, b, c))
            })
            .collect(),
    }
}

/// A triangle carried through `m` in f64, each vertex rounded once.
fn bake_triangle(v: &[DVec3; 3], m: &DMat4) -> Triangle {
    let [a, b, c] = v.map(|p| m.transform_point3(p).as_vec3());
    oriented(a, b, c, m.determinant() < 0.0)
}

/// A mirroring matrix reverses the winding; swapping two vertices keeps the
/// front side where the inverse-transpose normal says it is.
fn oriented(a: Vec3, b: Vec3, c: Vec3, flip: bool) -> Triangle {
    if flip {
        Triangle::new(a, c, b)
    } else {
        Triangle::new(a, b, c)
    }
}

/// A sphere under a similarity (rotation, uniform scale, translation) is a
/// sphere, its centre carried in f64 and rounded once; anything else keeps
/// its matrix (the centre then rounded in object space).
fn bake_sphere(center: DVec3, radius: f32, m: DMat4) -> Shape {
    let cols = [
        m.x_axis.truncate(),
        m.y_axis.truncate(),
        m.z_axis.truncate(),
    ];
    let scale = cols[0].length();
    let rel = 1e-5 * scale.max(1e-300);
    let uniform = cols.iter().all(|c| (c.length() - scale).abs() <= rel)
        && cols[0].dot(cols[1]).abs() <= rel * scale
        && cols[1].dot(cols[2]).abs() <= rel * scale
        && cols[0].dot(cols[2]).abs() <= rel * scale
        && m.row(3) == glam::DVec4::W;
    let s = Sphere {
        center: center.as_vec3(),
        radius,
    };
    let center = m.transform_point3(center).as_vec3();
    if uniform {
        Shape::Sphere(Sphere {
            center,
            radius: (s.radius as f64 * scale) as f32,
        })
    } else {
        match Transformed::from_f64(Shape::Sphere(s), m) {
            Some(x) => Shape::Transformed(Box::new(x)),
            None => Shape::Sphere(Sphere {
                center,
                radius: 0.0,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Mat4, Ray};
    use crate::scene::{Background, Camera};
    use crate::stats::Counters;

    fn scene(root: Node) -> Scene {
        Scene {
            camera: Camera::Orthographic {
                center: Vec3::ZERO.as_dvec3(),
                direction: Vec3::NEG_Z,
                up: Vec3::Y,
                size: 1.0,
            },
            lights: vec![],
            background: Background::default(),
            materials: vec![],
            root,
            effects: Default::default(),
        }
    }

    fn sphere() -> Node {
        Node::Shape {
            shape: Desc::Sphere {
                center: Vec3::ZERO.as_dvec3(),
                radius: 1.0,
            },
            material: None,
        }
    }

    fn xf(m: Mat4, child: Node) -> Node {
        Node::Transform {
            matrix: m.as_dmat4(),
            child: Box::new(child),
        }
    }

    #[test]
    fn similarity_sphere_is_baked() {
        let m = Mat4::from_translation(Vec3::X)
            * Mat4::from_rotation_y(0.3)
            * Mat4::from_scale(Vec3::splat(2.0));
        let w = World::build(&scene(xf(m, sphere())), BuildOptions::default());
        match &w.prims[0].shape {
            Shape::Sphere(s) => {
                assert!((s.radius - 2.0).abs() < 1e-5);
                assert!((s.center - Vec3::X).length() < 1e-6);
            }
            other => panic!("expected a baked sphere, got {other:?}"),
        }
    }

    #[test]
    fn squashed_sphere_keeps_its_matrix() {
        let m = Mat4::from_scale(Vec3::new(1.0, 2.0, 1.0));
        let w = World::build(&scene(xf(m, sphere())), BuildOptions::default());
        assert!(matches!(w.prims[0].shape, Shape::Transformed(_)));
    }

    #[test]
    fn nested_transforms_compose_outer_first() {
        // Translate(5) ∘ Scale(2): the unit sphere's centre lands at x = 5, radius 2.
        let inner = xf(Mat4::from_scale(Vec3::splat(2.0)), sphere());
        let root = xf(Mat4::from_translation(Vec3::new(5.0, 0.0, 0.0)), inner);
        let w = World::build(&scene(root), BuildOptions::default());
        let r = Ray::new(Vec3::new(5.0, 0.0, 10.0), Vec3::NEG_Z);
        let h = w
            .intersect(&r, 0.0, f32::INFINITY, &mut Counters::default())
            .unwrap();
        assert!((h.t - 8.0).abs() < 1e-5);
    }

    /// `occluded_leaving` skips the plane a shadow ray leaves, and only it:
    /// between a floor and a ceiling, a ray up from the floor is blocked by
    /// the ceiling (one plane test: its own plane is not tried), a ray up
    /// from the ceiling is free, and one down from the ceiling meets the
    /// floor.
    #[test]
    fn a_ray_leaving_a_plane_skips_that_plane_only() {
        let plane = |offset: f32| Node::Shape {
            shape: Desc::Plane {
                normal: Vec3::Y,
                offset: f64::from(offset),
            },
            material: None,
        };
        let w = World::build(
            &scene(Node::Group(vec![plane(0.0), plane(1.0)])),
            BuildOptions::default(),
        );
        let mut c = Counters::default();
        let down = Ray::new(Vec3::new(0.3, 0.5, 0.2), Vec3::new(0.1, -1.0, 0.0));
        let up = Ray::new(Vec3::new(0.3, 0.5, 0.2), Vec3::new(0.1, 1.0, 0.0));
        let floor = w.intersect(&down, 0.0, f32::INFINITY, &mut c).unwrap();
        let ceiling = w.intersect(&up, 0.0, f32::INFINITY, &mut c).unwrap();
        assert_ne!(floor.prim, ceiling.prim);
        let leave = |h: &crate::world::Hit, d: Vec3, c: &mut Counters| {
            let mut s = crate::math::Spawn::leaving(h.surface_point(), h.prim);
            let r = s.spawn_ray(d);
            w.occluded_leaving(&r, 0.0, f32::INFINITY, Some(h.prim), c)
        };
        let before = c.intersection_tests;
        assert!(
            leave(&floor, Vec3::Y, &mut c),
            "the ceiling shadows the floor"
        );
        assert_eq!(
            c.intersection_tests - before,
            1,
            "the floor itself is not tested"
        );
        assert!(
            !leave(&ceiling, Vec3::Y, &mut c),
            "nothing above the ceiling"
        );
        assert!(
            leave(&ceiling, Vec3::NEG_Y, &mut c),
            "the floor below the ceiling"
        );
    }

    #[test]
    fn flattening_off_gives_the_same_hits() {
        let m = Mat4::from_translation(Vec3::new(0.5, 0.0, 0.0)) * Mat4::from_rotation_z(0.4);
        let tri = Node::Shape {
            shape: Desc::Triangle([DVec3::ZERO, DVec3::X, DVec3::Y]),
            material: None,
        };
        let root = Node::Group(vec![xf(m, tri), xf(m, sphere())]);
        let on = World::build(&scene(root.clone()), BuildOptions::default());
        let off = World::build(
            &scene(root),
            BuildOptions {
                flatten: false,
                ..BuildOptions::default()
            },
        );
        for k in 0..50 {
            let x = -1.5 + 0.06 * k as f32;
            let r = Ray::new(Vec3::new(x, 0.3, 5.0), Vec3::new(0.01, 0.0, -1.0));
            let mut c = Counters::default();
            let a = on.intersect(&r, 0.0, f32::INFINITY, &mut c);
            let b = off.intersect(&r, 0.0, f32::INFINITY, &mut c);
            assert_eq!(a.is_some(), b.is_some());
            if let (Some(a), Some(b)) = (a, b) {
                assert!((a.t - b.t).abs() < 1e-4);
                assert!((a.normal - b.normal).length() < 1e-4);
            }
        }
    }

    #[test]
    fn mirrored_triangle_keeps_inverse_transpose_normal() {
        let m = DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0));
        let t = bake_triangle(&[DVec3::ZERO, DVec3::X, DVec3::Y], &m);
        // (M^-1)^T (0,0,1) = (0,0,1).
        assert!((t.normal - Vec3::Z).length() < 1e-6);
    }
}
