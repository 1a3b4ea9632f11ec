//! The MIT 6.837 command line, verbatim:
//! `raytracer -input scene.txt -size 200 200 -output out.tga -shadows -bounces 3 -weight 0.01`.

use glint::accel::AccelKind;
use glint::job::Job;
use glint::material::TextureSpace;
use glint::render::PixelOffset;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    glint::job::run_guarded("raytracer", real_main)
}

/// Every flag, its arguments and one line of help, in the order `-help` prints them.
const FLAGS: &[(&str, &str, &str)] = &[
    (
        "-input",
        "FILE",
        "scene file (MIT 6.837 format) or a bare .obj mesh",
    ),
    (
        "-output",
        "FILE",
        "colour image: .png .tga .ppm .bmp (8-bit) or .exr .pfm (float)",
    ),
    ("-size", "W H", "image size in pixels (default 100 100)"),
    ("-depth", "T0 T1 FILE", "depth image: t0 white, t1 black"),
    ("-normals", "FILE", "normals image: |x| |y| |z| as RGB"),
    ("-shadows", "", "cast shadow rays"),
    (
        "-transparent_shadows",
        "",
        "filter light through transparent occluders (implies -shadows' rays)",
    ),
    (
        "-shade_back",
        "",
        "light the back sides of surfaces (black otherwise)",
    ),
    (
        "-bounces",
        "N",
        "maximum reflection/refraction depth (default 0)",
    ),
    (
        "-weight",
        "W",
        "prune ray-tree branches contributing less than W (default 0)",
    ),
    ("-grid", "NX NY NZ", "use a uniform grid of this resolution"),
    (
        "-accel",
        "NAME",
        "none, grid, nested-grid[:THRESHOLD[:DEPTH]] (defaults 16:2), octree, octree-inner, bvh (= bvh-sah), bvh-median, bvh-midpoint, bvh-hierarchy",
    ),
    (
        "-no_flatten",
        "",
        "keep the transform hierarchy instead of baking it into world space",
    ),
    (
        "-texture_space",
        "world|object",
        "where textures are looked up (default world)",
    ),
    ("-stats", "", "print ray and traversal statistics"),
    ("-stats_json", "FILE", "write the statistics as JSON"),
    ("-threads", "N", "worker threads (default: all cores)"),
    ("-quiet", "", "no progress bar"),
    (
        "-gui",
        "",
        "accepted and ignored (the course's OpenGL preview)",
    ),
    (
        "-tessellation",
        "A B",
        "accepted and ignored (the course's OpenGL preview)",
    ),
    (
        "-gouraud",
        "",
        "accepted and ignored (the course's OpenGL preview)",
    ),
    ("-help", "", "print this help (also -h, --help)"),
];

/// The `-help` text: usage, then one line per flag.
fn help() -> String {
    let mut s = String::from(
        "raytracer: the MIT 6.837 ray tracer's command line, verbatim\n\n\
         usage: raytracer -input SCENE -output IMAGE [-size W H] [flags]\n\
         e.g.:  raytracer -input scene4_14_faceted_gem.txt -size 200 200 -output out.tga -shadows -bounces 3 -weight 0.01\n\n\
         Each pixel's eye ray goes through the pixel's lower-left corner (the course's convention;\n\
         `glint render` uses the centre).\n\nflags:\n",
    );
    for (flag, args, text) in FLAGS {
        let lhs = format!("{flag} {args}");
        s.push_str(&format!("  {lhs:<30}{text}\n"));
    }
    s
}

