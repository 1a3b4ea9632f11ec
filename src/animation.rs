//! Animations: frame `K` of a scene whose objects and camera move along
//! keyframes (`KeyframedTransform`, a camera's `numKeyframes`). A frame is
//! the scene seen at time `K / fps`, its shutter interval shifted to start
//! there, so every frame is an independent render: a task of a batch
//! scheduler like a piece of a frame (`--frame-from-env`).

use std::path::{Path, PathBuf};

/// Highest frame number accepted (ten million frames: over four days at
/// 24 fps; far beyond any job array, small enough for exact `f64` times).
pub const MAX_FRAME: u32 = 10_000_000;

/// Frame rate used when none is given.
pub const DEFAULT_FPS: f64 = 24.0;

/// Which frame of an animation to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTime {
    /// Frame number, from 0.
    pub index: u32,
    /// Frames per second: frame `index` starts at `index / fps`.
    pub fps: f64,
}

impl FrameTime {
    /// Frame `index` at `fps`, checked: `index <= MAX_FRAME`, `fps` finite
    /// and in `(0, 1e6]`.
    pub fn new(index: u32, fps: f64) -> Result<Self, String> {
        if index > MAX_FRAME {
            return Err(format!(
                "frame {index}: expected a frame number from 0 to {MAX_FRAME}"
            ));
        }
        if !(fps.is_finite() && fps > 0.0 && fps <= 1e6) {
            return Err(format!(
                "--fps {fps}: expected frames per second above 0 and at most 1000000"
            ));
        }
        Ok(Self { index, fps })
    }

    /// When the frame starts, in the scene's time unit.
    pub fn start(&self) -> f64 {
        f64::from(self.index) / self.fps
    }

    /// The scene's shutter interval `[open, close]` (relative to the start
    /// of a frame) moved to this frame. Sums in `f64`, rounded once.
    pub fn shutter(&self, [open, close]: [f32; 2]) -> [f32; 2] {
        let t = self.start();
        [(t + f64::from(open)) as f32, (t + f64::from(close)) as f32]
    }
}

/// The frame number in an environment variable (`SLURM_ARRAY_TASK_ID`,
/// `JOB_COMPLETION_INDEX`, ...), looked up by `env`.
pub fn frame_from_env(var: &str, env: impl Fn(&str) -> Option<String>) -> Result<u32, String> {
    let value =
        env(var).ok_or_else(|| format!("--frame-from-env {var}: the variable is not set"))?;
    value
        .trim()
        .parse::<u32>()
        .ok()
        .filter(|&k| k <= MAX_FRAME)
        .ok_or_else(|| format!("{var}={value}: expected a frame number from 0 to {MAX_FRAME}"))
}

/// `path` with the last run of `#` in its file name replaced by `index`,
/// zero-padded to the run's length (`shot_####.png`, frame 7 →
/// `shot_0007.png`; a longer number is written in full). A name without
/// `#` is returned as it is.
pub fn frame_path(path: &Path, index: u32) -> PathBuf {
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
        return path.to_path_buf();
    };
    let Some(end) = name.rfind('#') else {
        return path.to_path_buf();
    };
    let start = name[..end].trim_end_matches('#').len();
    let width = end + 1 - start;
    let new = format!("{}{index:0width$}{}", &name[..start], &name[end + 1..]);
    path.with_file_name(new)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_start_at_index_over_fps_and_shift_the_shutter() {
        let f = FrameTime::new(12, 24.0).unwrap();
        assert_eq!(f.start(), 0.5);
        assert_eq!(f.shutter([0.0, 0.02]), [0.5, 0.52]);
        assert_eq!(
            FrameTime::new(0, 30.0).unwrap().shutter([0.0, 0.0]),
            [0.0, 0.0]
        );
        // Rounded once from f64: 1/3 + 0.1 is the nearest f32 of the sum.
        let third = FrameTime::new(10, 30.0).unwrap();
        assert_eq!(
            third.shutter([0.1, 0.1])[0],
            (1.0f64 / 3.0 + 0.1f32 as f64) as f32
        );
    }

    #[test]
    fn bad_frames_and_rates_are_refused() {
        assert!(FrameTime::new(MAX_FRAME + 1, 24.0).is_err());
        for fps in [0.0, -1.0, f64::NAN, f64::INFINITY, 2e6] {
            let e = FrameTime::new(0, fps).unwrap_err();
            assert!(e.contains("--fps"), "{e}");
        }
        assert!(FrameTime::new(MAX_FRAME, 1e6).is_ok());
    }

    #[test]
    fn frame_numbers_come_from_the_environment() {
        let env = |v: &str| match v {
            "SLURM_ARRAY_TASK_ID" => Some(" 41\n".to_string()),
            "BAD" => Some("-3".to_string()),
            _ => None,
        };
        assert_eq!(frame_from_env("SLURM_ARRAY_TASK_ID", env), Ok(41));
        assert!(frame_from_env("BAD", env).unwrap_err().contains("BAD=-3"));
        assert!(frame_from_env("UNSET", env)
            .unwrap_err()
            .contains("not set"));
    }

    #[test]
    fn hashes_in_the_name_become_the_frame_number() {
        let p = |s: &str, k| frame_path(Path::new(s), k).to_string_lossy().into_owned();
        assert_eq!(p("out/shot_####.png", 7), "out/shot_0007.png");
        assert_eq!(p("shot_#.exr", 123), "shot_123.exr");
        assert_eq!(p("a#b_##.png", 5), "a#b_05.png");
        assert_eq!(p("still.png", 5), "still.png");
        assert_eq!(p("dir#/still.png", 5), "dir#/still.png");
    }
}
