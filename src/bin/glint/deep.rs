//! Generated scenes with deep transform hierarchies, for `glint bench`: where
//! the modeling hierarchy (`--accel bvh-hierarchy`) and flattening matter
//! most. Both are deterministic (no randomness), so every run benches the
//! same scene.

use glint::math::{Mat4, Vec3};
use glint::scene::{Mesh, Node, Scene, ShapeDesc};
use std::f32::consts::TAU;
use std::sync::Arc;

fn xf(matrix: Mat4, child: Node) -> Node {
    Node::Transform {
        matrix: matrix.as_dmat4(),
        child: Box::new(child),
    }
}

fn shape(shape: ShapeDesc, material: usize) -> Node {
    Node::Shape {
        shape,
        material: Some(material),
    }
}

/// A UV sphere of radius 1 with `nu × nv` quads (two triangles each, fewer
/// at the poles' degenerate quads, which are kept: meshes have them).
fn uv_sphere(nu: u32, nv: u32) -> Mesh {
    let mut m = Mesh::default();
    for j in 0..=nv {
        for i in 0..nu {
            let (th, ph) = (
                std::f32::consts::PI * j as f32 / nv as f32,
                TAU * i as f32 / nu as f32,
            );
            m.positions.push(Vec3::new(
                th.sin() * ph.cos(),
                th.cos(),
                th.sin() * ph.sin(),
            ));
        }
    }
    for j in 0..nv {
        for i in 0..nu {
            let (a, b) = (j * nu + i, j * nu + (i + 1) % nu);
            m.triangles.push([a, b + nu, b]);
            m.triangles.push([a, a + nu, b + nu]);
        }
    }
    m
}

/// A recursive tree of transformed groups, `depth` levels, `branching`
/// children per level. Each level is a group holding a branch (a sphere
/// stretched along y, which stays a transformed sphere even when
/// flattened) and its sub-branches, each under a translate · rotate · scale
/// 0.62 transform; the leaves are a 100-triangle mesh. Depth 5 with 3
/// branches: 243 leaves (24,300 triangles), 121 branches, 6 levels of
/// nested transforms.
pub fn tree(depth: u32, branching: u32) -> Scene {
    let leaf = Arc::new(uv_sphere(10, 5));
    framed(branch(depth, branching, &leaf, 0))
}

fn branch(depth: u32, branching: u32, leaf: &Arc<Mesh>, seed: u32) -> Node {
    if depth == 0 {
        return xf(
            Mat4::from_scale(Vec3::splat(0.9)),
            shape(ShapeDesc::Mesh(leaf.clone()), 1),
        );
    }
    let stem = xf(
        Mat4::from_translation(Vec3::Y) * Mat4::from_scale(Vec3::new(0.15, 1.0, 0.15)),
        shape(
            ShapeDesc::Sphere {
                center: Vec3::ZERO.as_dvec3(),
                radius: 1.0,
            },
            0,
        ),
    );
    let mut kids = vec![stem];
    for k in 0..branching {
        let yaw = TAU * (k as f32 + 0.37 * seed as f32) / branching as f32;
        let m = Mat4::from_translation(Vec3::Y * 1.9)
            * Mat4::from_rotation_y(yaw)
            * Mat4::from_rotation_z(0.6)
            * Mat4::from_scale(Vec3::splat(0.62));
        kids.push(xf(
            m,
            branch(depth - 1, branching, leaf, seed * branching + k + 1),
        ));
    }
    Node::Group(kids)
}

/// `n³` instances of `mesh` on a lattice, each turned differently, nested
/// as rows in slabs in a block (translate per level: 4 levels of
/// transforms), the way a modeller would place copies.
pub fn instances(mesh: Mesh, n: u32) -> Scene {
    let b = glint::math::Aabb::from_points(mesh.positions.iter().copied());
    let size = b.extent().max_element().max(1e-6);
    let mesh = Arc::new(mesh);
    let step = 1.3 * size;
    let level = |axis: Vec3, child: &dyn Fn(u32) -> Node| {
        Node::Group(
            (0..n)
                .map(|i| xf(Mat4::from_translation(axis * step * i as f32), child(i)))
                .collect(),
        )
    };
    let root = level(Vec3::Z, &|k| {
        level(Vec3::Y, &|j| {
            level(Vec3::X, &|i| {
                let turn = 0.7 * (i + 2 * j + 3 * k) as f32;
                xf(
                    Mat4::from_rotation_y(turn) * Mat4::from_translation(-b.center()),
                    shape(ShapeDesc::Mesh(mesh.clone()), 1),
                )
            })
        })
    });
    framed(root)
}

/// A scene around `root`: camera looking at its bounds, one light, two
/// materials (bark and leaves).
fn framed(root: Node) -> Scene {
    let mut scene = Scene::for_mesh(Mesh::default());
    let b = root.bounds(&glam::DMat4::IDENTITY);
    let (c, r) = (b.center(), 0.5 * b.extent().length());
    let view = Vec3::new(0.3, 0.4, 1.0).normalize();
    scene.camera = glint::scene::Camera::Perspective {
        center: (c + view * r * 2.2).as_dvec3(),
        direction: -view,
        up: Vec3::Y,
        angle_deg: 45.0,
    };
    let leaves = match &scene.materials[0] {
        glint::scene::Material::Phong(p) => glint::scene::Material::Phong(glint::scene::Phong {
            diffuse: Vec3::new(0.3, 0.7, 0.3),
            ..*p
        }),
        other => other.clone(),
    };
    scene.materials.push(leaves);
    scene.root = root;
    scene
}
