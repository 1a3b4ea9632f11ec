//! The files a job writes: a list of requested [`Output`]s, what each is
//! called in messages, and the stage that writes them from a rendered frame.

use super::spec::FlagNames;
use super::{partial_path, Job, JobError};
use crate::limits;
use crate::math::Vec3;
use crate::output::{write_file, write_rgb, write_rgb_as};
use crate::render::views::{filter_view, heat_map, samples_view, Image};
use crate::render::{Rendered, Settings};
use std::borrow::Cow;
use std::mem::discriminant;
use std::path::{Path, PathBuf};

/// One file a job writes.
#[derive(Clone, Debug, PartialEq)]
pub enum Output {
    /// The colour image (or, with [`Job::piece`], the piece as an EXR).
    Colour(PathBuf),
    /// The depth image: `near` white, `far` black.
    Depth {
        /// Distance drawn white.
        near: f32,
        /// Distance drawn black.
        far: f32,
        /// The file.
        path: PathBuf,
    },
    /// The normals image: `|x| |y| |z|` as RGB.
    Normals(PathBuf),
    /// The course's `-render_samples FILE zoom` view.
    SamplesView {
        /// The file.
        path: PathBuf,
        /// Pixels a pixel of the frame becomes, per side.
        zoom: u32,
    },
    /// The course's `-render_filter FILE zoom` view.
    FilterView {
        /// The file.
        path: PathBuf,
        /// Pixels a pixel of the frame becomes, per side.
        zoom: u32,
    },
    /// Heat map of camera rays per pixel, with a scale bar.
    SamplesHeatMap(PathBuf),
    /// Heat maps of intersection tests and nodes visited per pixel, with
    /// scale bars and totals (`--cost-image`).
    Cost(PathBuf),
    /// The statistics as JSON.
    Stats(PathBuf),
}

/// The largest zoom of the sample and filter views.
pub const MAX_ZOOM: u32 = 1000;

/// The file of an output, by reference (`ref`) or mutable reference
/// (`ref mut`): the one list of which variant keeps its path where.
macro_rules! output_path {
    ($o:expr, $($r:tt)+) => {
        match $o {
            Output::Colour($($r)+ p)
            | Output::Normals($($r)+ p)
            | Output::SamplesHeatMap($($r)+ p)
            | Output::Cost($($r)+ p)
            | Output::Stats($($r)+ p)
            | Output::Depth { path: $($r)+ p, .. }
            | Output::SamplesView { path: $($r)+ p, .. }
            | Output::FilterView { path: $($r)+ p, .. } => p,
        }
    };
}

impl Output {
    /// The file.
    pub fn path(&self) -> &Path {
        output_path!(self, ref)
    }

    /// The file, to rename it.
    pub fn path_mut(&mut self) -> &mut PathBuf {
        output_path!(self, ref mut)
    }

    /// What the file is, for messages.
    pub fn what(&self) -> &'static str {
        match self {
            Output::Colour(_) => "colour image",
            Output::Depth { .. } => "depth image",
            Output::Normals(_) => "normals image",
            Output::SamplesView { .. } => "samples view",
            Output::FilterView { .. } => "filter view",
            Output::SamplesHeatMap(_) => "samples heat map",
            Output::Cost(_) => "cost image",
            Output::Stats(_) => "statistics file",
        }
    }

    /// An image (every output but the statistics).
    pub fn is_image(&self) -> bool {
        !matches!(self, Output::Stats(_))
    }

    /// An image of the frame's own size (colour, depth, normals).
    pub fn is_frame_sized(&self) -> bool {
        matches!(
            self,
            Output::Colour(_) | Output::Depth { .. } | Output::Normals(_)
        )
    }

    /// The output's numbers in range: finite depths, zooms from 1 to
    /// [`MAX_ZOOM`].
    pub fn validate(&self, names: FlagNames) -> Result<(), String> {
        match self {
            Output::Depth { near, far, .. } => {
                for t in [*near, *far] {
                    limits::finite_in(&names.flag("depth"), t, f32::MIN, f32::MAX)?;
                }
            }
            Output::SamplesView { zoom, .. } => {
                limits::int_in(&names.flag("render-samples"), *zoom, 1, MAX_ZOOM)?;
            }
            Output::FilterView { zoom, .. } => {
                limits::int_in(&names.flag("render-filter"), *zoom, 1, MAX_ZOOM)?;
            }
            _ => {}
        }
        Ok(())
    }
}

impl Job {
    /// Adds `output`, replacing any output of the same kind (a flag given
    /// twice: the last one wins).
    pub fn set_output(&mut self, output: Output) {
        match self
            .outputs
            .iter_mut()
            .find(|o| discriminant(*o) == discriminant(&output))
        {
            Some(o) => *o = output,
            None => self.outputs.push(output),
        }
    }

