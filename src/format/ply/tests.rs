//! The PLY reader's unit tests.

use super::*;

fn parse(src: &[u8]) -> Result<Mesh, ParseError> {
    parse_ply(src, Path::new("m.ply"))
}

/// A square (two fanned triangles) and a triangle, with normals, in
/// ASCII.
const ASCII: &str = "ply\nformat ascii 1.0\ncomment made by hand\n\
    element vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
    property float nx\nproperty float ny\nproperty float nz\n\
    property uchar red\nproperty uchar green\nproperty uchar blue\n\
    element face 2\nproperty list uchar int vertex_indices\nend_header\n\
    0 0 0 0 0 1 255 0 0\n1 0 0 0 0 1 0 255 0\n1 1 0 0 0 1 0 0 255\n\
    0 1 0 0 0 1 0 0 0\n0.5 0.5 1e-3 0 0 1 1 2 3\n\
    4 0 1 2 3\n3 0 2 4\n";

/// The same mesh in binary, little- or big-endian.
fn binary(big: bool) -> Vec<u8> {
    let order = if big { "big" } else { "little" };
    let mut out = ASCII
        .replace("format ascii", &format!("format binary_{order}_endian"))
        .split("end_header\n")
        .next()
        .unwrap()
        .to_owned()
        .into_bytes();
    out.extend_from_slice(b"end_header\n");
    let f = |out: &mut Vec<u8>, x: f32| {
        out.extend_from_slice(&if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        })
    };
    let i = |out: &mut Vec<u8>, x: i32| {
        out.extend_from_slice(&if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        })
    };
    let body = ASCII.split("end_header\n").nth(1).unwrap();
    let lines: Vec<&str> = body.lines().collect();
    for l in &lines[..5] {
        let w: Vec<&str> = l.split(' ').collect();
        for x in &w[..6] {
            f(&mut out, x.parse().unwrap());
        }
        for x in &w[6..] {
            out.push(x.parse().unwrap());
        }
    }
    for l in &lines[5..] {
        let w: Vec<i32> = l.split(' ').map(|x| x.parse().unwrap()).collect();
        out.push(w[0] as u8);
        for &x in &w[1..] {
            i(&mut out, x);
        }
    }
    out
}

#[test]
fn ascii_and_both_binaries_read_the_same_mesh() {
    let a = parse(ASCII.as_bytes()).unwrap();
    assert_eq!(a.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 2, 4]]);
    assert_eq!(a.positions[4], Vec3::new(0.5, 0.5, 1e-3));
    assert_eq!(a.normals, vec![Vec3::Z; 5]);
    assert_eq!(a.colors[0], Vec3::X);
    assert_eq!(a.colors[4], Vec3::new(1.0, 2.0, 3.0) / 255.0);
    for big in [false, true] {
        assert_eq!(parse(&binary(big)).unwrap(), a, "big-endian: {big}");
    }
}

#[test]
fn same_triangles_as_the_obj_reader() {
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1e-3\nf 1 2 3 4\nf 1 3 5\n";
    let o = super::super::obj::load_obj_from_bytes(obj.as_bytes(), Path::new("m.obj")).unwrap();
    let p = parse(ASCII.as_bytes()).unwrap();
    assert_eq!((o.positions, o.triangles), (p.positions, p.triangles));
}

