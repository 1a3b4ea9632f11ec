//! Keyframed motion: a transform given at a few instants (translation,
//! rotation as a unit quaternion, scale) and interpolated in between, for
//! motion blur.

use super::Aabb;
use glam::{Mat4, Quat, Vec3};

/// The transform of a moving object at one instant: `T · R · S` (scale
/// first, then rotation, then translation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keyframe {
    /// Instant of this pose.
    pub time: f32,
    /// Translation.
    pub translation: Vec3,
    /// Rotation (unit quaternion).
    pub rotation: Quat,
    /// Scale per axis (no component zero).
    pub scale: Vec3,
}

impl Keyframe {
    /// The identity pose at `time`.
    pub fn identity(time: f32) -> Self {
        Self {
            time,
            translation: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        }
    }
}

/// Keyframes in increasing time order (at least one). Before the first and
/// after the last keyframe the pose holds still.
///
/// Why decomposed poses and not matrices: interpolating matrices entry by
/// entry shrinks a rotating object halfway (the average of two rotations is
/// not a rotation); translation, quaternion and scale interpolate into valid
/// poses, and the quaternion takes the shortest arc at constant speed.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    keys: Vec<Keyframe>,
}

impl Motion {
    /// The motion through `keys`; `None` when there are none or their times
    /// do not strictly increase.
    pub fn new(keys: Vec<Keyframe>) -> Option<Self> {
        let increasing = keys.windows(2).all(|w| w[0].time < w[1].time);
        (!keys.is_empty() && increasing).then_some(Self { keys })
    }

    /// The keyframes.
    pub fn keys(&self) -> &[Keyframe] {
        &self.keys
    }

    /// Translation, rotation and scale at instant `time`.
    pub fn pose(&self, time: f32) -> (Vec3, Quat, Vec3) {
        let k = &self.keys;
        let last = k.len() - 1;
        if time <= k[0].time || last == 0 {
            return (k[0].translation, k[0].rotation, k[0].scale);
        }
        if time >= k[last].time {
            return (k[last].translation, k[last].rotation, k[last].scale);
        }
        // Few keyframes: a linear scan beats a binary search.
        let i = k.iter().position(|key| key.time > time).unwrap_or(last) - 1;
        let (a, b) = (&k[i], &k[i + 1]);
        let s = (time - a.time) / (b.time - a.time);
        (
            a.translation.lerp(b.translation, s),
            a.rotation.slerp(b.rotation, s),
            a.scale.lerp(b.scale, s),
        )
    }

    /// Object-to-parent matrix at instant `time`.
    pub fn matrix(&self, time: f32) -> Mat4 {
        let (t, r, s) = self.pose(time);
        Mat4::from_scale_rotation_translation(s, r, t)
    }

    /// Parent-to-object matrix at instant `time`, built from the inverted
    /// pose (`S⁻¹ · R⁻¹ · T⁻¹`) rather than by a general 4×4 inverse.
    pub fn inverse_matrix(&self, time: f32) -> Mat4 {
        let (t, r, s) = self.pose(time);
        Mat4::from_scale(s.recip()) * Mat4::from_quat(r.conjugate()) * Mat4::from_translation(-t)
    }

    /// A box holding the object box `b` seen through `parent · matrix(t)` for
    /// every instant: what accelerators see of a moving object, so any of
    /// them works unchanged on timed rays.
    ///
    /// The pose is sampled [`SWEEP_STEPS`] times per keyframe interval and
    /// the union of those boxes is grown by the largest distance any box
    /// corner moved between two consecutive samples. Between samples a
    /// corner follows a smooth arc whose distance from its chord is a small
    /// fraction of the chord (`r(1 - cos(θ/2))` against `2r·sin(θ/2)` for a
    /// rotation by `θ`), so growing by the whole chord is conservative.
    pub fn swept_bounds(&self, b: &Aabb, parent: &Mat4) -> Aabb {
        if !b.is_finite() || b.is_empty() {
            return *b;
        }
        let corners = |m: &Mat4| -> [Vec3; 8] {
            std::array::from_fn(|i| {
                let p = Vec3::new(
                    if i & 1 == 0 { b.min.x } else { b.max.x },
                    if i & 2 == 0 { b.min.y } else { b.max.y },
                    if i & 4 == 0 { b.min.z } else { b.max.z },
                );
                m.transform_point3(p)
            })
        };
        let mut out = Aabb::EMPTY;
        let mut step = 0.0f32;
        let mut prev: Option<[Vec3; 8]> = None;
        let k = &self.keys;
        let mut times = vec![k[0].time];
        for w in k.windows(2) {
            for j in 1..=SWEEP_STEPS {
                times.push(w[0].time + (w[1].time - w[0].time) * j as f32 / SWEEP_STEPS as f32);
            }
        }
        for t in times {
            let c = corners(&(*parent * self.matrix(t)));
            for (i, p) in c.iter().enumerate() {
                out = out.grow(*p);
                if let Some(q) = &prev {
                    step = step.max((*p - q[i]).length());
                }
            }
            prev = Some(c);
        }
        // Plus a relative margin for the rounding of the matrices themselves.
        let pad = step + 1e-5 * out.min.abs().max(out.max.abs()).max_element().max(1.0);
        Aabb::new(out.min - Vec3::splat(pad), out.max + Vec3::splat(pad))
    }
}

/// Pose samples per keyframe interval in [`Motion::swept_bounds`].
pub const SWEEP_STEPS: u32 = 32;

#[cfg(test)]
mod tests {
    use super::*;

    fn spin() -> Motion {
        Motion::new(vec![
            Keyframe::identity(0.0),
            Keyframe {
                time: 1.0,
                translation: Vec3::new(4.0, 0.0, 0.0),
                rotation: Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
                scale: Vec3::splat(2.0),
            },
        ])
        .unwrap()
    }

    #[test]
    fn interpolates_and_holds_outside() {
        let m = spin();
        let p = m.matrix(0.5).transform_point3(Vec3::ZERO);
        assert!((p - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6);
        let x = m.matrix(0.5).transform_point3(Vec3::X);
        // Scale 1.5, rotated 45° about y: a rotation keeps the length.
        assert!((x - p).length() - 1.5 < 1e-5);
        assert_eq!(m.matrix(-3.0), m.matrix(0.0));
        assert_eq!(m.matrix(7.0), m.matrix(1.0));
    }

    #[test]
    fn inverse_matrix_inverts() {
        let m = spin();
        for t in [0.0, 0.3, 0.77, 1.0] {
            let id = m.matrix(t) * m.inverse_matrix(t);
            assert!(id.abs_diff_eq(Mat4::IDENTITY, 1e-5), "{t}: {id}");
        }
    }

    #[test]
    fn times_must_increase() {
        assert!(Motion::new(vec![]).is_none());
        assert!(Motion::new(vec![Keyframe::identity(1.0), Keyframe::identity(1.0)]).is_none());
    }

    #[test]
    fn swept_bounds_hold_every_pose() {
        let m = spin();
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let parent = Mat4::from_translation(Vec3::Y);
        let sweep = m.swept_bounds(&b, &parent);
        for i in 0..=1000 {
            let t = i as f32 / 1000.0;
            let bt = b.transformed(&(parent * m.matrix(t)));
            assert!(
                sweep.min.cmple(bt.min).all() && sweep.max.cmpge(bt.max).all(),
                "{t}"
            );
        }
        // Not absurdly loose: within a unit of the exact sweep.
        assert!(sweep.max.x < 4.0 + 2.0 * 2f32.sqrt() + 1.0);
    }
}
