//! Reconstruction filters: how much a sample counts for a pixel, by its
//! offset from the pixel centre (in pixels).
//!
//! The course's semantics (`../shared/scenes/6837/NOTES.md`, A7): box `r` is
//! 1 inside the square `|x|, |y| ≤ r`; tent `r` falls linearly from 1 at the
//! centre to 0 at distance `r`; gaussian `σ` is `exp(−d²/2σ²)`, cut at
//! `d = 2σ` (a round kernel, what `glint render --filter gaussian:σ` uses).
//! A filter reaches the pixels up to [`Filter::support`] away,
//! `⌈radius − 0.5⌉` (0 = the pixel itself, 1 = 3×3, …). Weights are
//! unnormalised; the film divides by their sum, so the filter as used always
//! integrates to 1.
//!
//! [`Filter::GaussianSquare`] is the course implementations' gaussian, which
//! `raytracer -gaussian_filter σ` uses: the same `exp(−d²/2σ²)` limited only
//! by the pixel support `⌈2σ − 0.5⌉`, so its kernel is the whole support
//! square. Both independent reference render sets agree on it bit for bit
//! (`filter7_01f`, `filter7_01i`; `tests/sampling_reference.rs`).
//!
//! Arithmetic is in `f32` like the rest of the renderer (and the course's C++
//! code): `2 + 16/20 − 4.5` is then 1.6999998, inside a box of radius 1.7, as
//! the reference renders show.

use std::fmt;
use std::str::FromStr;

/// A reconstruction filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Filter {
    /// 1 inside the square of half-width `r`.
    Box(f32),
    /// `max(0, 1 − d/r)`.
    Tent(f32),
    /// `exp(−d²/2σ²)` for `d ≤ 2σ`, else 0.
    Gaussian(f32),
    /// `exp(−d²/2σ²)` inside the square of half-width `⌈2σ − 0.5⌉ + 0.5`
    /// (the pixels of the support), else 0: the course's kernel.
    GaussianSquare(f32),
}

impl Default for Filter {
    /// Box of radius 0.5: each sample counts for its own pixel only.
    fn default() -> Self {
        Filter::Box(0.5)
    }
}

impl Filter {
    /// Distance from the pixel centre beyond which the weight is 0.
    pub fn radius(&self) -> f32 {
        match *self {
            Filter::Box(r) | Filter::Tent(r) => r,
            Filter::Gaussian(s) => 2.0 * s,
            // The half-width of the support square.
            Filter::GaussianSquare(_) => self.support() as f32 + 0.5,
        }
    }

    /// How many pixels away a sample can count: `⌈radius − 0.5⌉`, at least 0
    /// (for the square gaussian `⌈2σ − 0.5⌉`, as for the round one).
    pub fn support(&self) -> u32 {
        let r = match *self {
            Filter::GaussianSquare(s) => 2.0 * s,
            _ => self.radius(),
        };
        (r - 0.5).ceil().max(0.0) as u32
    }

    /// Weight of a sample at offset `(dx, dy)` from the pixel centre.
    #[inline]
    pub fn weight(&self, dx: f32, dy: f32) -> f32 {
        match *self {
            Filter::Box(r) => {
                if dx.abs() <= r && dy.abs() <= r {
                    1.0
                } else {
                    0.0
                }
            }
            Filter::Tent(r) => (1.0 - (dx * dx + dy * dy).sqrt() / r).max(0.0),
            Filter::Gaussian(s) => {
                let d2 = dx * dx + dy * dy;
                if d2 <= 4.0 * s * s {
                    (-d2 / (2.0 * s * s)).exp()
                } else {
                    0.0
                }
            }
            Filter::GaussianSquare(s) => {
                let h = self.radius();
                if dx.abs() <= h && dy.abs() <= h {
                    (-(dx * dx + dy * dy) / (2.0 * s * s)).exp()
                } else {
                    0.0
                }
            }
        }
    }

