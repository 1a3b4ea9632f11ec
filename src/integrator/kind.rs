//! Which integrator renders an image: the one place the set is named.
//!
//! A new integrator is a new module beside this one, an arm here (with its
//! command-line name) and an arm of the job's dispatch
//! (`crate::job::pipeline`); both command lines take the names from
//! [`IntegratorKind::NAMES`].

use super::PathSettings;
use std::fmt;
use std::str::FromStr;

/// The integrators a job can render with.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum IntegratorKind {
    /// The Whitted ray tree ([`super::Whitted`]; Cook's distribution ray
    /// tracer when the scene has sampled effects): the shaded image.
    #[default]
    Whitted,
    /// Ambient occlusion alone ([`super::AmbientOcclusion`]): the grey image.
    Ao,
    /// Path tracing with light sampling and multiple importance sampling
    /// ([`super::PathTracer`]): the physically read image. Its texture space
    /// is the job's shading's.
    Path(PathSettings),
}

impl IntegratorKind {
    /// Every kind with its default settings, in the order the help lists
    /// them.
    pub fn all() -> [IntegratorKind; 3] {
        [
            IntegratorKind::Whitted,
            IntegratorKind::Ao,
            IntegratorKind::Path(PathSettings::default()),
        ]
    }

    /// The command-line names, in the order of [`IntegratorKind::all`].
    pub const NAMES: [&'static str; 3] = ["whitted", "ao", "path"];

    /// The bounces `glint`'s commands use when none are named: 5 for the
    /// ray tree (the course's `raytracer` keeps its 0), 64 scattering events
    /// for the path tracer.
    pub fn default_bounces(self) -> u32 {
        match self {
            IntegratorKind::Path(_) => PathSettings::default().max_bounces,
            _ => 5,
        }
    }

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Whitted => "whitted",
            IntegratorKind::Ao => "ao",
            IntegratorKind::Path(_) => "path",
        }
    }

    /// One line saying what the integrator computes, for the help.
    pub fn about(self) -> &'static str {
        match self {
            IntegratorKind::Whitted => "the shaded image (Whitted's ray tree)",
            IntegratorKind::Ao => "the grey ambient-occlusion image",
            IntegratorKind::Path(_) => {
                "path tracing with light sampling and MIS (see docs/path-tracing.md)"
            }
        }
    }
}

impl fmt::Display for IntegratorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for IntegratorKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::all()
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown integrator {}: expected {}",
                    crate::limits::shorten(s),
                    Self::NAMES.join(", ")
                )
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_match_the_list() {
        for (k, name) in IntegratorKind::all().into_iter().zip(IntegratorKind::NAMES) {
            assert_eq!(k.name(), name);
            assert_eq!(name.parse::<IntegratorKind>(), Ok(k));
            assert_eq!(k.to_string(), name);
        }
        let e = "paths".parse::<IntegratorKind>().unwrap_err();
        assert!(e.contains("whitted, ao, path"), "{e}");
        assert_eq!(IntegratorKind::Whitted.default_bounces(), 5);
        assert_eq!(IntegratorKind::all()[2].default_bounces(), 64);
    }
}
