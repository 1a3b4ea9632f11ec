//! The glTF reader's unit tests.

use super::uri::{percent_decode, resolve_uri};
use super::*;
use base64::Engine as _;

/// One triangle: 3 positions then 3 u16 indices (+2 bytes of padding).
fn buffer() -> Vec<u8> {
    let mut b = Vec::new();
    for x in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        b.extend(x.to_le_bytes());
    }
    for i in [0u16, 1, 2, 3] {
        b.extend(i.to_le_bytes());
    }
    b
}

fn data_uri(b: &[u8]) -> String {
    let enc = base64::engine::general_purpose::STANDARD.encode(b);
    format!("data:application/octet-stream;base64,{enc}")
}

/// A document with `extra` spliced into the top-level object.
fn doc(uri: &str, count: usize, extra: &str) -> String {
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}],
        "nodes": [{{"mesh": 0, "translation": [0, 0, -5]}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
        "buffers": [{{"uri": "{uri}", "byteLength": 44}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 36}},
                        {{"buffer": 0, "byteOffset": 36, "byteLength": 8}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                        "min": [0, 0, 0], "max": [1, 1, 0]}},
                      {{"bufferView": 1, "componentType": 5123, "count": {count},
                        "type": "SCALAR"}}]{extra}}}"#
    )
}

fn parse(src: &str) -> Result<Scene, ParseError> {
    parse_gltf(src.as_bytes(), Path::new("m.gltf"), &mut |u| {
        Err(format!("no file {u}"))
    })
}

#[test]
fn a_triangle_with_its_node_transform() {
    let s = parse(&doc(&data_uri(&buffer()), 3, "")).unwrap();
    let b = s.root.bounds(&glam::DMat4::IDENTITY);
    assert_eq!(
        (b.min, b.max),
        (Vec3::new(0., 0., -5.), Vec3::new(1., 1., -5.))
    );
    assert_eq!(s.summary().triangles, 1);
    // No camera, no lights: the bare-mesh framing and light.
    assert_eq!(s.lights.len(), 1);
    // glTF's default material is white and diffuse.
    match &s.materials[0] {
        Material::Phong(p) => assert_eq!(p.diffuse, Vec3::ONE),
        m => panic!("{m:?}"),
    }
}

#[test]
fn camera_lights_and_materials_are_mapped() {
    let extra = r#", "cameras": [{"type": "perspective", "perspective":
          {"yfov": 0.5, "aspectRatio": 2.0, "znear": 0.1}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
          {"type": "point", "color": [1, 0.5, 0], "intensity": 3.14159265},
          {"type": "directional", "intensity": 0}]}},
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1],
          "metallicFactor": 0, "roughnessFactor": 0.5}}]"#;
    let mut src = doc(&data_uri(&buffer()), 3, extra);
    src = src.replace(
        r#""nodes": [{"mesh": 0, "translation": [0, 0, -5]}]"#,
        r#""nodes": [{"mesh": 0, "children": [1, 2]}, {"camera": 0, "translation": [0, 0, 3]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [1, 2, 3]}]"#,
    );
    src = src.replace(r#""indices": 1}"#, r#""indices": 1, "material": 0}"#);
    let s = parse(&src).unwrap();
    match s.camera {
        Camera::Perspective {
            center,
            direction,
            angle_deg,
            ..
        } => {
            assert_eq!(
                (center.as_vec3(), direction),
                (Vec3::new(0., 0., 3.), Vec3::NEG_Z)
            );
            let want = (2.0 * (0.25f64.tan() * 2.0).atan()).to_degrees();
            assert!((angle_deg as f64 - want).abs() < 1e-4, "{angle_deg}");
        }
        c => panic!("{c:?}"),
    }
    match &s.lights[..] {
        [Light::Point {
            position, color, ..
        }] => {
            assert_eq!(*position, glam::DVec3::new(1., 2., 3.));
            assert!((*color - Vec3::new(1., 0.5, 0.)).length() < 1e-6);
        }
        l => panic!("{l:?}"),
    }
    match &s.materials[0] {
        Material::Phong(p) => {
            assert_eq!(p.diffuse, Vec3::X);
            assert!((p.specular - Vec3::splat(0.02)).length() < 1e-7);
            assert_eq!(p.exponent, 30.0);
        }
        m => panic!("{m:?}"),
    }
}

