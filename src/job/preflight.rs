//! Every check made before any work: the request's ranges, memory, each
//! output's format, folder and size limits, that no output is an input or
//! another output, and what a piece of a frame may be.

use super::outputs::Output;
use super::spec::FlagNames;
use super::{Job, JobError};
use crate::format::load_scene_files;
use crate::limits;
use crate::output::OutputError;
use crate::output::{check_image, check_not_input, check_path, check_writable, FileIdentity};
use crate::piece::PieceSpec;
use crate::scene::Scene;
use std::path::{Path, PathBuf};

impl Job {
    /// Every check that needs no scene, done before any work: the numeric
    /// settings' ranges ([`Job::validate`]), image size and memory, each
    /// output's format, folder and size limits, what a piece may be, and
    /// that no output is the scene file or another output. The meshes are
    /// checked once the scene has named them (still before anything is
    /// written).
    pub fn preflight(&self) -> Result<(), JobError> {
        self.validate(FlagNames::Plain)?;
        check_frame_memory(self.width, self.height, available_memory())?;
        for o in &self.outputs {
            if o.is_image() {
                check_path(o.path())?;
            }
            if o.is_frame_sized() {
                check_image(o.path(), self.width, self.height)?;
            }
        }
        self.check_views()?;
        for o in &self.outputs {
            if let Output::Stats(p) = o {
                check_writable(p)?;
            }
        }
        self.check_clashes(std::slice::from_ref(&self.input))?;
        if let Some(p) = &self.piece {
            self.check_piece(p)?;
        }
        Ok(())
    }

