use super::SampleStream;
use crate::light::area::concentric_disk;
use crate::math::{Motion, Ray, Vec2, Vec3};
use crate::scene::{Camera, Lens};
use glam::DVec3;
use std::sync::Arc;

/// A camera ready to make rays: an orthonormal frame built from the scene's
/// direction and approximate up vector; optionally moving.
#[derive(Clone, Debug)]
pub struct CameraModel {
    center: Vec3,
    direction: Vec3,
    horizontal: Vec3,
    up: Vec3,
    /// Orthographic: world size of the screen; perspective: `2·tan(angle/2)`.
    span: f32,
    perspective: bool,
    lens: Lens,
    /// The moving camera's rig, if it moves.
    rig: Option<Arc<Rig>>,
}

/// A moving camera: the rig's keyframed motion carries the camera's
/// centre, direction and up, in world space, while the image is computed in
/// rendering space (see [`crate::world`]).
#[derive(Debug)]
struct Rig {
    /// The camera at the rig's rest pose, in rendering space.
    base: Camera,
    motion: Arc<Motion>,
    /// Where the rendering-space origin lies in world space.
    origin: DVec3,
}

impl Rig {
    /// The camera at instant `time`. The pose is applied in f64 in world
    /// space (rendering space plus `origin`), then moved back and rounded
    /// once, so a scene far from the origin moves its camera as precisely
    /// as one near it.
    fn at(&self, time: f32) -> Camera {
        let m = self.motion.matrix(time).as_dmat4();
        let o = self.origin;
        let point = |p: DVec3| m.transform_point3(p + o) - o;
        let vector = |v: Vec3| m.transform_vector3(v.as_dvec3()).as_vec3();
        match self.base {
            Camera::Orthographic {
                center,
                direction,
                up,
                size,
            } => Camera::Orthographic {
                center: point(center),
                direction: vector(direction),
                up: vector(up),
                size,
            },
            Camera::Perspective {
                center,
                direction,
                up,
                angle_deg,
            } => Camera::Perspective {
                center: point(center),
                direction: vector(direction),
                up: vector(up),
                angle_deg,
            },
        }
    }
}

impl CameraModel {
    /// The frame of `cam`: `horizontal = direction × up`, `up' = horizontal × direction`.
    pub fn new(cam: &Camera) -> Self {
        let (center, direction, up, span, perspective) = match *cam {
            Camera::Orthographic {
                center,
                direction,
                up,
                size,
            } => (center.as_vec3(), direction, up, size, false),
            Camera::Perspective {
                center,
                direction,
                up,
                angle_deg,
            } => (
                center.as_vec3(),
                direction,
                up,
                2.0 * (angle_deg.to_radians() * 0.5).tan(),
                true,
            ),
        };
        // In f64: an f32 `normalize` overflows to zero for vectors longer than
        // ~1e19 and underflows for shorter than ~1e-19, and the cross product
        // of a nearly parallel up vector can cancel to zero; any of these made
        // every camera ray NaN. The parser has checked that the vectors are
        // non-zero and not parallel, in f64.
        let d = direction.as_dvec3().normalize();
        let h = d.cross(up.as_dvec3()).normalize();
        let (direction, horizontal, up) = (d.as_vec3(), h.as_vec3(), h.cross(d).as_vec3());
        Self {
            center,
            direction,
            horizontal,
            up,
            span,
            perspective,
            lens: Lens::default(),
            rig: None,
        }
    }

    /// The camera a render of `world` uses: the scene's camera in rendering
    /// space with the scene's lens and shutter, on its rig if it moves.
    pub fn of_world(world: &crate::world::World, effects: &crate::scene::Effects) -> Self {
        let cam = CameraModel::new(world.camera()).with_lens(effects.lens);
        match &effects.camera_motion {
            Some(m) => cam.with_motion(world.camera(), m.clone(), world.origin()),
            None => cam,
        }
    }

    /// The same camera carried by a rig moving along `motion` (world space);
    /// `cam` is the camera in rendering space (as [`CameraModel::new`] takes
    /// it) and `origin` the rendering-space origin in world space. Each
    /// camera ray then starts from the camera's pose at the ray's time.
    pub fn with_motion(self, cam: &Camera, motion: Arc<Motion>, origin: DVec3) -> Self {
        let rig = Rig {
            base: cam.clone(),
            motion,
            origin,
        };
        Self {
            rig: Some(Arc::new(rig)),
            ..self
        }
    }