#[test]
fn other_elements_and_properties_are_skipped() {
    let mut src = b"ply\nformat binary_little_endian 1.0\nelement range_grid 2\n\
        property list uchar int vertex_indices\nelement vertex 3\nproperty double x\n\
        property double y\nproperty double z\nproperty float confidence\n\
        element face 1\nproperty uchar flags\nproperty list uint8 uint32 vertex_index\n\
        end_header\n"
        .to_vec();
    src.extend_from_slice(&[2, 1, 0, 0, 0, 2, 0, 0, 0, 0]);
    for p in [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in p {
            src.extend_from_slice(&x.to_le_bytes());
        }
        src.extend_from_slice(&0.5f32.to_le_bytes());
    }
    src.extend_from_slice(&[7, 3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
    let m = parse(&src).unwrap();
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
    assert_eq!(m.positions[2], Vec3::Y);
    assert!(m.normals.is_empty() && m.colors.is_empty());
}

#[test]
fn triangle_strips_keep_one_orientation() {
    let src = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n\
        property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n\
        0 0 0\n0 1 0\n1 0 0\n1 1 0\n2 0 0\n6 0 2 1 3 -1 4\n";
    let m = parse(src.as_bytes()).unwrap();
    assert_eq!(m.triangles, vec![[0, 2, 1], [1, 2, 3]]);
    // Both face the same way.
    let n = |t: [u32; 3]| {
        let p = t.map(|i| m.positions[i as usize]);
        (p[1] - p[0]).cross(p[2] - p[0]).z
    };
    assert!(n(m.triangles[0]) > 0.0 && n(m.triangles[1]) > 0.0);
}

#[test]
fn ascii_errors_have_line_and_column() {
    let bad = ASCII.replace("1 1 0 0 0 1 0 0 255", "1 x 0 0 0 1 0 0 255");
    let e = parse(bad.as_bytes()).unwrap_err();
    assert_eq!((e.line, e.col), (19, 3), "{e}");
    assert!(e.to_string().contains("vertex 2 of 5"), "{e}");
    assert_eq!(e.source_line.as_deref(), Some("1 x 0 0 0 1 0 0 255"));
    let bad = ASCII.replace("3 0 2 4", "3 0 2 5");
    let e = parse(bad.as_bytes()).unwrap_err();
    assert_eq!((e.line, e.col), (23, 1), "{e}");
    assert!(
        e.to_string().contains("from 0 to 4, found 5 in face 1"),
        "{e}"
    );
    let e = parse(
        ASCII
            .replace("property float y\n", "property flot y\n")
            .as_bytes(),
    )
    .unwrap_err();
    assert_eq!((e.line, e.col), (6, 10), "{e}");
    let e = parse(&ASCII.as_bytes()[..ASCII.len() - 4]).unwrap_err();
    assert!(e.to_string().contains("end of file"), "{e}");
}

#[test]
fn binary_errors_name_the_byte_offset() {
    let mut b = binary(false);
    let header = b.len() - (5 * 27 + 2 + 4 * 4 + 3 * 4);
    // Face 1's last index (the file's last 4 bytes) out of range.
    let n = b.len();
    b[n - 4..].copy_from_slice(&9i32.to_le_bytes());
    let e = parse(&b).unwrap_err();
    let face1 = header + 5 * 27 + 17;
    assert!(
        e.to_string()
            .contains(&format!("found 9 in face 1 at byte {face1}")),
        "{e}"
    );
    // Truncated: the last face loses its last byte.
    let b = binary(true);
    let e = parse(&b[..b.len() - 1]).unwrap_err();
    assert!(e.to_string().contains("face 1 of 2"), "{e}");
    assert!(
        e.to_string()
            .contains(&format!("end of file at byte {}", b.len() - 4)),
        "{e}"
    );
}

#[test]
fn hostile_counts_are_refused_before_allocating() {
    for count in ["4294967296", "18446744073709551615", "1000000"] {
        let src = ASCII.replace("element vertex 5", &format!("element vertex {count}"));
        let e = parse(src.as_bytes()).unwrap_err();
        assert_eq!(e.line, 4, "{e}");
        assert!(e.expected.contains("counts the file can hold"), "{e}");
    }
    let src = ASCII.replace("element face 2", "element face 99999999999");
    assert_eq!(parse(src.as_bytes()).unwrap_err().line, 14);
    // A last face claiming 255 corners.
    let mut b = binary(false);
    let n = b.len();
    b[n - 13] = 255;
    let e = parse(&b).unwrap_err();
    assert!(e.to_string().contains("end of file"), "{e}");
}

#[test]
fn not_a_ply_file() {
    for (src, found) in [
        ("hello\n", "'hello' at the start"),
        ("ply\nformat ascii 1.0\n", "no 'end_header' line"),
        ("", "'' at the start"),
    ] {
        let e = parse(src.as_bytes()).unwrap_err();
        assert_eq!(e.found, found, "{e}");
    }
    let e = parse(
        ASCII
            .replace("element face 2", "element face 0")
            .split("4 0 1")
            .next()
            .unwrap()
            .as_bytes(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("5 vertices and no faces"), "{e}");
}

proptest::proptest! {
    /// Whatever the bytes after a plausible header, reading never panics,
    /// and an accepted mesh has finite positions and in-range indices.
    #[test]
    fn arbitrary_bodies_are_safe(
        body in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..200),
        big in proptest::prelude::any::<bool>(),
        ascii in proptest::prelude::any::<bool>(),
    ) {
        let head = if ascii { ASCII.to_owned() } else { String::from_utf8_lossy(&binary(big)).into_owned() };
        let mut src = head.split("end_header\n").next().unwrap().as_bytes().to_vec();
        src.extend_from_slice(b"end_header\n");
        src.extend_from_slice(&body);
        if let Ok(m) = parse(&src) {
            proptest::prop_assert!(m.positions.iter().all(|p| p.is_finite()));
            let n = m.positions.len();
            proptest::prop_assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < n));
        }
    }
}