    /// The integral of [`Filter::weight`] over the plane (what the film's
    /// normalisation divides by, on average).
    pub fn integral(&self) -> f64 {
        match *self {
            Filter::Box(r) => 4.0 * (r as f64).powi(2),
            // A cone of height 1 and base radius r.
            Filter::Tent(r) => std::f64::consts::PI * (r as f64).powi(2) / 3.0,
            // 2πσ² · (1 − e^{−2}): the Gaussian's mass inside d = 2σ.
            Filter::Gaussian(s) => {
                2.0 * std::f64::consts::PI * (s as f64).powi(2) * (1.0 - (-2.0f64).exp())
            }
            // Separable: (σ√(2π) · erf(h / σ√2))² over the square of half-width h.
            Filter::GaussianSquare(s) => {
                let s = s as f64;
                let h = self.radius() as f64;
                let side = s * (2.0 * std::f64::consts::PI).sqrt() * erf(h / (s * 2f64.sqrt()));
                side * side
            }
        }
    }

    /// Checks the parameter: finite and positive.
    pub fn validate(&self) -> Result<(), String> {
        let (name, v) = match *self {
            Filter::Box(r) => ("box radius", r),
            Filter::Tent(r) => ("tent radius", r),
            Filter::Gaussian(s) | Filter::GaussianSquare(s) => ("gaussian sigma", s),
        };
        if v.is_finite() && v > 0.0 && v <= 64.0 {
            Ok(())
        } else {
            Err(format!(
                "{name} {v}: must be greater than 0 and at most 64 pixels"
            ))
        }
    }
}

impl FromStr for Filter {
    type Err = String;
    /// `box:R`, `tent:R`, `gaussian:SIGMA` or `gaussian-square:SIGMA`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (name, value) = s
            .split_once(':')
            .ok_or_else(|| format!("filter '{s}': expected box:R, tent:R or gaussian:SIGMA"))?;
        let v: f32 = value
            .parse()
            .map_err(|_| format!("filter '{s}': '{value}' is not a number"))?;
        let f = match name {
            "box" => Filter::Box(v),
            "tent" => Filter::Tent(v),
            "gaussian" => Filter::Gaussian(v),
            "gaussian-square" => Filter::GaussianSquare(v),
            _ => {
                return Err(format!(
                    "filter '{s}': expected box, tent, gaussian or gaussian-square"
                ))
            }
        };
        f.validate()?;
        Ok(f)
    }
}

impl fmt::Display for Filter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Filter::Box(r) => write!(f, "box:{r}"),
            Filter::Tent(r) => write!(f, "tent:{r}"),
            Filter::Gaussian(s) => write!(f, "gaussian:{s}"),
            Filter::GaussianSquare(s) => write!(f, "gaussian-square:{s}"),
        }
    }
}