    /// The camera at instant `time` (itself, unless it moves).
    pub fn at_time(&self, time: f32) -> CameraModel {
        match &self.rig {
            Some(rig) => CameraModel::new(&rig.at(time)).with_lens(self.lens),
            None => self.clone(),
        }
    }

    /// The same camera with a thin lens and shutter.
    pub fn with_lens(self, lens: Lens) -> Self {
        Self { lens, ..self }
    }

    /// The camera ray of one camera sample through screen point `s`: its
    /// time is the stream's next 1-D value mapped onto the shutter interval
    /// (only when the shutter is open for a while), its start the next 2-D
    /// value mapped onto the lens (only with an aperture).
    ///
    /// Thin lens: every ray through screen point `s` passes through the point
    /// where the pinhole ray meets the focus plane (at `focus_distance` along
    /// the viewing direction), so that plane is sharp and a point at depth
    /// `z` spreads over a disk of radius `aperture · |z − f| / z` on it.
    pub fn sample_ray(&self, s: Vec2, stream: &mut SampleStream) -> Ray {
        let [open, close] = self.lens.shutter;
        let time = if self.lens.has_motion_blur() {
            open + (close - open) * stream.next_1d()
        } else {
            open
        };
        match &self.rig {
            // A moving camera: the frame at the ray's time makes the ray.
            Some(rig) => CameraModel::new(&rig.at(time))
                .with_lens(self.lens)
                .lens_ray(s, time, stream),
            None => self.lens_ray(s, time, stream),
        }
    }

    /// The ray through `s` at `time`, through the lens point the stream's
    /// next 2-D value picks (with an aperture).
    fn lens_ray(&self, s: Vec2, time: f32, stream: &mut SampleStream) -> Ray {
        if !self.lens.has_depth_of_field() {
            return self.ray(s).at_time(time);
        }
        let l = concentric_disk(stream.next_2d()) * self.lens.aperture;
        let lens = l.x * self.horizontal + l.y * self.up;
        let offset = self.screen_offset(s);
        // Every ray through `s` passes through the point where the pinhole
        // ray meets the focus plane. Perspective: `direction + offset` is
        // that ray's direction scaled to unit depth along the viewing
        // direction (the frame is orthonormal: the offset adds no depth),
        // so the focus point lies `focus_distance` times it from the
        // centre. Orthographic: `focus_distance` along the parallel ray.
        // The new direction, focus point minus lens point, is taken
        // relative to the pinhole ray's start, without the centre: no
        // cancellation, no division and one normalisation (perf,
        // dof_spheres_lit: the two normalisations' square roots and
        // divisions, and what waited on them, drew the largest share of
        // this function's samples; the whole render ran 3% faster with
        // one of them gone).
        let (start, to_focus) = if self.perspective {
            (
                self.center,
                self.lens.focus_distance * (self.direction + offset),
            )
        } else {
            (
                self.center + offset,
                self.lens.focus_distance * self.direction,
            )
        };
        Ray::new(start + lens, (to_focus - lens).normalize()).at_time(time)
    }

    /// Where screen point `s` lies on the screen plane, relative to its
    /// centre (one unit along the viewing direction for a perspective
    /// camera).
    #[inline]
    fn screen_offset(&self, s: Vec2) -> Vec3 {
        (s.x - 0.5) * self.span * self.horizontal + (s.y - 0.5) * self.span * self.up
    }

    /// The ray through screen point `s` in `[0,1]²` (the square spanned by
    /// the image's longer side; (0,0) is bottom-left).
    pub fn ray(&self, s: Vec2) -> Ray {
        let offset = self.screen_offset(s);
        if self.perspective {
            Ray::new(self.center, (self.direction + offset).normalize())
        } else {
            Ray::new(self.center + offset, self.direction)
        }
    }