    /// The colour image's file, if one was asked for.
    pub fn colour(&self) -> Option<&Path> {
        self.outputs.iter().find_map(|o| match o {
            Output::Colour(p) => Some(p.as_path()),
            _ => None,
        })
    }

    /// Every image file this job will write.
    pub fn image_paths(&self) -> impl Iterator<Item = &Path> {
        self.outputs
            .iter()
            .filter(|o| o.is_image())
            .map(Output::path)
    }

    /// Every file this job may write, with what it is: the images, their
    /// `.partial` twins (written when interrupted) and the statistics.
    /// [`Job::preflight`] checks this list against the inputs and against
    /// itself.
    pub fn files(&self) -> Vec<(String, PathBuf)> {
        let mut out: Vec<(String, PathBuf)> = Vec::new();
        for o in &self.outputs {
            let (what, p) = (o.what(), o.path());
            out.push((what.into(), p.into()));
            if o.is_image() {
                out.push((format!("{what} if interrupted"), partial_path(p)));
            }
        }
        out
    }

    /// Writes every requested image of `rendered` (under its `.partial`
    /// name if the render was interrupted, `complete` false) and returns the
    /// files written. The colour image of a piece and the statistics are
    /// written by their own stages.
    pub(super) fn write_images(
        &self,
        rendered: &Rendered,
        settings: &Settings,
        complete: bool,
    ) -> Result<Vec<PathBuf>, JobError> {
        let frame = &rendered.frame;
        let (w, h) = (self.width, self.height);
        let mut written = Vec::new();
        for o in &self.outputs {
            let (iw, ih, pixels): (u32, u32, Cow<[Vec3]>) = match o {
                Output::Colour(_) if self.piece.is_some() => continue,
                Output::Stats(_) => continue,
                Output::Colour(_) => (w, h, Cow::Borrowed(&frame.color)),
                Output::Depth { near, far, .. } => (w, h, frame.depth_image(*near, *far).into()),
                Output::Normals(_) => (w, h, frame.normals_image().into()),
                Output::SamplesView { zoom, .. } => {
                    owned(samples_view(w, h, *zoom, &rendered.samples))
                }
                Output::FilterView { zoom, .. } => {
                    owned(filter_view(&settings.filter, w, h, *zoom))
                }
                Output::SamplesHeatMap(_) => owned(heat_map(w, h, &frame.samples)),
                Output::Cost(_) => {
                    let c = crate::viz::cost::image(frame);
                    (c.width, c.height, c.pixels.into())
                }
            };
            let path = if complete {
                o.path().to_path_buf()
            } else {
                partial_path(o.path())
            };
            match o {
                Output::Colour(_) => write_rgb_as(&path, iw, ih, &pixels, self.encoding)?,
                _ => write_rgb(&path, iw, ih, &pixels)?,
            }
            written.push(path);
        }
        Ok(written)
    }

    /// Writes the statistics file, if one was asked for.
    pub(super) fn write_stats(&self, report: &super::Report) -> Result<(), JobError> {
        for o in &self.outputs {
            if let Output::Stats(path) = o {
                let text = serde_json::to_string_pretty(&report.stats())
                    .map_err(|e| JobError::Internal(e.to_string()))?;
                write_file(path, (text + "\n").as_bytes())?;
            }
        }
        Ok(())
    }
}

fn owned(image: Image) -> (u32, u32, Cow<'static, [Vec3]>) {
    (image.width, image.height, Cow::Owned(image.pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_output_replaces_its_kind_and_at_frame_renames_every_file() {
        let mut j = Job::new("s.txt".into(), 4, 4);
        j.set_output(Output::Colour("a.png".into()));
        j.set_output(Output::Stats("s_##.json".into()));
        j.set_output(Output::Colour("shot_###.png".into()));
        j.set_output(Output::Depth {
            near: 1.0,
            far: 2.0,
            path: "d#.png".into(),
        });
        assert_eq!(j.outputs.len(), 3);
        assert_eq!(j.colour(), Some(Path::new("shot_###.png")));
        let f = crate::animation::FrameTime::new(7, 24.0).unwrap();
        let j = j.at_frame(f);
        let names: Vec<&Path> = j.outputs.iter().map(Output::path).collect();
        assert_eq!(
            names,
            [
                Path::new("shot_007.png"),
                Path::new("s_07.json"),
                Path::new("d7.png")
            ]
        );
        // Images have a partial twin; the statistics do not.
        let files = j.files();
        assert_eq!(files.len(), 5);
        assert!(files
            .iter()
            .any(|(w, p)| w == "colour image if interrupted"
                && p == Path::new("shot_007.partial.png")));
        assert_eq!(j.image_paths().count(), 2);
    }
}
