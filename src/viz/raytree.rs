//! The ray tree of one pixel: every ray the integrator (the Whitted tree,
//! or any other) spawned for it, recorded by a [`RayRecorder`] during an ordinary trace, then written
//! as JSON (the tree), OBJ or PLY line segments (to load beside the scene in
//! a 3-D viewer) or drawn over the rendered image in the camera's projection.
//!
//! Colours and the segment clamp are the course's (`NOTES.md`, A4): eye rays
//! grey (0.7, 0.7, 0.7), shadow rays green (0.1, 0.9, 0.1), reflected red
//! (0.9, 0.1, 0.1), transmitted blue (0.1, 0.1, 0.9); a ray that escapes is
//! drawn to `t = 100`. A shadow ray that something blocked is drawn dashed.

use super::draw::Canvas;
use crate::integrator::{Integrator, RayKind, RayRecorder, RecordedRay, Trace};
use crate::math::{Ray, Vec2, Vec3};
use crate::render::{pixel_of_screen, screen_point, CameraModel, PixelOffset};
use crate::sampler::{SampleStream, Sampler};
use crate::stats::Counters;
use crate::world::World;
use std::fmt::Write as _;

/// Segments are drawn for `t` in `[-T_CLAMP, T_CLAMP]` (the course's rayTree).
pub const T_CLAMP: f32 = 100.0;

/// The rays one pixel spawned, in the order they were traced.
#[derive(Clone, Debug)]
pub struct RayTree {
    /// The pixel: x from the left, y from the top of the image.
    pub pixel: (u32, u32),
    /// Image size the pixel belongs to.
    pub size: (u32, u32),
    /// Every ray, the eye ray first.
    pub rays: Vec<RecordedRay>,
    /// The pixel's colour.
    pub color: Vec3,
}

/// Traces pixel `(x, y)` (y from the top) of a `w`×`h` image through
/// `offset` of the pixel, recording every ray.
pub fn record<I: Integrator>(
    world: &World,
    camera: &CameraModel,
    integrator: &I,
    (w, h): (u32, u32),
    (x, y): (u32, u32),
    offset: PixelOffset,
) -> RayTree {
    let j = h - 1 - y.min(h - 1);
    let ray = camera.ray(screen_point(x.min(w - 1), j, offset.0, w, h));
    // Every random decision (light point, lobe, hemisphere) at the centre
    // of its stratum, as in a one-ray render at the pixel centre.
    let sampler = Sampler::fixed(Vec2::splat(0.5));
    let mut stream = sampler.stream((0, 0), 0);
    stream.skip();
    let tmin = camera.tmin();
    trace_recorded(world, integrator, &ray, tmin, &mut stream, (w, h), (x, y))
}

/// Traces sample `index` of pixel `(x, y)` (y from the top) of a `w`×`h`
/// image exactly as a render with `sampler` traces it (the pixel position,
/// lens point and every later decision from that sample's stream),
/// recording every ray: for the path tracer, one of the paths the render
/// averages, with its light samples and their MIS weights. Its colour is
/// that sample's value.
pub fn record_sample<I: Integrator>(
    world: &World,
    camera: &CameraModel,
    integrator: &I,
    (w, h): (u32, u32),
    (x, y): (u32, u32),
    sampler: &Sampler,
    index: u32,
) -> RayTree {
    let (i, j) = (x.min(w - 1), h - 1 - y.min(h - 1));
    let mut stream = sampler.stream((i, j), index);
    let offset = stream.next_2d();
    let ray = camera.sample_ray(screen_point(i, j, offset, w, h), &mut stream);
    let tmin = camera.tmin();
    trace_recorded(world, integrator, &ray, tmin, &mut stream, (w, h), (x, y))
}

/// Traces `ray` with `stream` through `integrator`, recording every ray,
/// as the tree of pixel `(x, y)` of a `w`×`h` image.
fn trace_recorded<I: Integrator>(
    world: &World,
    integrator: &I,
    ray: &Ray,
    tmin: f32,
    stream: &mut SampleStream,
    size: (u32, u32),
    pixel: (u32, u32),
) -> RayTree {
    let mut rec = RayRecorder::default();
    let cx = &mut Trace {
        world,
        stream,
        counters: &mut Counters::default(),
        observer: &mut rec,
        packets: false,
    };
    let (color, _) = integrator.li(cx, ray, tmin);
    RayTree {
        pixel,
        size,
        rays: rec.rays,
        color,
    }
}

