//! Choosing an aggregate by name: [`AccelKind`] and its text form.

use std::fmt;
use std::str::FromStr;

/// How a BVH node's primitives are divided between its two children.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Split {
    /// At the middle of the centroids' extent on its longest axis (cheap,
    /// falls back to the median when everything lands on one side).
    Midpoint,
    /// Equal counts on either side along the longest centroid axis.
    Median,
    /// Binned surface-area heuristic, compared against making a leaf.
    #[default]
    Sah,
}

/// Which aggregate to build.
///
/// The default is `Bvh8`, the fast 8-wide BVH; the others are kept for
/// teaching and comparison.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum AccelKind {
    /// Test every primitive.
    None,
    /// A uniform grid walked with 3DDDA.
    Grid {
        /// Cells per axis; `None` picks about `3·N^(1/3)` cells along the
        /// longest axis and scales the others by the box's aspect.
        res: Option<[u32; 3]>,
    },
    /// An adaptive grid: crowded cells are halved (into up to eight) again.
    Octree,
    /// A binary bounding-volume hierarchy.
    Bvh(Split),
    /// The octree with the other storage policy: a primitive that straddles
    /// a split plane stays at the inner node and is tested whenever a ray
    /// enters that node (`octree-inner`).
    OctreeInner,
    /// A coarse uniform grid whose crowded cells hold finer grids
    /// (`nested-grid[:THRESHOLD[:DEPTH]]`).
    NestedGrid {
        /// A cell holding more than this many primitives gets a finer grid.
        threshold: u32,
        /// Most levels of finer grids below the coarse one.
        depth: u32,
    },
    /// A BVH whose inner nodes are the scene's own groups and transforms
    /// (`bvh-hierarchy`); a mesh's triangles are split by the median.
    BvhHierarchy,
    /// The fast 8-wide BVH (binned SAH, 4-triangle leaf blocks).
    #[default]
    Bvh8,
}

impl AccelKind {
    /// `nested-grid` with its default parameters.
    pub const NESTED_GRID: AccelKind = AccelKind::NestedGrid {
        threshold: 16,
        depth: 2,
    };
}

impl AccelKind {
    /// Every accepted name, for help texts (`grid:NxNxN` and `grid:N` are
    /// accepted too and fix the resolution).
    pub const NAMES: [&'static str; 11] = [
        "none",
        "grid",
        "octree",
        "bvh",
        "bvh-sah",
        "bvh-median",
        "bvh-midpoint",
        "octree-inner",
        "nested-grid",
        "bvh-hierarchy",
        "bvh8",
    ];
}

/// A name [`AccelKind::from_str`] does not know.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown accelerator `{0}` (expected none, grid, grid:NxNxN, octree, bvh, bvh-sah, bvh-median, bvh-midpoint, bvh8 (alias bvh4), octree-inner, nested-grid, nested-grid:THRESHOLD[:DEPTH] or bvh-hierarchy)"
)]
pub struct ParseAccelError(pub String);

impl FromStr for AccelKind {
    type Err = ParseAccelError;

    /// `none | grid | octree | bvh | bvh-sah | bvh-median | bvh-midpoint | bvh8`
    /// (case-insensitive; `bvh` is `bvh-sah`; `bvh4`, the 8-wide BVH's old
    /// name, is `bvh8`), and `grid:NxNxN` or `grid:N`
    /// for a fixed grid resolution; `octree-inner`, `bvh-hierarchy`, and
    /// `nested-grid[:THRESHOLD[:DEPTH]]` (defaults 16 and 2).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = || ParseAccelError(s.to_string());
        let name = s.trim().to_ascii_lowercase();
        Ok(match name.as_str() {
            "none" => AccelKind::None,
            "grid" => AccelKind::Grid { res: None },
            "octree" => AccelKind::Octree,
            "bvh" | "bvh-sah" => AccelKind::Bvh(Split::Sah),
            "bvh-median" => AccelKind::Bvh(Split::Median),
            "bvh-midpoint" => AccelKind::Bvh(Split::Midpoint),
            "octree-inner" | "octree:inner" => AccelKind::OctreeInner,
            "bvh-hierarchy" => AccelKind::BvhHierarchy,
            "nested-grid" => AccelKind::NESTED_GRID,
            other if other.starts_with("nested-grid:") => parse_nested(other).ok_or_else(err)?,
            "bvh8" | "bvh4" => AccelKind::Bvh8,
            other => {
                let res = other.strip_prefix("grid:").ok_or_else(err)?;
                let n: Vec<u32> = res
                    .split('x')
                    .map(|v| v.trim().parse().ok().filter(|&n| n > 0))
                    .collect::<Option<_>>()
                    .ok_or_else(err)?;
                let res = match n[..] {
                    [a] => [a, a, a],
                    [a, b, c] => [a, b, c],
                    _ => return Err(err()),
                };
                AccelKind::Grid { res: Some(res) }
            }
        })
    }
}

