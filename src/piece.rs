//! Pieces of a frame, for batch schedulers: a Slurm job array, a Kubernetes
//! Indexed Job or GNU parallel hands each task an index; `--tile I/N` makes
//! task `I` render band `I` of `N` of the frame (`--crop` any rectangle),
//! and `glint merge` assembles the pieces into exactly the image one
//! machine would have made.
//!
//! Why the merge is exact: a piece renders every tile whose film reaches
//! into it ([`crate::render::render_region`]), each tile a pure function of
//! the settings and the tile (per-pixel sample streams, no shared random
//! state), and reconstructs its pixels from those films in the same order as
//! a whole render. A piece is written as an OpenEXR file whose data window is
//! the piece inside the display window of the whole frame (the standard way
//! to store a crop), with the frame size, the piece, a hash of everything
//! that decides the image, and the piece's statistics in its header.

use crate::math::Vec3;
use crate::render::{Frame, Rect};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Header attribute names (custom EXR attributes, text).
pub const ATTR_HASH: &str = "glint.settings_hash";
/// The piece's label: `tile I/N` or `crop X0 Y0 X1 Y1`.
pub const ATTR_PIECE: &str = "glint.piece";
/// The piece's ray and traversal counters, as JSON.
pub const ATTR_STATS: &str = "glint.stats";

/// Which part of the frame a task renders.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PieceSpec {
    /// The pixels, in frame coordinates (row 0 at the top).
    pub rect: Rect,
    /// How it was asked for (`tile 3/7`, `crop 0 0 64 32`), for messages.
    pub label: String,
}

/// `"I/N"` as `(I, N)`: `I` counts from 0 and is below `N`.
pub fn parse_index(text: &str) -> Result<(u32, u32), String> {
    let (i, n) = text
        .split_once('/')
        .ok_or_else(|| format!("'{text}': expected I/N, e.g. 3/8"))?;
    let num = |s: &str| {
        s.trim()
            .parse::<u32>()
            .map_err(|_| format!("'{text}': '{s}' is not a whole number"))
    };
    let (i, n) = (num(i)?, num(n)?);
    if n == 0 || i >= n {
        return Err(format!(
            "'{text}': the piece index counts from 0 and must be below the number of pieces"
        ));
    }
    Ok((i, n))
}

/// `"VAR/N"`: the index from environment variable `VAR` (e.g.
/// `SLURM_ARRAY_TASK_ID`, `JOB_COMPLETION_INDEX`), looked up by `env`.
pub fn index_from_env(
    spec: &str,
    env: impl Fn(&str) -> Option<String>,
) -> Result<(u32, u32), String> {
    let (var, n) = spec
        .split_once('/')
        .ok_or_else(|| format!("'{spec}': expected VARIABLE/N, e.g. SLURM_ARRAY_TASK_ID/8"))?;
    let value = env(var).ok_or_else(|| format!("'{spec}': the variable {var} is not set"))?;
    parse_index(&format!("{}/{n}", value.trim())).map_err(|e| format!("{var}={value}: {e}"))
}

/// Band `i` of `n` of a `w`×`h` frame rendered in tiles of `tile` pixels:
/// whole rows of tiles when there are at least `n` of them (a piece then
/// renders no tile another piece renders, except for the filter's margin),
/// else whole pixel rows; as even as integers allow.
pub fn band(i: u32, n: u32, (w, h): (u32, u32), tile: u32) -> Result<PieceSpec, String> {
    if n > h {
        return Err(format!(
            "{n} pieces of a frame {h} rows high: at most one piece per row"
        ));
    }
    let tile = tile.max(1);
    let tile_rows = h.div_ceil(tile);
    let row = |k: u32| {
        if n <= tile_rows {
            ((u64::from(k) * u64::from(tile_rows) / u64::from(n)) as u32 * tile).min(h)
        } else {
            (u64::from(k) * u64::from(h) / u64::from(n)) as u32
        }
    };
    Ok(PieceSpec {
        rect: Rect {
            x0: 0,
            row0: row(i),
            x1: w,
            row1: row(i + 1),
        },
        label: format!("tile {i}/{n}"),
    })
}

/// The rectangle `x0 y0 x1 y1` (x right, y down from the top, half-open),
/// checked against the frame.
pub fn crop([x0, y0, x1, y1]: [u32; 4], (w, h): (u32, u32)) -> Result<PieceSpec, String> {
    if x0 >= x1 || y0 >= y1 || x1 > w || y1 > h {
        return Err(format!(
            "--crop {x0} {y0} {x1} {y1}: expected 0 <= x0 < x1 <= {w} and 0 <= y0 < y1 <= {h} (pixels, half-open)"
        ));
    }
    Ok(PieceSpec {
        rect: Rect {
            x0,
            row0: y0,
            x1,
            row1: y1,
        },
        label: format!("crop {x0} {y0} {x1} {y1}"),
    })
}