    /// Where the world point `p` appears: the screen point (in the `[0,1]²`
    /// coordinates of [`CameraModel::ray`]) whose ray passes through `p`, or
    /// `None` for a point on or behind a perspective camera's centre plane.
    /// The inverse of `ray`, for drawing world-space things over an image.
    pub fn project(&self, p: Vec3) -> Option<Vec2> {
        let v = p - self.center;
        let (x, y) = (v.dot(self.horizontal), v.dot(self.up));
        let (x, y) = if self.perspective {
            let z = v.dot(self.direction);
            if z <= 0.0 {
                return None;
            }
            (x / z, y / z)
        } else {
            (x, y)
        };
        Some(Vec2::new(x / self.span + 0.5, y / self.span + 0.5))
    }

    /// Signed distance of `p` in front of the camera's centre plane (along
    /// the viewing direction); what [`CameraModel::project`] needs positive.
    pub fn depth_of(&self, p: Vec3) -> f32 {
        (p - self.center).dot(self.direction)
    }

    /// The width of one pixel of a `w`×`h` image on the screen plane: for a
    /// perspective camera at unit distance along the viewing direction
    /// (the angle between neighbouring pixels' rays near the centre, in
    /// radians), for an orthographic one in world units.
    pub fn pixel_span(&self, (w, h): (u32, u32)) -> f32 {
        self.span / w.max(h).max(1) as f32
    }

    /// Whether the camera is perspective (else orthographic).
    pub fn is_perspective(&self) -> bool {
        self.perspective
    }

    /// Smallest `t` a camera ray accepts: orthographic cameras see objects
    /// behind their centre plane (scene1_07 puts the camera inside spheres).
    pub fn tmin(&self) -> f32 {
        if self.perspective {
            0.0
        } else {
            f32::NEG_INFINITY
        }
    }
}

/// Screen coordinate of a point in pixel `(i, j)` at in-pixel offset `o`
/// (`(0.5, 0.5)` = the centre) of a `w`×`h` image: the longer side spans
/// `[0,1]`, the shorter one is centred and cropped.
pub fn screen_point(i: u32, j: u32, o: Vec2, w: u32, h: u32) -> Vec2 {
    let m = w.max(h) as f32;
    Vec2::new(
        (i as f32 + o.x - w as f32 * 0.5) / m + 0.5,
        (j as f32 + o.y - h as f32 * 0.5) / m + 0.5,
    )
}