    /// A piece renders one image, an EXR: nothing else this job could write
    /// would be a piece of anything.
    fn check_piece(&self, p: &PieceSpec) -> Result<(), JobError> {
        let exr = self
            .colour()
            .is_some_and(|o| o.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")));
        let usage = |m: &str| Err(JobError::Usage(format!("{}{m}", p.label)));
        if !exr {
            return usage(
                ": a piece of a frame is written as OpenEXR: give an output ending in .exr",
            );
        }
        if self.image_paths().count() > 1 {
            return usage(": only the colour image can be rendered in pieces (no depth, normals, views or cost images)");
        }
        if self.sampling.adaptive.is_some() {
            return usage(": adaptive sampling shares corner rays between tiles, so it cannot be split into pieces");
        }
        if p.rect.x1 > self.width || p.rect.row1 > self.height {
            return usage(&format!(
                " lies outside the {}x{} frame",
                self.width, self.height
            ));
        }
        Ok(())
    }

    /// The zoomed views (`-render_samples`, `-render_filter`) are `zoom²`
    /// times the image: their size must fit memory and their format too.
    fn check_views(&self) -> Result<(), JobError> {
        for o in &self.outputs {
            let (path, zoom, border) = match o {
                Output::SamplesView { path, zoom } => (path, *zoom, 0),
                Output::FilterView { path, zoom } => (path, *zoom, 1),
                _ => continue,
            };
            let side = |n: u32| u64::from(n) * u64::from(zoom.max(1)) + border;
            let (w, h) = (side(self.width), side(self.height));
            let (Ok(w), Ok(h)) = (u32::try_from(w), u32::try_from(h)) else {
                return Err(JobError::Usage(format!(
                    "{}: a {w}x{h} view is too large; choose a smaller zoom",
                    path.display()
                )));
            };
            // The format's own limit first: it holds on any machine.
            check_image(path, w, h)?;
            check_frame_memory(w, h, available_memory())?;
        }
        Ok(())
    }

    /// Refuses the job if an output is one of `inputs` or another output,
    /// however either is spelled (links, `..`, hard links).
    pub fn check_clashes(&self, inputs: &[PathBuf]) -> Result<(), JobError> {
        let outputs: Vec<(String, PathBuf, FileIdentity)> = self
            .files()
            .into_iter()
            .map(|(what, p)| {
                let id = FileIdentity::of(&p);
                (what, p, id)
            })
            .collect();
        let refuse = |path: &Path, reason: String| {
            JobError::Output(OutputError::Refused {
                path: path.into(),
                reason,
            })
        };
        for input in inputs {
            let id = FileIdentity::of(input);
            if let Some((what, p, _)) = outputs.iter().find(|o| o.2.same(&id)) {
                return Err(refuse(
                    p,
                    format!(
                        "the {what} would overwrite the input file {}; choose another name",
                        input.display()
                    ),
                ));
            }
        }
        for (i, (what, p, id)) in outputs.iter().enumerate() {
            if let Some((other, _, _)) = outputs[..i].iter().find(|o| o.2.same(id)) {
                return Err(refuse(
                    p,
                    format!("the {other} and the {what} are the same file; choose two names"),
                ));
            }
        }
        Ok(())
    }
}

/// Loads `scene` for a command that writes the single file `output` (the
/// `glint raytree`, `traverse` and `structure` views), rendering at `size`
/// if `output` is an image: first checks that `output` can be written (and
/// an image of that size fits memory and the format) and is not the scene,
/// then, once the scene has named its meshes, that it is none of them.
/// Nothing is written.
pub fn load_scene_for(scene: &Path, output: &Path, size: (u32, u32)) -> Result<Scene, JobError> {
    if size.0 == 0 || size.1 == 0 {
        return Err(JobError::Usage(format!(
            "image size {}x{}: width and height must be at least 1",
            size.0, size.1
        )));
    }
    check_writable(output)?;
    if check_path(output).is_ok() {
        check_frame_memory(size.0, size.1, available_memory())?;
        check_image(output, size.0, size.1)?;
    }
    check_not_input(output, &[scene.to_path_buf()])?;
    let (loaded, files) = load_scene_files(scene)?;
    check_not_input(output, &files)?;
    Ok(loaded)
}

/// Bytes per pixel of a [`crate::render::Frame`] (colour `Vec3`, depth
/// `f32`, normal `Vec3`, sample count `u32`) plus the tile films' filter sums
/// (`Vec3` and `f32`) that exist until the merge.
pub const FRAME_BYTES_PER_PIXEL: u64 = 12 + 4 + 12 + 4 + 16 + 16;

/// Bytes this process can allocate now: see [`limits::available_memory`]
/// (`MemAvailable`, and the address-space limit if one is set).
pub fn available_memory() -> u64 {
    limits::available_memory()
}

/// Refuses, before anything is allocated, an image whose frame planes would
/// take more than three quarters of `available` bytes (the rest is left for
/// the scene, the output encoder and everything else running).
pub fn check_frame_memory(width: u32, height: u32, available: u64) -> Result<(), JobError> {
    let need = u128::from(width) * u128::from(height) * u128::from(FRAME_BYTES_PER_PIXEL);
    let limit = u128::from(available / 4 * 3);
    if need <= limit {
        return Ok(());
    }
    let gib = |b: u128| b as f64 / f64::from(1u32 << 30);
    Err(JobError::Usage(format!(
        "image size {width}x{height} would need {:.1} GiB of memory for its frame \
         ({FRAME_BYTES_PER_PIXEL} bytes per pixel), more than the {:.1} GiB allowed \
         (3/4 of the {:.1} GiB available); choose a smaller size",
        gib(need),
        gib(limit),
        gib(u128::from(available)),
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_memory_limit() {
        let gib = 1u64 << 30;
        assert!(check_frame_memory(1000, 1000, gib).is_ok());
        let e = check_frame_memory(100_000, 100_000, 16 * gib).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let msg = e.to_string();
        assert!(msg.contains("100000x100000"), "{msg}");
        assert!(msg.contains("596.0 GiB"), "{msg}");
        assert!(msg.contains("12.0 GiB allowed"), "{msg}");
        // The product cannot overflow.
        assert!(check_frame_memory(u32::MAX, u32::MAX, u64::MAX).is_err());
        assert!(available_memory() > 0);
    }
}