fn real_main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args
        .iter()
        .any(|a| matches!(a.as_str(), "-help" | "-h" | "--help"))
    {
        print!("{}", help());
        return ExitCode::SUCCESS;
    }
    let (mut job, stats) = match parse(&args) {
        Ok(j) => j,
        Err(msg) => {
            eprintln!("raytracer: {msg}");
            return ExitCode::from(2);
        }
    };
    job.cancel = Some(glint::job::interrupt_flag());
    match job.run() {
        Ok(report) => {
            if stats {
                print!("{}", report.stats_text());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("raytracer: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

/// Flags of the course's OpenGL preview: accepted so the handouts' lines run.
const PREVIEW_ONLY: &[(&str, usize)] = &[("-gui", 0), ("-tessellation", 2), ("-gouraud", 0)];

fn parse(args: &[String]) -> Result<(Job, bool), String> {
    let mut it = args.iter();
    let mut job = Job::new(PathBuf::new(), 100, 100);
    job.pixel_offset = PixelOffset::CORNER;
    let mut input = None;
    let mut stats = false;
    let mut ignored = Vec::new();
    let mut quiet = false;
    let mut grid = None;
    let mut accel = None;
    while let Some(flag) = it.next() {
        let mut value = |what: &str| -> Result<&String, String> {
            it.next().ok_or_else(|| format!("{flag} expects {what}"))
        };
        match flag.as_str() {
            "-input" => input = Some(PathBuf::from(value("a scene file")?)),
            "-output" => job.output = Some(PathBuf::from(value("an image file")?)),
            "-size" => {
                job.width = number(flag, value("a width")?)?;
                job.height = number(flag, value("a height")?)?;
            }
            "-depth" => {
                let t0 = number(flag, value("t0 t1 file")?)?;
                let t1 = number(flag, value("t1 file")?)?;
                job.depth = Some((t0, t1, PathBuf::from(value("a file")?)));
            }
            "-normals" => job.normals = Some(PathBuf::from(value("an image file")?)),
            "-shade_back" => job.integrator.shade_back = true,
            "-shadows" => job.integrator.shadows = true,
            "-transparent_shadows" => job.integrator.transparent_shadows = true,
            "-bounces" => job.integrator.bounces = number(flag, value("a count")?)?,
            "-weight" => job.integrator.weight_cutoff = number(flag, value("a weight")?)?,
            "-stats" => stats = true,
            "-threads" => job.threads = Some(number(flag, value("a count")?)?),
            "-quiet" => quiet = true,
            "-grid" => {
                let mut res = [0u32; 3];
                for r in &mut res {
                    *r = number(flag, value("nx ny nz")?)?;
                }
                if res.contains(&0) {
                    return Err(format!(
                        "-grid {} {} {}: every resolution must be at least 1",
                        res[0], res[1], res[2]
                    ));
                }
                grid = Some(res);
            }
            "-accel" => {
                let name = value("an accelerator name (see -help)")?;
                accel = Some(
                    name.parse::<AccelKind>()
                        .map_err(|e| format!("-accel: {e}"))?,
                );
            }
            "-no_flatten" => job.build.flatten = false,
            "-texture_space" => {
                job.integrator.texture_space = match value("world or object")?.as_str() {
                    "world" => TextureSpace::World,
                    "object" => TextureSpace::Object,
                    other => {
                        return Err(format!(
                            "-texture_space: expected world or object, found '{other}'"
                        ))
                    }
                }
            }
            "-stats_json" => job.stats_json = Some(PathBuf::from(value("a file")?)),
            other => match PREVIEW_ONLY.iter().find(|(f, _)| *f == other) {
                Some((f, n)) => {
                    for _ in 0..*n {
                        value("its arguments")?;
                    }
                    ignored.push(*f);
                }
                None => {
                    return Err(format!(
                        "unknown flag '{other}' (raytracer -help lists every flag)"
                    ))
                }
            },
        }
    }
    if !ignored.is_empty() {
        eprintln!(
            "raytracer: ignoring preview-only flags: {}",
            ignored.join(" ")
        );
    }
    // `-grid nx ny nz` alone selects the grid (the course's syntax); with
    // `-accel grid` it sets that grid's resolution; with another `-accel`
    // the explicit accelerator wins.
    job.build.accel = match (accel, grid) {
        (None, Some(res)) | (Some(AccelKind::Grid { .. }), Some(res)) => {
            AccelKind::Grid { res: Some(res) }
        }
        (Some(kind), _) => kind,
        (None, None) => AccelKind::default(),
    };
    job.input = input.ok_or("missing -input SCENE")?;
    job.progress = !quiet && std::io::stdout().is_terminal();
    Ok((job, stats))
}

fn number<T: std::str::FromStr>(flag: &str, s: &str) -> Result<T, String> {
    s.parse()
        .map_err(|_| format!("{flag}: '{s}' is not a valid number"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn handout_line_parses() {
        let (j, _) = parse(&args(
            "-input scene4_14_faceted_gem.txt -size 200 100 -output out.tga -shadows -shade_back -bounces 3 -weight 0.01 -gui -tessellation 10 5",
        ))
        .unwrap();
        assert_eq!((j.width, j.height), (200, 100));
        assert!(j.integrator.shadows && j.integrator.shade_back);
        assert_eq!(j.integrator.bounces, 3);
        assert_eq!(j.integrator.weight_cutoff, 0.01);
    }

    #[test]
    fn grid_and_accel_flags() {
        let (j, _) = parse(&args("-input a.txt -grid 10 10 7")).unwrap();
        assert_eq!(
            j.build.accel,
            AccelKind::Grid {
                res: Some([10, 10, 7])
            }
        );
        let (j, _) = parse(&args("-input a.txt -grid 10 10 7 -accel octree")).unwrap();
        assert_eq!(j.build.accel, AccelKind::Octree);
        let (j, _) = parse(&args("-input a.txt")).unwrap();
        assert_eq!(j.build.accel, AccelKind::default());
        assert!(parse(&args("-input a.txt -accel kdtree"))
            .unwrap_err()
            .contains("kdtree"));
        assert!(parse(&args("-input a.txt -grid 0 1 1")).is_err());
    }

    /// Every flag `parse` accepts is in the help, and every flag in the help
    /// is accepted: the help cannot drift from the parser.
    #[test]
    fn help_lists_every_flag_parse_accepts() {
        let source = include_str!("raytracer.rs");
        let parse_src =
            &source[source.find("fn parse(").unwrap()..source.find("fn number<").unwrap()];
        let mut accepted: Vec<&str> = parse_src
            .split('"')
            .filter(|t| {
                t.starts_with('-')
                    && t.len() > 1
                    && t[1..].chars().all(|c| c.is_ascii_lowercase() || c == '_')
            })
            .collect();
        accepted.extend(PREVIEW_ONLY.iter().map(|(f, _)| *f));
        let text = help();
        for flag in &accepted {
            assert!(
                text.lines()
                    .any(|l| l.trim_start().split(' ').next() == Some(flag)),
                "{flag} is accepted but not in -help"
            );
        }
        for (flag, _, _) in FLAGS {
            assert!(
                *flag == "-help" || accepted.contains(flag),
                "{flag} is in -help but not accepted"
            );
        }
        assert!(accepted.len() >= 20, "{accepted:?}");
    }

    /// `-help` names every accelerator `-accel` accepts.
    #[test]
    fn help_lists_every_accelerator() {
        let text = help();
        let line = text
            .lines()
            .find(|l| l.trim_start().starts_with("-accel"))
            .unwrap();
        for name in AccelKind::NAMES {
            assert!(line.contains(name), "{name} is not in -help's -accel line");
        }
    }

    #[test]
    fn unknown_flag_is_named() {
        let e = parse(&args("-input a.txt -bogus")).unwrap_err();
        assert!(e.contains("-bogus"));
    }

    #[test]
    fn missing_value_and_bad_number() {
        assert!(parse(&args("-input a.txt -size 200")).is_err());
        assert!(parse(&args("-input a.txt -bounces x"))
            .unwrap_err()
            .contains("'x'"));
    }
}