/// The course's name and drawing colour of a ray kind.
pub fn kind_style(kind: RayKind) -> (&'static str, Vec3) {
    match kind {
        RayKind::Primary => ("eye", Vec3::splat(0.7)),
        RayKind::Shadow => ("shadow", Vec3::new(0.1, 0.9, 0.1)),
        RayKind::Reflected => ("reflected", Vec3::new(0.9, 0.1, 0.1)),
        RayKind::Transmitted => ("transmitted", Vec3::new(0.1, 0.1, 0.9)),
        RayKind::Occlusion => ("occlusion", Vec3::new(0.9, 0.8, 0.1)),
    }
}

/// Where a recorded ray's segment ends: its end point, or `t = ±T_CLAMP`
/// for a ray that escaped (or a light at infinity).
fn segment_end(r: &RecordedRay) -> f32 {
    if r.t_end.is_finite() {
        r.t_end.clamp(-T_CLAMP, T_CLAMP)
    } else {
        T_CLAMP
    }
}

impl RayTree {
    /// Rays of each kind, as (name, count), in the course's order.
    pub fn counts(&self) -> Vec<(&'static str, usize)> {
        [
            RayKind::Primary,
            RayKind::Shadow,
            RayKind::Reflected,
            RayKind::Transmitted,
            RayKind::Occlusion,
        ]
        .into_iter()
        .map(|k| {
            let n = self.rays.iter().filter(|r| r.kind == k).count();
            (kind_style(k).0, n)
        })
        // The course has no occlusion rays: listed only when there are some.
        .filter(|&(name, n)| n > 0 || name != "occlusion")
        .collect()
    }

    /// The tree as JSON: the pixel, counts by kind and every ray with its
    /// kind, depth, weight, origin, direction, end, hit normal, for shadow
    /// rays whether it was blocked and, for the rays that carried light to
    /// a path (the path tracer's light samples and emitters hit), the MIS
    /// weight and the radiance added (`null` for the others).
    pub fn to_json(&self) -> serde_json::Value {
        let v = |p: Vec3| serde_json::json!([p.x, p.y, p.z]);
        let rays: Vec<_> = self
            .rays
            .iter()
            .map(|r| {
                let hit = r.kind != RayKind::Shadow && r.t_end.is_finite();
                serde_json::json!({
                    "kind": kind_style(r.kind).0,
                    "depth": r.depth,
                    "weight": r.weight,
                    "origin": v(r.ray.origin),
                    "direction": v(r.ray.dir),
                    "t_end": r.t_end.is_finite().then_some(r.t_end),
                    "end": v(r.ray.at(segment_end(r))),
                    "hit": hit,
                    "normal": r.normal.map(v),
                    "occluded": r.occluded,
                    "mis_weight": r.light.map(|l| l.0),
                    "contribution": r.light.map(|l| v(l.1)),
                })
            })
            .collect();
        let counts: serde_json::Map<String, serde_json::Value> = self
            .counts()
            .into_iter()
            .map(|(k, n)| (k.to_string(), n.into()))
            .collect();
        serde_json::json!({
            "pixel": [self.pixel.0, self.pixel.1],
            "size": [self.size.0, self.size.1],
            "color": v(self.color),
            "counts": counts,
            "max_depth": self.rays.iter().map(|r| r.depth).max().unwrap_or(0),
            "rays": rays,
        })
    }

    /// Line segments as OBJ: one group per kind, per-vertex colours
    /// (`v x y z r g b`, which MeshLab, Blender and most viewers read).
    pub fn to_obj(&self) -> String {
        let mut s = format!(
            "# glint ray tree of pixel ({}, {}) of a {}x{} image: {} rays\n",
            self.pixel.0,
            self.pixel.1,
            self.size.0,
            self.size.1,
            self.rays.len()
        );
        for (i, r) in self.rays.iter().enumerate() {
            let (name, c) = kind_style(r.kind);
            let (a, b) = (r.ray.origin, r.ray.at(segment_end(r)));
            let _ = writeln!(s, "g {name}");
            for p in [a, b] {
                let _ = writeln!(s, "v {} {} {} {} {} {}", p.x, p.y, p.z, c.x, c.y, c.z);
            }
            let _ = writeln!(s, "l {} {}", 2 * i + 1, 2 * i + 2);
        }
        s
    }