/// A hash of everything that decides the image: the scene (its full
/// description, meshes included, streamed through `Debug`), then `parts`
/// (the render settings, the integrator, the image size...). FNV-1a over
/// the text: the same on every machine, since `Debug` prints floats exactly.
pub fn settings_hash(scene: &crate::scene::Scene, parts: &str) -> String {
    struct Fnv(u64);
    impl std::fmt::Write for Fnv {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            for b in s.bytes() {
                self.0 ^= u64::from(b);
                self.0 = self.0.wrapping_mul(0x100_0000_01b3);
            }
            Ok(())
        }
    }
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    let _ = write!(h, "{scene:?}\u{0}{parts}");
    format!("{:016x}", h.0)
}

/// Writes the piece `spec` of `frame` as an EXR whose data window is the
/// piece and whose display window is the whole frame, with the hash, the
/// label and `stats` (JSON) in its header; atomically, like every image.
pub fn write(
    path: &Path,
    frame: &Frame,
    spec: &PieceSpec,
    hash: &str,
    stats: &serde_json::Value,
) -> Result<(), crate::output::OutputError> {
    let r = spec.rect;
    let mut pixels = Vec::with_capacity(r.area());
    for row in r.row0..r.row1 {
        let start = (row * frame.width + r.x0) as usize;
        pixels.extend_from_slice(&frame.color[start..start + r.width() as usize]);
    }
    crate::output::write_exr_window(
        path,
        (frame.width, frame.height),
        (r.x0, r.row0, r.width(), r.height()),
        &pixels,
        &[
            (ATTR_HASH, hash.to_string()),
            (ATTR_PIECE, spec.label.clone()),
            (ATTR_STATS, stats.to_string()),
        ],
    )
}

/// A piece read back from its file.
#[derive(Clone, Debug)]
pub struct PieceFile {
    /// The file.
    pub path: PathBuf,
    /// The whole frame's size.
    pub frame: (u32, u32),
    /// Where the piece sits in it.
    pub rect: Rect,
    /// The settings hash.
    pub hash: String,
    /// The label (`tile 3/7`).
    pub label: String,
    /// The piece's statistics.
    pub stats: serde_json::Value,
    /// Its pixels, row-major, top row first.
    pub pixels: Vec<Vec3>,
}

/// Reads a piece written by [`write()`].
pub fn read(path: &Path) -> Result<PieceFile, String> {
    let w = crate::output::read_exr_window(path)?;
    let attr = |name: &str| {
        w.attributes
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.clone())
            .ok_or_else(|| {
                format!(
                    "{}: not a glint piece (no {name} in its header)",
                    path.display()
                )
            })
    };
    let (x0, row0, pw, ph) = w.window;
    Ok(PieceFile {
        path: path.to_path_buf(),
        frame: w.display,
        rect: Rect {
            x0,
            row0,
            x1: x0 + pw,
            row1: row0 + ph,
        },
        hash: attr(ATTR_HASH)?,
        label: attr(ATTR_PIECE)?,
        stats: serde_json::from_str(&attr(ATTR_STATS)?).unwrap_or(serde_json::Value::Null),
        pixels: w.pixels,
    })
}

/// A merged frame: its size, its pixels (row-major, top row first) and the
/// pieces' statistics added up.
pub type Merged = ((u32, u32), Vec<Vec3>, serde_json::Value);

