//! `glint raytree`: the recorded tree is exactly what the renderer traced,
//! checked against a tree derived by hand, and every export of it.

use crate::common::*;
use std::process::Command;

/// A mirror plane through the origin facing (1, 0, 1), seen head-on by an
/// orthographic camera on the z axis: the eye ray hits the origin and
/// reflects along +x into a glass sphere at (5, 0, 0) of radius 1, at normal
/// incidence, so it enters undeviated, crosses the sphere and meets its back
/// at (6, 0, 0) from inside. One point light at (0, 5, 10).
///
/// By hand, with `--bounces 2 --shadows --shade-back`:
/// - depth 0: the eye ray; a shadow ray from the mirror (unblocked: the
///   sphere is off to the side); the reflected ray (mirror coefficient > 0);
/// - depth 1: the reflected ray hits the sphere's front: a shadow ray
///   (unblocked, the light is on this side) and the transmitted ray (glass,
///   no reflectiveColor so no reflected child);
/// - depth 2: the transmitted ray hits the back from inside: lit because of
///   `--shade-back`, so a shadow ray, blocked by the sphere itself; depth 2
///   = bounces, so no children.
///
/// Total: 1 eye, 3 shadow (1 blocked), 1 reflected, 1 transmitted.
const SCENE: &str = "
OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 4 }
Lights { numLights 1 PointLight { position 0 5 10 color 1 1 1 } }
Background { color 0 0 0 ambientLight 0.1 0.1 0.1 }
Materials { numMaterials 2
  PhongMaterial { diffuseColor 0.1 0.1 0.1 reflectiveColor 0.9 0.9 0.9 }
  PhongMaterial { diffuseColor 0.1 0.1 0.1 transparentColor 0.9 0.9 0.9 indexOfRefraction 1.5 }
}
Group { numObjects 2
  MaterialIndex 0 Plane { normal 0.7071068 0 0.7071068 offset 0 }
  MaterialIndex 1 Sphere { center 5 0 0 radius 1 }
}
";

fn raytree(args: &[&str], dir: &std::path::Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_glint"))
        .arg("raytree")
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

#[test]
fn hand_derived_tree_matches_the_json() {
    let dir = scratch("raytree");
    std::fs::write(dir.join("s.txt"), SCENE).unwrap();
    // 21x21 pixels: pixel (10, 10)'s centre is the screen centre, the z axis.
    let flags = [
        "--size",
        "21",
        "21",
        "--pixel",
        "10",
        "10",
        "--bounces",
        "2",
        "--shadows",
        "--shade-back",
    ];
    let out = raytree(&[&["s.txt", "-o", "t.json"][..], &flags].concat(), &dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("t.json")).unwrap()).unwrap();
    let counts = &json["counts"];
    assert_eq!(
        (
            &counts["eye"],
            &counts["shadow"],
            &counts["reflected"],
            &counts["transmitted"]
        ),
        (&1.into(), &3.into(), &1.into(), &1.into()),
        "{json}"
    );
    let rays = json["rays"].as_array().unwrap();
    let by = |kind: &str| -> Vec<(u64, bool)> {
        rays.iter()
            .filter(|r| r["kind"] == kind)
            .map(|r| {
                (
                    r["depth"].as_u64().unwrap(),
                    r["occluded"].as_bool().unwrap(),
                )
            })
            .collect()
    };
    assert_eq!(by("eye"), [(0, false)]);
    assert_eq!(by("reflected"), [(1, false)]);
    assert_eq!(by("transmitted"), [(2, false)]);
    let mut shadows = by("shadow");
    shadows.sort();
    assert_eq!(shadows, [(0, false), (1, false), (2, true)]);
    // The reflected ray ends on the sphere's front at (4, 0, 0), the
    // transmitted one on its back at (6, 0, 0).
    let end = |kind: &str| -> Vec<f64> {
        let r = rays.iter().find(|r| r["kind"] == kind).unwrap();
        r["end"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    for (kind, x) in [("reflected", 4.0), ("transmitted", 6.0)] {
        let e = end(kind);
        assert!(
            (e[0] - x).abs() < 1e-3 && e[1].abs() < 1e-3 && e[2].abs() < 1e-3,
            "{kind}: {e:?}"
        );
    }
    assert_eq!(json["max_depth"], 2);

    // The same tree as segments: one `l` per ray in the OBJ, one edge each in the PLY.
    let out = raytree(&[&["s.txt", "-o", "t.obj"][..], &flags].concat(), &dir);
    assert!(out.status.success());
    let obj = std::fs::read_to_string(dir.join("t.obj")).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("l ")).count(), 6);
    assert_eq!(obj.lines().filter(|l| l.starts_with("v ")).count(), 12);
    assert!(obj.contains("g shadow") && obj.contains("0.1 0.9 0.1"));
    let out = raytree(&[&["s.txt", "-o", "t.ply"][..], &flags].concat(), &dir);
    assert!(out.status.success());
    let ply = std::fs::read_to_string(dir.join("t.ply")).unwrap();
    assert!(ply.contains("element vertex 12\n") && ply.contains("element edge 6\n"));

    // Bounces 1 cuts the tree after the reflection: no transmitted ray.
    let mut fewer = flags.to_vec();
    fewer[7] = "1";
    let out = raytree(&[&["s.txt", "-o", "u.json"][..], &fewer].concat(), &dir);
    assert!(out.status.success());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("u.json")).unwrap()).unwrap();
    assert_eq!(json["counts"]["transmitted"], 0);
    assert_eq!(json["counts"]["shadow"], 2);
}