/// Most levels of finer grids `nested-grid:T:D` accepts.
const MAX_NESTING: u32 = 8;

/// `nested-grid:T` or `nested-grid:T:D` (T ≥ 1, 1 ≤ D ≤ [`MAX_NESTING`]).
fn parse_nested(s: &str) -> Option<AccelKind> {
    let nums: Vec<u32> = s
        .strip_prefix("nested-grid:")?
        .split(':')
        .map(|v| v.trim().parse().ok())
        .collect::<Option<_>>()?;
    let (threshold, depth) = match nums[..] {
        [t] => (t, 2),
        [t, d] => (t, d),
        _ => return None,
    };
    (threshold > 0 && (1..=MAX_NESTING).contains(&depth))
        .then_some(AccelKind::NestedGrid { threshold, depth })
}

impl fmt::Display for AccelKind {
    /// The canonical name, which [`AccelKind::from_str`] reads back.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AccelKind::None => f.write_str("none"),
            AccelKind::Grid { res: None } => f.write_str("grid"),
            AccelKind::Grid {
                res: Some([x, y, z]),
            } => write!(f, "grid:{x}x{y}x{z}"),
            AccelKind::Octree => f.write_str("octree"),
            AccelKind::Bvh(s) => write!(f, "bvh-{s}"),
            AccelKind::OctreeInner => f.write_str("octree-inner"),
            AccelKind::BvhHierarchy => f.write_str("bvh-hierarchy"),
            k if *k == AccelKind::NESTED_GRID => f.write_str("nested-grid"),
            AccelKind::NestedGrid { threshold, depth } => {
                write!(f, "nested-grid:{threshold}:{depth}")
            }
            AccelKind::Bvh8 => f.write_str("bvh8"),
        }
    }
}

impl fmt::Display for Split {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Split::Midpoint => "midpoint",
            Split::Median => "median",
            Split::Sah => "sah",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_and_round_trip() {
        assert_eq!("bvh".parse(), Ok(AccelKind::Bvh(Split::Sah)));
        assert_eq!("BVH-Median".parse(), Ok(AccelKind::Bvh(Split::Median)));
        assert_eq!(
            "grid:4x5x6".parse(),
            Ok(AccelKind::Grid {
                res: Some([4, 5, 6])
            })
        );
        assert_eq!(
            "grid:7".parse(),
            Ok(AccelKind::Grid {
                res: Some([7, 7, 7])
            })
        );
        for name in AccelKind::NAMES {
            let k: AccelKind = name.parse().unwrap();
            assert_eq!(k.to_string().parse::<AccelKind>(), Ok(k));
        }
        let fixed = AccelKind::Grid {
            res: Some([1, 2, 3]),
        };
        assert_eq!(fixed.to_string().parse::<AccelKind>(), Ok(fixed));
        // Default parameters print as the short name the user typed.
        for (kind, name) in [
            (AccelKind::NESTED_GRID, "nested-grid"),
            (AccelKind::OctreeInner, "octree-inner"),
            (AccelKind::BvhHierarchy, "bvh-hierarchy"),
            (AccelKind::Bvh(Split::Midpoint), "bvh-midpoint"),
            (AccelKind::Bvh8, "bvh8"),
            (fixed, "grid:1x2x3"),
        ] {
            assert_eq!(kind.to_string(), name);
        }
    }

    #[test]
    fn new_names_parse() {
        assert_eq!("octree:inner".parse(), Ok(AccelKind::OctreeInner));
        assert_eq!("nested-grid".parse(), Ok(AccelKind::NESTED_GRID));
        // The 8-wide BVH's old name stays accepted.
        assert_eq!("bvh4".parse(), Ok(AccelKind::Bvh8));
        assert_eq!("BVH4".parse(), Ok(AccelKind::Bvh8));
        assert_eq!(
            "nested-grid:4".parse(),
            Ok(AccelKind::NestedGrid {
                threshold: 4,
                depth: 2
            })
        );
        let k = AccelKind::NestedGrid {
            threshold: 30,
            depth: 3,
        };
        assert_eq!("nested-grid:30:3".parse(), Ok(k));
        assert_eq!(k.to_string().parse::<AccelKind>(), Ok(k));
    }

    #[test]
    fn bad_names_are_errors() {
        for bad in [
            "kd",
            "grid:",
            "grid:0",
            "grid:1x2",
            "grid:axbxc",
            "",
            "nested-grid:",
            "nested-grid:0",
            "nested-grid:4:0",
            "nested-grid:4:9",
            "nested-grid:4:2:1",
            "nested-grid:x",
        ] {
            assert!(bad.parse::<AccelKind>().is_err(), "{bad}");
        }
    }

    #[test]
    fn default_is_the_fast_bvh() {
        assert_eq!(AccelKind::default(), AccelKind::Bvh8);
    }
}