    /// Line segments as ASCII PLY: vertices and coloured edges.
    pub fn to_ply(&self) -> String {
        let n = self.rays.len();
        let mut s = format!(
            "ply\nformat ascii 1.0\ncomment glint ray tree of pixel ({}, {})\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             element edge {n}\nproperty int vertex1\nproperty int vertex2\n\
             property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
            self.pixel.0,
            self.pixel.1,
            2 * n
        );
        for r in &self.rays {
            for p in [r.ray.origin, r.ray.at(segment_end(r))] {
                let _ = writeln!(s, "{} {} {}", p.x, p.y, p.z);
            }
        }
        for (i, r) in self.rays.iter().enumerate() {
            let c = kind_style(r.kind).1 * 255.0;
            let _ = writeln!(
                s,
                "{} {} {} {} {}",
                2 * i,
                2 * i + 1,
                c.x as u8,
                c.y as u8,
                c.z as u8
            );
        }
        s
    }

    /// Draws every ray over `canvas` (the rendered image) in the camera's
    /// projection, clipped at the frame; blocked shadow rays dashed. Returns
    /// how many rays have some visible part.
    pub fn draw(&self, canvas: &mut Canvas, camera: &CameraModel) -> usize {
        let (w, h) = (canvas.width, canvas.height);
        let mut visible = 0;
        for (r, seg) in self.rays.iter().zip(self.projected(camera, (w, h))) {
            let Some((pa, pb)) = seg else {
                continue;
            };
            let frame = (Vec2::ZERO, Vec2::new(w as f32, h as f32));
            if super::draw::clip(pa, pb, frame.0, frame.1).is_some() {
                visible += 1;
            }
            let dash = if r.occluded { 3 } else { 0 };
            canvas.line(pa, pb, kind_style(r.kind).1, dash);
            if r.kind != RayKind::Shadow && r.t_end.is_finite() {
                canvas.cross(pb, 2, kind_style(r.kind).1);
            }
        }
        visible
    }
}

impl RayTree {
    /// Where each ray's segment appears in a `w`×`h` image seen through
    /// `camera`: its end points in continuous pixel coordinates (y up from
    /// the bottom edge, as [`pixel_of_screen`] gives them), unclipped by the
    /// frame, or `None` when no part of it lies in front of the camera. One
    /// entry per ray, in [`RayTree::rays`] order: what [`RayTree::draw`]
    /// draws, and what `glint serve` sends the page.
    pub fn projected(&self, camera: &CameraModel, (w, h): (u32, u32)) -> Vec<Option<(Vec2, Vec2)>> {
        self.rays
            .iter()
            .map(|r| {
                let (a, b) = clip_to_front(camera, r.ray.origin, r.ray.at(segment_end(r)))?;
                let (sa, sb) = (camera.project(a)?, camera.project(b)?);
                Some((pixel_of_screen(sa, w, h), pixel_of_screen(sb, w, h)))
            })
            .collect()
    }
}

/// The part of segment `a`–`b` in front of a perspective camera (a small
/// distance past its centre plane), so that projecting it is defined.
fn clip_to_front(camera: &CameraModel, a: Vec3, b: Vec3) -> Option<(Vec3, Vec3)> {
    if !camera.is_perspective() {
        return Some((a, b));
    }
    let (da, db) = (camera.depth_of(a), camera.depth_of(b));
    let near = 1e-3 * (da.abs().max(db.abs())).max(1e-6);
    match (da >= near, db >= near) {
        (true, true) => Some((a, b)),
        (false, false) => None,
        _ => {
            let t = (near - da) / (db - da);
            let m = a + (b - a) * t;
            Some(if da >= near { (a, m) } else { (m, b) })
        }
    }
}

/// The image `(w, h)` rendered as `glint render` renders it (one ray through
/// each pixel's centre), dimmed, with `tree` drawn over it.
pub fn overlay<I: Integrator>(
    world: &World,
    camera: &CameraModel,
    integrator: &I,
    (w, h): (u32, u32),
    tree: &RayTree,
) -> Canvas {
    let (frame, _) = crate::render::render(world, camera, integrator, (w, h), PixelOffset::CENTER);
    let mut canvas = Canvas::new(w, h, frame.color);
    canvas.dim(0.5);
    tree.draw(&mut canvas, camera);
    canvas
}