/// The overlay of scene4_14's pixel (100, 100) draws every ray of the tree
/// inside the frame, and changes the image.
#[test]
fn overlay_shows_every_ray_of_the_gem() {
    use glint::render::{CameraModel, PixelOffset};
    use glint::viz::raytree;
    let Some(scenes) = scenes("overlay_shows_every_ray_of_the_gem") else {
        return;
    };
    let scene = glint::format::load_scene(&scenes.join("scene4_14_faceted_gem.txt")).unwrap();
    let world = glint::world::World::build(&scene, Default::default());
    let camera = CameraModel::new(world.camera());
    let integrator = glint::integrator::Whitted {
        bounces: 5,
        weight_cutoff: 0.01,
        shadows: true,
        shade_back: true,
        ..Default::default()
    };
    let tree = raytree::record(
        &world,
        &camera,
        &integrator,
        (200, 200),
        (100, 100),
        PixelOffset::CENTER,
    );
    assert!(tree.rays.len() > 10, "{} rays", tree.rays.len());
    let (frame, _) = glint::render::render(
        &world,
        &camera,
        &integrator,
        (200, 200),
        PixelOffset::CENTER,
    );
    let mut canvas = glint::viz::draw::Canvas::new(200, 200, frame.color.clone());
    let visible = tree.draw(&mut canvas, &camera);
    assert_eq!(visible, tree.rays.len(), "rays outside the frame");
    let changed = canvas
        .pixels
        .iter()
        .zip(&frame.color)
        .filter(|(a, b)| a != b)
        .count();
    assert!(changed > 200, "only {changed} pixels drawn");
}

#[test]
fn bad_pixel_and_format_exit_2() {
    let dir = scratch("raytree-bad");
    std::fs::write(dir.join("s.txt"), SCENE).unwrap();
    let out = raytree(
        &[
            "s.txt", "--size", "4", "4", "--pixel", "4", "0", "-o", "t.json",
        ],
        &dir,
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("outside"));
    let out = raytree(&["s.txt", "--pixel", "1", "1", "-o", "t.xyz"], &dir);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains(".json"));
}