#[test]
fn hostile_documents_are_refused_with_the_element() {
    let good = data_uri(&buffer());
    let short = data_uri(&buffer()[..40]);
    for (src, want) in [
        (
            doc(&short, 3, ""),
            "44 bytes in buffer 0 (its byteLength), found 40 bytes",
        ),
        (
            doc(&good, 5, ""),
            "5 elements inside buffer view 1, found a view of 8 bytes (accessor 1",
        ),
        (
            doc(&good, 4, ""),
            "indices below the 3 vertices of mesh 0 primitive 0, found 3 in accessor 1",
        ),
        (
            doc(&good, 4294967295, ""),
            "4294967295 elements inside buffer view 1",
        ),
        (
            doc("../secret.bin", 3, ""),
            "'../secret.bin' (a path outside the file's folder)",
        ),
        (doc("/etc/passwd", 3, ""), "outside the file's folder"),
        (
            doc("http://example.com/a.bin", 3, ""),
            "outside the file's folder",
        ),
        (
            doc("file:///etc/passwd", 3, ""),
            "outside the file's folder",
        ),
        (
            doc("data:application/octet-stream;base64,@@@@", 3, ""),
            "bad base64",
        ),
        (doc("sub/m.bin", 3, ""), "no file sub/m.bin"),
    ] {
        let e = parse(&src).unwrap_err();
        assert!(e.to_string().contains(want), "{e}\n  wanted: {want}");
        assert!(e.to_string().starts_with("m.gltf: "), "{e}");
    }
    // A cycle in the node tree.
    let cyc = doc(&good, 3, "").replace(
        r#""nodes": [{"mesh": 0, "translation": [0, 0, -5]}]"#,
        r#""nodes": [{"mesh": 0, "children": [1]}, {"children": [0]}]"#,
    );
    let e = parse(&cyc).unwrap_err();
    assert!(!e.to_string().is_empty());
    // JSON errors have a line and column.
    let e = parse("{\n  \"asset\": [}").unwrap_err();
    assert_eq!(e.line, 2, "{e}");
    for junk in [
        &b"glTF\x02\0\0\0\xff\xff\xff\xff"[..],
        b"",
        b"\0\0\0",
        b"glTF",
    ] {
        assert!(parse_gltf(junk, Path::new("m.glb"), &mut |_| Ok(vec![])).is_err());
    }
}

#[test]
fn uris_resolve_inside_the_folder_only() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    assert!(resolve_uri(d, "a/b.bin").is_ok());
    assert!(resolve_uri(d, "./b.bin").is_ok());
    for bad in [
        "../b.bin",
        "a/../../b.bin",
        "/b.bin",
        "C:\\b.bin",
        "",
        "x:y",
    ] {
        assert!(resolve_uri(d, bad).is_err(), "{bad}");
    }
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("/etc", d.join("out")).unwrap();
        assert!(resolve_uri(d, "out/passwd").is_err());
    }
    assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
    assert!(percent_decode("a%2").is_err());
}

proptest::proptest! {
    /// Arbitrary bytes, or a valid document with bytes changed, never
    /// make the reader panic.
    #[test]
    fn arbitrary_documents_are_safe(
        edits in proptest::collection::vec((0usize..2000, proptest::prelude::any::<u8>()), 0..6),
    ) {
        let mut src = doc(&data_uri(&buffer()), 3, "").into_bytes();
        for (at, b) in edits {
            let n = src.len();
            src[at % n] = b;
        }
        let _ = parse_gltf(&src, Path::new("m.gltf"), &mut |_| Ok(vec![0; 64]));
        let g = glb(&src);
        let _ = parse_gltf(&g, Path::new("m.glb"), &mut |_| Ok(vec![]));
    }
}

fn glb(json: &[u8]) -> Vec<u8> {
    let mut j = json.to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((12 + 8 + j.len() as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(j);
    out
}