/// The error function, to about 1e-7 (Abramowitz and Stegun 7.1.26); only
/// [`Filter::integral`] of the square gaussian needs it.
fn erf(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    (1.0 - poly * (-x * x).exp()).copysign(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILTERS: [Filter; 12] = [
        Filter::Box(0.5),
        Filter::Box(1.7),
        Filter::Box(2.3),
        Filter::Tent(0.5),
        Filter::Tent(1.5),
        Filter::Tent(2.3),
        Filter::Gaussian(0.4),
        Filter::Gaussian(1.0),
        Filter::Gaussian(2.3),
        Filter::GaussianSquare(0.4),
        Filter::GaussianSquare(1.7),
        Filter::GaussianSquare(2.3),
    ];

    /// Midpoint-rule integral of the weight over `[-ext, ext]²`.
    fn integrate(f: &Filter, ext: f32, n: u32) -> f64 {
        let h = 2.0 * ext as f64 / n as f64;
        let mut sum = 0.0;
        for a in 0..n {
            for b in 0..n {
                let x = -ext as f64 + (a as f64 + 0.5) * h;
                let y = -ext as f64 + (b as f64 + 0.5) * h;
                sum += f.weight(x as f32, y as f32) as f64;
            }
        }
        sum * h * h
    }

    #[test]
    fn normalised_filters_integrate_to_one_over_their_support() {
        for f in FILTERS {
            // The support square (in pixels) holds the whole filter.
            let ext = f.support() as f32 + 0.5;
            assert!(f.radius() <= ext + 1e-6, "{f}");
            let i = integrate(&f, ext, 1200) / f.integral();
            assert!((i - 1.0).abs() < 2e-3, "{f}: {i}");
        }
    }

    #[test]
    fn weight_is_zero_outside_the_radius() {
        for f in FILTERS {
            let r = f.radius();
            for k in 0..360 {
                let a = (k as f32).to_radians();
                // Outside the radius along every direction (the box's square
                // corners reach √2·r).
                let d = r * if matches!(f, Filter::Box(_) | Filter::GaussianSquare(_)) {
                    1.42
                } else {
                    1.0001
                };
                assert_eq!(f.weight(d * a.cos(), d * a.sin()), 0.0, "{f} at {k}°");
            }
            // And beyond the support square entirely.
            let s = f.support() as f32 + 0.5;
            assert_eq!(f.weight(s + 0.01, 0.0), 0.0, "{f}");
            assert!(f.weight(0.0, 0.0) > 0.99);
        }
    }

    #[test]
    fn course_support_radii() {
        assert_eq!(Filter::Box(0.5).support(), 0);
        assert_eq!(Filter::Box(1.7).support(), 2);
        assert_eq!(Filter::Tent(1.5).support(), 1);
        assert_eq!(Filter::Gaussian(0.4).support(), 1);
        assert_eq!(Filter::Gaussian(2.3).support(), 5);
        assert_eq!(Filter::Gaussian(0.2).support(), 0);
        for s in [0.2, 0.4, 1.7, 2.3] {
            let (round, square) = (Filter::Gaussian(s), Filter::GaussianSquare(s));
            assert_eq!(round.support(), square.support(), "{s}");
        }
    }

    /// The course's gaussian is the round one wherever the round one is not
    /// cut, and keeps the corners of the support square it cuts away.
    #[test]
    fn square_gaussian_keeps_the_corners_of_its_support() {
        let (round, square) = (Filter::Gaussian(1.7), Filter::GaussianSquare(1.7));
        assert_eq!(square.support(), 3);
        for (dx, dy) in [(0.0, 0.0), (1.0, -2.0), (3.3, 0.5), (-2.4, 2.3)] {
            assert_eq!(round.weight(dx, dy), square.weight(dx, dy), "({dx}, {dy})");
        }
        // d = 4.8 > 2σ = 3.4, still inside the 3.5-pixel square.
        assert_eq!(round.weight(3.4, -3.4), 0.0);
        let corner = square.weight(3.4, -3.4);
        assert!((corner - (-(2.0 * 3.4f32 * 3.4) / (2.0 * 1.7 * 1.7)).exp()).abs() < 1e-7);
        assert!(corner > 0.0);
        assert_eq!(square.weight(3.51, 0.0), 0.0);
        assert_eq!(square.weight(0.0, -3.51), 0.0);
    }

    #[test]
    fn erf_matches_tabulated_values() {
        // erf(0.5), erf(1), erf(2) to 10 digits.
        for (x, e) in [
            (0.5, 0.520_499_877_8),
            (1.0, 0.842_700_792_9),
            (2.0, 0.995_322_265_0),
        ] {
            assert!((erf(x) - e).abs() < 3e-7, "erf({x}) = {}", erf(x));
            assert!((erf(-x) + e).abs() < 3e-7);
        }
        assert!(erf(0.0).abs() < 1e-7);
    }

    #[test]
    fn parse_and_print() {
        assert_eq!("tent:1.5".parse::<Filter>().unwrap(), Filter::Tent(1.5));
        assert_eq!(
            "gaussian:0.4".parse::<Filter>().unwrap().to_string(),
            "gaussian:0.4"
        );
        assert!("box".parse::<Filter>().is_err());
        assert!("box:-1".parse::<Filter>().is_err());
        assert_eq!("box:0.5".parse::<Filter>().unwrap(), Filter::Box(0.5));
        assert_eq!("box:64".parse::<Filter>().unwrap(), Filter::Box(64.0));
        // Greater than 0, at most 64.
        for bad in [
            "box:0",
            "tent:0",
            "gaussian:0",
            "box:64.01",
            "tent:inf",
            "box:nan",
        ] {
            assert!(bad.parse::<Filter>().is_err(), "{bad}");
        }
        assert!("mitchell:1".parse::<Filter>().is_err());
        let sq = "gaussian-square:1.7".parse::<Filter>().unwrap();
        assert_eq!(sq, Filter::GaussianSquare(1.7));
        assert_eq!(sq.to_string(), "gaussian-square:1.7");
    }
}