/// Assembles `pieces` into the whole frame: they must come from the same
/// render (same hash and frame size) and cover every pixel exactly once. On
/// success returns the frame size, its pixels and the summed statistics.
pub fn merge(pieces: &[PieceFile]) -> Result<Merged, String> {
    let first = pieces.first().ok_or("no pieces to merge")?;
    let name = |p: &PieceFile| format!("{} ({})", p.path.display(), p.label);
    let strangers: Vec<String> = pieces
        .iter()
        .filter(|p| p.hash != first.hash || p.frame != first.frame)
        .map(|p| {
            format!(
                "{}: settings {} frame {}x{}",
                name(p),
                p.hash,
                p.frame.0,
                p.frame.1
            )
        })
        .collect();
    if !strangers.is_empty() {
        return Err(format!(
            "pieces of different renders (the first, {}, has settings {} and frame {}x{}):\n  {}",
            name(first),
            first.hash,
            first.frame.0,
            first.frame.1,
            strangers.join("\n  ")
        ));
    }
    let (w, h) = first.frame;
    let mut owner: Vec<Option<usize>> = vec![None; w as usize * h as usize];
    let mut pixels = vec![Vec3::ZERO; owner.len()];
    let mut overlaps: Vec<(usize, usize)> = Vec::new();
    for (k, p) in pieces.iter().enumerate() {
        let r = p.rect;
        if r.x1 > w || r.row1 > h {
            return Err(format!("{}: lies outside the {w}x{h} frame", name(p)));
        }
        for row in r.row0..r.row1 {
            for x in r.x0..r.x1 {
                let i = row as usize * w as usize + x as usize;
                match owner[i] {
                    Some(o) if !overlaps.contains(&(o, k)) => overlaps.push((o, k)),
                    Some(_) => {}
                    None => {
                        owner[i] = Some(k);
                        pixels[i] = p.pixels[((row - r.row0) * r.width() + x - r.x0) as usize];
                    }
                }
            }
        }
    }
    if !overlaps.is_empty() {
        let list: Vec<String> = overlaps
            .iter()
            .map(|&(a, b)| format!("{} and {}", name(&pieces[a]), name(&pieces[b])))
            .collect();
        return Err(format!("pieces overlap (duplicated?): {}", list.join("; ")));
    }
    let missing = owner.iter().filter(|o| o.is_none()).count();
    if missing > 0 {
        let rows: Vec<u32> = (0..h)
            .filter(|&r| (0..w).any(|x| owner[(r * w + x) as usize].is_none()))
            .collect();
        let labels = first
            .label
            .strip_prefix("tile ")
            .and_then(|l| l.split_once('/'))
            .and_then(|(_, n)| n.parse::<u32>().ok())
            .map(|n| {
                let have: Vec<u32> = pieces
                    .iter()
                    .filter_map(|p| {
                        p.label
                            .strip_prefix("tile ")?
                            .split_once('/')?
                            .0
                            .parse()
                            .ok()
                    })
                    .collect();
                let absent: Vec<String> = (0..n)
                    .filter(|i| !have.contains(i))
                    .map(|i| format!("tile {i}/{n}"))
                    .collect();
                format!(" (missing pieces: {})", absent.join(", "))
            })
            .unwrap_or_default();
        return Err(format!(
            "{missing} pixels are in no piece, in rows {}..={}{labels}",
            rows.first().unwrap_or(&0),
            rows.last().unwrap_or(&0)
        ));
    }
    Ok(((w, h), pixels, sum_stats(pieces)))
}

/// The pieces' counters added up (every numeric field; times add up to the
/// total render time spent on all machines).
fn sum_stats(pieces: &[PieceFile]) -> serde_json::Value {
    let mut total = serde_json::Map::new();
    for p in pieces {
        if let Some(m) = p.stats.as_object() {
            for (k, v) in m {
                if let Some(x) = v.as_f64() {
                    let sum = total.get(k).and_then(|t| t.as_f64()).unwrap_or(0.0) + x;
                    let value = if v.is_u64() {
                        serde_json::Value::from(sum as u64)
                    } else {
                        serde_json::Value::from(sum)
                    };
                    total.insert(k.clone(), value);
                }
            }
        }
    }
    total.insert("pieces".into(), pieces.len().into());
    serde_json::Value::Object(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_cover_the_frame_once() {
        for (n, h) in [(1, 10), (4, 10), (7, 10), (10, 10), (3, 1000)] {
            let mut next = 0;
            for i in 0..n {
                let b = band(i, n, (5, h), 32).unwrap().rect;
                assert_eq!(b.row0, next);
                assert!(b.row1 > b.row0);
                next = b.row1;
            }
            assert_eq!(next, h);
        }
        assert!(band(0, 11, (5, 10), 32).is_err());
        // Along tile rows when there are enough of them.
        let rows: Vec<u32> = (0..3)
            .map(|i| band(i, 3, (5, 100), 32).unwrap().rect.row0)
            .collect();
        assert_eq!(rows, [0, 32, 64]);
    }

    #[test]
    fn indices_parse_and_come_from_the_environment() {
        assert_eq!(parse_index("3/8"), Ok((3, 8)));
        for bad in ["8/8", "1/0", "x/3", "3", "-1/4"] {
            assert!(parse_index(bad).is_err(), "{bad}");
        }
        let env = |v: &str| (v == "SLURM_ARRAY_TASK_ID").then(|| "5".to_string());
        assert_eq!(index_from_env("SLURM_ARRAY_TASK_ID/7", env), Ok((5, 7)));
        let e = index_from_env("JOB_COMPLETION_INDEX/7", env).unwrap_err();
        assert!(e.contains("JOB_COMPLETION_INDEX is not set"), "{e}");
        assert!(index_from_env("SLURM_ARRAY_TASK_ID/5", env).is_err());
    }

    #[test]
    fn crops_are_checked() {
        assert!(crop([0, 0, 4, 4], (4, 4)).is_ok());
        assert!(crop([2, 0, 2, 4], (4, 4)).is_err());
        assert!(crop([0, 0, 5, 4], (4, 4)).is_err());
    }
}