/// `glint raytree --integrator path`: the path of sample `k` of a pixel is
/// the one `glint render --integrator path` traced with the same `--spp`,
/// `--sampler` and `--seed` (the mean of the pixel's recorded paths is the
/// rendered pixel), its vertices chain (each scattered ray leaves where
/// the previous one ended), and the light it carries is itemised: every
/// shadow ray and every ray that met an emitter or the environment has its
/// MIS weight in [0, 1] and its contribution, blocked shadow rays add
/// nothing, and the contributions add up to the path's colour. Across the
/// paths, emitters hit by a scattered ray take weights strictly between 0
/// and 1 (both strategies could find them), as do light samples.
#[test]
fn path_tree_is_a_path_of_the_render_with_its_mis_weights() {
    let dir = scratch("raytree-path");
    let scene = own_scene("cornell_caustics.txt")
        .to_string_lossy()
        .into_owned();
    let sampling = ["--spp", "4", "--sampler", "random", "--seed", "3"];
    let size = ["--size", "32", "32"];
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args([
            "render",
            &scene,
            "-o",
            "r.exr",
            "--integrator",
            "path",
            "--quiet",
        ])
        .args(size)
        .args(sampling)
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let image = glint::output::read_exr_window(&dir.join("r.exr")).unwrap();
    let (mut mixed_emitter, mut mixed_light) = (0, 0);
    for (x, y) in [(16, 28), (8, 20), (24, 12), (16, 4), (20, 24), (10, 26)] {
        let mut sum = [0f64; 3];
        for k in 0..4 {
            let (px, k_) = (format!("{x} {y}"), k.to_string());
            let mut px = px.split(' ');
            let args = [
                &[scene.as_str(), "-o", "t.json", "--integrator", "path"][..],
                &["--pixel", px.next().unwrap(), px.next().unwrap()],
                &size,
                &sampling,
                &["--sample", &k_],
            ]
            .concat();
            let out = raytree(&args, &dir);
            assert!(out.status.success(), "{out:?}");
            let t: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(dir.join("t.json")).unwrap())
                    .unwrap();
            let color: Vec<f64> = (0..3).map(|c| t["color"][c].as_f64().unwrap()).collect();
            let mut carried = [0f64; 3];
            let mut last_end: Option<Vec<f64>> = None;
            for r in t["rays"].as_array().unwrap() {
                let kind = r["kind"].as_str().unwrap();
                let xyz = |key: &str| -> Vec<f64> {
                    (0..3).map(|c| r[key][c].as_f64().unwrap()).collect()
                };
                if kind != "shadow" {
                    if let Some(end) = &last_end {
                        let o = xyz("origin");
                        let d: f64 = (0..3).map(|c| (o[c] - end[c]).abs()).sum();
                        assert!(
                            d < 1e-3,
                            "({x}, {y}) sample {k}: {kind} ray leaves {o:?}, not {end:?}"
                        );
                    }
                    last_end = r["hit"].as_bool().unwrap().then(|| xyz("end"));
                }
                let w = r["mis_weight"].as_f64();
                if kind == "shadow" {
                    assert!(w.is_some(), "a light sample without its weight: {r}");
                }
                let Some(w) = w else { continue };
                assert!((0.0..=1.0).contains(&w), "{r}");
                let c = xyz("contribution");
                if r["occluded"].as_bool().unwrap() {
                    assert_eq!(c, [0.0; 3], "{r}");
                }
                if w > 0.0 && w < 1.0 && c.iter().any(|&v| v > 0.0) {
                    if kind == "shadow" {
                        mixed_light += 1;
                    } else {
                        mixed_emitter += 1;
                    }
                }
                for ch in 0..3 {
                    carried[ch] += c[ch];
                    assert!(c[ch] >= 0.0, "{r}");
                }
            }
            for ch in 0..3 {
                assert!(
                    (carried[ch] - color[ch]).abs() <= 1e-5 * color[ch].max(1.0),
                    "({x}, {y}) sample {k}: contributions {carried:?}, colour {color:?}"
                );
                sum[ch] += color[ch] / 4.0;
            }
        }
        let p = image.pixels[y * 32 + x];
        for ch in 0..3 {
            let want = p[ch] as f64;
            assert!(
                (sum[ch] - want).abs() <= 1e-5 * want.max(1.0),
                "({x}, {y}): paths {sum:?}, rendered {p}"
            );
        }
    }
    assert!(
        mixed_emitter > 0 && mixed_light > 0,
        "{mixed_emitter} emitters hit and {mixed_light} light samples with 0 < w < 1"
    );
    // Path flags without the path tracer, and a sample outside --spp.
    for (args, want) in [
        (&["--seed", "3"][..], "need --integrator path"),
        (
            &["--integrator", "path", "--spp", "4", "--sample", "4"][..],
            "not one of the 4 samples",
        ),
    ] {
        let all = [
            &[scene.as_str(), "-o", "t.json", "--pixel", "1", "1"][..],
            &size,
            args,
        ]
        .concat();
        let out = raytree(&all, &dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
}