/// The inverse of [`screen_point`]: continuous pixel coordinates of screen
/// point `s` in a `w`×`h` image, x to the right and y *up* from the bottom
/// edge (pixel `(i, j)` covers `[i, i+1]×[j, j+1]`).
pub fn pixel_of_screen(s: Vec2, w: u32, h: u32) -> Vec2 {
    let m = w.max(h) as f32;
    Vec2::new(
        (s.x - 0.5) * m + w as f32 * 0.5,
        (s.y - 0.5) * m + h as f32 * 0.5,
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn project_inverts_ray() {
        for cam in [
            Camera::Perspective {
                center: Vec3::new(1.0, 2.0, 3.0).as_dvec3(),
                direction: Vec3::new(0.2, -0.5, -1.0),
                up: Vec3::Y,
                angle_deg: 40.0,
            },
            Camera::Orthographic {
                center: Vec3::new(1.0, 2.0, 3.0).as_dvec3(),
                direction: Vec3::new(0.2, -0.5, -1.0),
                up: Vec3::Y,
                size: 5.0,
            },
        ] {
            let c = CameraModel::new(&cam);
            for s in [
                Vec2::new(0.1, 0.7),
                Vec2::new(0.5, 0.5),
                Vec2::new(0.9, 0.2),
            ] {
                let p = c.ray(s).at(7.5);
                let back = c.project(p).unwrap();
                assert!((back - s).length() < 1e-5, "{s} -> {back}");
                let px = pixel_of_screen(back, 40, 30);
                let s2 = screen_point(0, 0, px, 40, 30);
                assert!((s2 - back).length() < 1e-5);
            }
            if c.is_perspective() {
                assert!(c.project(c.ray(Vec2::splat(0.5)).at(-1.0)).is_none());
            }
        }
    }

    use super::*;

    /// Thin lens, closed form: every lens ray through a screen point starts
    /// on the lens (the disk of radius `aperture` around the centre, in the
    /// plane of `horizontal` and `up`) and passes through the pinhole ray's
    /// point on the focus plane, `focus_distance` along the viewing
    /// direction (orthographic: `focus_distance` along the parallel ray);
    /// the lens points spread over the disk, and a pinhole's rays are the
    /// plain rays.
    #[test]
    fn lens_rays_start_on_the_lens_and_meet_at_the_focus_point() {
        let (center, direction) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.2, -0.5, -1.0));
        let lens = Lens {
            aperture: 0.3,
            focus_distance: 6.0,
            shutter: [0.0, 0.0],
        };
        for cam in [
            Camera::Perspective {
                center: center.as_dvec3(),
                direction,
                up: Vec3::Y,
                angle_deg: 40.0,
            },
            Camera::Orthographic {
                center: center.as_dvec3(),
                direction,
                up: Vec3::Y,
                size: 5.0,
            },
        ] {
            let pinhole = CameraModel::new(&cam);
            let c = pinhole.clone().with_lens(lens);
            let sampler = crate::sampler::Sampler::new(crate::sampler::SamplerKind::Random, 64, 7);
            for s in [
                Vec2::new(0.1, 0.7),
                Vec2::new(0.5, 0.5),
                Vec2::new(0.9, 0.2),
            ] {
                let plain = pinhole.ray(s);
                let d = c.direction;
                // The pinhole ray's point on the focus plane (or at the focus
                // distance along a parallel ray), computed here from the frame.
                let focus = if c.is_perspective() {
                    let p = plain.at(6.0 / plain.dir.dot(d));
                    assert!(((p - c.center).dot(d) - 6.0).abs() < 1e-4);
                    p
                } else {
                    plain.origin + 6.0 * d
                };
                let mut widest: f32 = 0.0;
                for index in 0..64 {
                    let r = c.sample_ray(s, &mut sampler.stream((3, 4), index));
                    let off = r.origin - plain.origin;
                    assert!(off.dot(d).abs() < 1e-5, "{off} leaves the lens plane");
                    assert!(off.length() <= 0.3 + 1e-5, "{off} outside the lens");
                    widest = widest.max(off.length());
                    assert!((r.dir.length() - 1.0).abs() < 1e-5);
                    // Distance from the focus point to the ray's line.
                    let v = focus - r.origin;
                    let miss = (v - v.dot(r.dir) * r.dir).length();
                    assert!(miss < 1e-4, "{cam:?} {s}: {miss}");
                    assert!(v.dot(r.dir) > 0.0);
                }
                assert!(widest > 0.2, "lens points spread over the disk: {widest}");
                let r = pinhole.sample_ray(s, &mut sampler.stream((3, 4), 0));
                assert_eq!((r.origin, r.dir), (plain.origin, plain.dir));
            }
        }
    }

    /// With the shutter open over `[0.25, 0.75]`, camera rays carry times
    /// spread over that interval and are otherwise the pinhole's rays.
    #[test]
    fn shutter_times_spread_over_the_open_interval() {
        let pinhole = CameraModel::new(&Camera::Perspective {
            center: Vec3::ZERO.as_dvec3(),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            angle_deg: 30.0,
        });
        let c = pinhole.clone().with_lens(Lens {
            shutter: [0.25, 0.75],
            ..Lens::default()
        });
        let sampler = crate::sampler::Sampler::new(crate::sampler::SamplerKind::Random, 64, 1);
        let s = Vec2::new(0.3, 0.6);
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for index in 0..64 {
            let r = c.sample_ray(s, &mut sampler.stream((0, 0), index));
            assert!((0.25..0.75).contains(&r.time), "{}", r.time);
            (lo, hi) = (lo.min(r.time), hi.max(r.time));
            let plain = pinhole.ray(s);
            assert_eq!((r.origin, r.dir), (plain.origin, plain.dir));
        }
        assert!(lo < 0.3 && hi > 0.7, "times {lo}..{hi}");
    }

    /// A moving camera is posed in world space: the rig turns a quarter
    /// turn about world's y axis while the rendering space's origin lies at
    /// world (100, 0, 0). The camera at rendering (0, 0, 5), world
    /// (100, 0, 5), ends at world (5, 0, −100), rendering (−95, 0, −100),
    /// looking along −x; at rest it stays where it was.
    #[test]
    fn a_moving_camera_is_posed_in_world_space() {
        use crate::math::{Keyframe, Motion};
        let cam = Camera::Perspective {
            center: Vec3::new(0.0, 0.0, 5.0).as_dvec3(),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            angle_deg: 30.0,
        };
        let turned = Keyframe {
            rotation: glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            ..Keyframe::identity(1.0)
        };
        let motion = Motion::new(vec![Keyframe::identity(0.0), turned]).unwrap();
        let c =
            CameraModel::new(&cam).with_motion(&cam, Arc::new(motion), DVec3::new(100.0, 0.0, 0.0));
        let near = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-3;
        let start = c.at_time(0.0);
        assert!(
            near(start.center, Vec3::new(0.0, 0.0, 5.0)),
            "{:?}",
            start.center
        );
        let end = c.at_time(1.0);
        assert!(
            near(end.center, Vec3::new(-95.0, 0.0, -100.0)),
            "{:?}",
            end.center
        );
        assert!(near(end.direction, Vec3::NEG_X), "{:?}", end.direction);
        assert!(near(end.up, Vec3::Y), "{:?}", end.up);
    }

    /// Depth is the signed distance along the viewing direction from the
    /// centre plane, whatever the point's sideways offset.
    #[test]
    fn depth_is_measured_along_the_viewing_direction() {
        let c = CameraModel::new(&Camera::Perspective {
            center: Vec3::new(1.0, 2.0, 3.0).as_dvec3(),
            direction: Vec3::new(0.0, 0.0, -2.0),
            up: Vec3::Y,
            angle_deg: 40.0,
        });
        assert_eq!(c.depth_of(Vec3::new(1.0, 2.0, -1.0)), 4.0);
        assert_eq!(c.depth_of(Vec3::new(6.0, -5.0, -1.0)), 4.0);
        assert_eq!(c.depth_of(Vec3::new(1.0, 2.0, 5.5)), -2.5);
        assert_eq!(c.depth_of(Vec3::new(9.0, 2.0, 3.0)), 0.0);
    }

    #[test]
    fn frame_is_orthonormal_for_skewed_up() {
        let c = CameraModel::new(&Camera::Perspective {
            center: Vec3::ZERO.as_dvec3(),
            direction: Vec3::new(0.0, -6.0, -16.0),
            up: Vec3::Y,
            angle_deg: 30.0,
        });
        assert!(c.up.dot(c.direction).abs() < 1e-6);
        assert!(c.horizontal.dot(c.direction).abs() < 1e-6);
        assert!((c.up.length() - 1.0).abs() < 1e-6);
        assert!(c.up.y > 0.0 && c.horizontal.x > 0.0);
    }

    #[test]
    fn perspective_edges_are_at_half_angle() {
        let c = CameraModel::new(&Camera::Perspective {
            center: Vec3::ZERO.as_dvec3(),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            angle_deg: 90.0,
        });
        let r = c.ray(Vec2::new(1.0, 0.5));
        assert!((r.dir.x - r.dir.z.abs()).abs() < 1e-6); // 45° to the right
    }

    #[test]
    fn orthographic_size_is_the_full_extent() {
        let c = CameraModel::new(&Camera::Orthographic {
            center: Vec3::new(0.0, 0.0, 10.0).as_dvec3(),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            size: 5.0,
        });
        assert!((c.ray(Vec2::new(1.0, 0.5)).origin.x - 2.5).abs() < 1e-6);
        assert!((c.ray(Vec2::new(0.5, 0.0)).origin.y + 2.5).abs() < 1e-6);
        assert_eq!(c.tmin(), f32::NEG_INFINITY);
    }

    #[test]
    fn wide_image_crops_vertically() {
        let s = screen_point(0, 0, Vec2::splat(0.5), 400, 200);
        assert!((s.x - 0.5 / 400.0).abs() < 1e-6);
        assert!((s.y - (0.5 - 100.0 / 400.0 + 0.5 / 400.0)).abs() < 1e-6);
    }
}
