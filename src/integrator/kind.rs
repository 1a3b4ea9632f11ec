//! Which integrator renders an image: the one place the set is named.
//!
//! A new integrator is a new module beside this one, an arm here (with its
//! command-line name) and an arm of the job's dispatch
//! (`crate::job::pipeline`); both command lines take the names from
//! [`IntegratorKind::NAMES`].

use std::fmt;
use std::str::FromStr;

/// The integrators a job can render with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum IntegratorKind {
    /// The Whitted ray tree ([`super::Whitted`]; Cook's distribution ray
    /// tracer when the scene has sampled effects): the shaded image.
    #[default]
    Whitted,
    /// Ambient occlusion alone ([`super::AmbientOcclusion`]): the grey image.
    Ao,
}

impl IntegratorKind {
    /// Every kind, in the order the help lists them.
    pub const ALL: [IntegratorKind; 2] = [IntegratorKind::Whitted, IntegratorKind::Ao];

    /// The command-line names, in the order of [`IntegratorKind::ALL`].
    pub const NAMES: [&'static str; 2] = ["whitted", "ao"];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Whitted => "whitted",
            IntegratorKind::Ao => "ao",
        }
    }

    /// One line saying what the integrator computes, for the help.
    pub fn about(self) -> &'static str {
        match self {
            IntegratorKind::Whitted => "the shaded image (Whitted's ray tree)",
            IntegratorKind::Ao => "the grey ambient-occlusion image",
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
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown integrator {}: expected {}",
                    crate::limits::shorten(s),
                    Self::NAMES.join(" or ")
                )
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_match_the_list() {
        for (k, name) in IntegratorKind::ALL.into_iter().zip(IntegratorKind::NAMES) {
            assert_eq!(k.name(), name);
            assert_eq!(name.parse::<IntegratorKind>(), Ok(k));
            assert_eq!(k.to_string(), name);
        }
        let e = "path".parse::<IntegratorKind>().unwrap_err();
        assert!(e.contains("whitted or ao"), "{e}");
    }
}
