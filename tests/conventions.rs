//! The conventions `docs/scene-format.md` ("Conventions") and `glint render
//! --help` write down, each pinned here through the command line a user
//! runs, with closed forms read from linear `.pfm` output.

use crate::common::scratch;
use crate::hdr_output::read_pfm;
use glint::math::Vec3;
use std::path::Path;
use std::process::Command;

/// Renders `scene` (text) at `w`×`h` into a PFM and returns its pixels.
fn render(dir: &Path, name: &str, scene: &str, (w, h): (u32, u32), extra: &[&str]) -> Vec<Vec3> {
    let file = dir.join(format!("{name}.txt"));
    std::fs::write(&file, scene).unwrap();
    let out = dir.join(format!("{name}.pfm"));
    let o = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["render", "--quiet"])
        .arg(&file)
        .arg("-o")
        .arg(&out)
        .args(["--size", &w.to_string(), &h.to_string()])
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (pw, ph, px) = read_pfm(&out);
    assert_eq!((pw, ph), (w, h));
    px
}

/// The floor `y = 0` seen from above by an orthographic camera.
const FLOOR_CAMERA: &str =
    "OrthographicCamera { center 0 1.5 0 direction 0 -1 0 up 0 0 -1 size 0.2 }";

/// A pixel is diffuse colour × irradiance, with no 1/π: a white light of
/// colour 0.8 straight above a floor of diffuse 0.5 makes it exactly 0.4
/// (with the 1/π of a Lambertian BRDF it would be 0.127).
#[test]
fn diffuse_term_has_no_one_over_pi() {
    let dir = scratch("convention-diffuse");
    let scene = format!(
        "{FLOOR_CAMERA}
         Lights {{ numLights 1 DirectionalLight {{ direction 0 -1 0 color 0.8 0.8 0.8 }} }}
         Background {{ color 0 0 0 ambientLight 0 0 0 }}
         Materials {{ numMaterials 1 PhongMaterial {{ diffuseColor 0.5 0.5 0.5 }} }}
         Group {{ numObjects 1 MaterialIndex 0 Plane {{ normal 0 1 0 offset 0 }} }}"
    );
    for p in render(&dir, "diffuse", &scene, (3, 3), &[]) {
        assert!((p - Vec3::splat(0.4)).abs().max_element() < 1e-6, "{p}");
    }
}

/// A flat area light's `power` is shared by its two faces: a small quad of
/// power P at height h above the floor gives irradiance P / (2π h²) under
/// it (radiance P / (π · 2A) times A / h²), whichever way its edges turn.
#[test]
fn flat_area_light_power_is_shared_by_its_two_faces() {
    let dir = scratch("convention-area-power");
    let (h, power) = (2.0f32, 4.0 * std::f32::consts::PI);
    let want = power / (2.0 * std::f32::consts::PI * h * h); // 0.5
                                                             // The same 0.1 × 0.1 quad, its normal up, then down.
    for (name, edges) in [
        ("up", "edge1 0 0 0.1 edge2 0.1 0 0"),
        ("down", "edge1 0.1 0 0 edge2 0 0 0.1"),
    ] {
        let scene = format!(
            "{FLOOR_CAMERA}
             Lights {{ numLights 1 AreaLight {{
                 quad {{ corner -0.05 {h} -0.05 {edges} }} color 1 1 1 power {power} }} }}
             Samples {{ shadow 16 }}
             Background {{ color 0 0 0 ambientLight 0 0 0 }}
             Materials {{ numMaterials 1 PhongMaterial {{ diffuseColor 1 1 1 }} }}
             Group {{ numObjects 1 MaterialIndex 0 Plane {{ normal 0 1 0 offset 0 }} }}"
        );
        let px = render(&dir, name, &scene, (3, 3), &[]);
        let centre = px[4];
        // The small-light approximation is good to (side / h)² ≈ 0.3%.
        assert!(
            (centre.x - want).abs() < 0.01 * want,
            "{name}: {centre}, expected {want}"
        );
    }
}

/// An orthographic camera sees objects behind its centre plane (its rays
/// start at t = −∞, the course's behaviour); a perspective camera does not.
#[test]
fn orthographic_camera_sees_behind_its_centre_plane() {
    let dir = scratch("convention-behind");
    let rest = "Background { color 0 0 0 ambientLight 0 0 0 }
         Materials { numMaterials 1 PhongMaterial { diffuseColor 0.2 0.7 0.3 } }
         Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 3 radius 1 } }";
    // No lights: white ambient, so a hit shows its diffuse colour.
    let ortho =
        format!("OrthographicCamera {{ center 0 0 0 direction 0 0 -1 up 0 1 0 size 4 }} {rest}");
    let persp =
        format!("PerspectiveCamera {{ center 0 0 0 direction 0 0 -1 up 0 1 0 angle 40 }} {rest}");
    let o = render(&dir, "ortho", &ortho, (5, 5), &[])[12];
    assert!(
        (o - Vec3::new(0.2, 0.7, 0.3)).abs().max_element() < 1e-6,
        "{o}"
    );
    let p = render(&dir, "persp", &persp, (5, 5), &[]);
    assert!(
        p.iter().all(|&c| c == Vec3::ZERO),
        "perspective saw behind itself"
    );
}

/// `aperture` is the lens radius and `focusDistance` the distance of the
/// focus plane along the viewing direction, as read from the file; what
/// the thin lens does with them (a point on that plane stays sharp off the
/// axis, blur grows as `aperture · |z − f| / z`) is pinned by
/// `distribution::thin_lens_focus_and_blur`.
#[test]
fn aperture_is_the_lens_radius_and_focus_a_plane_along_the_view() {
    let src = "PerspectiveCamera { center 0 0 0 direction 0 0 -2 up 0 1 0 angle 40
                   aperture 0.25 focusDistance 6 }
               Group { numObjects 0 }";
    let scene = glint::format::parse_scene(src, Path::new("lens.txt")).unwrap();
    assert_eq!(scene.effects.lens.aperture, 0.25);
    assert_eq!(scene.effects.lens.focus_distance, 6.0);
}

/// Where a user looks for them: `glint render --help` and the scene
/// format's "Conventions" section state each of the above.
#[test]
fn help_and_scene_format_state_the_conventions() {
    let o = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["render", "--help"])
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&o.stdout).replace('\n', " ");
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/scene-format.md"))
        .unwrap();
    let section = doc
        .split("## Conventions")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .expect("docs/scene-format.md has a Conventions section")
        .replace('\n', " ");
    for (text, name) in [(&help, "glint render --help"), (&section, "Conventions")] {
        for phrase in [
            "1/",
            "two faces",
            "behind its centre plane",
            "lens radius",
            "focusDistance",
        ] {
            assert!(text.contains(phrase), "{name} does not say '{phrase}'");
        }
    }
}
