//! Every image format glint writes, opened by readers other than the one that
//! wrote it: the `image` crate's decoders, small decoders written here from
//! the format specifications (which also check the header fields), the `exr`
//! crate's reader for OpenEXR, and Pillow when Python has it (`.ci/run`
//! installs it and sets `GLINT_REQUIRE_PILLOW=1`, so CI cannot skip it).

use crate::common::*;
use std::path::Path;
use std::process::Command;

const W: u32 = 41;
const H: u32 = 29;

/// Renders glint's Whitted scene into `dir/out.EXT` for every extension.
fn render_all(dir: &Path) {
    let scene = own_scene("whitted.txt");
    for ext in ["png", "tga", "ppm", "bmp", "exr", "pfm"] {
        let out = Command::new(env!("CARGO_BIN_EXE_glint"))
            .arg("render")
            .arg(&scene)
            .args(["-o", &format!("out.{ext}"), "--size"])
            .args([W.to_string(), H.to_string()])
            .args(["--shadows", "--bounces", "3", "--quiet"])
            .current_dir(dir)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{ext}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// A TGA decoder from the TGA 2.0 specification, for the files glint writes:
/// checks the header, and for run-length files that no packet crosses a row.
/// Returns RGB bytes, top row first.
fn decode_tga(bytes: &[u8]) -> Result<Vec<u8>, String> {
    let id_len = bytes[0] as usize;
    let (cmap_type, image_type) = (bytes[1], bytes[2]);
    let w = u16::from_le_bytes([bytes[12], bytes[13]]) as usize;
    let h = u16::from_le_bytes([bytes[14], bytes[15]]) as usize;
    let (bpp, descriptor) = (bytes[16], bytes[17]);
    if cmap_type != 0 || bpp != 24 {
        return Err(format!("colour map {cmap_type}, {bpp} bits per pixel"));
    }
    if (w, h) != (W as usize, H as usize) {
        return Err(format!("size {w}x{h}"));
    }
    let mut data = &bytes[18 + id_len..];
    let mut rows: Vec<Vec<u8>> = Vec::new();
    for _ in 0..h {
        let mut row = Vec::with_capacity(3 * w);
        match image_type {
            2 => {
                row.extend_from_slice(&data[..3 * w]);
                data = &data[3 * w..];
            }
            10 => {
                while row.len() < 3 * w {
                    let head = data[0] as usize;
                    let count = (head & 0x7f) + 1;
                    if row.len() + 3 * count > 3 * w {
                        return Err("a run-length packet crosses a scanline".into());
                    }
                    if head & 0x80 != 0 {
                        for _ in 0..count {
                            row.extend_from_slice(&data[1..4]);
                        }
                        data = &data[4..];
                    } else {
                        row.extend_from_slice(&data[1..1 + 3 * count]);
                        data = &data[1 + 3 * count..];
                    }
                }
            }
            t => return Err(format!("image type {t}")),
        }
        rows.push(row);
    }
    // Bit 5 of the descriptor: 0 = bottom-left origin (rows stored bottom-up).
    if descriptor & 0x20 == 0 {
        rows.reverse();
    }
    Ok(rows
        .concat()
        .chunks_exact(3)
        .flat_map(|bgr| [bgr[2], bgr[1], bgr[0]])
        .collect())
}

/// A binary PPM (`P6`) decoder from the Netpbm specification.
fn decode_ppm(bytes: &[u8]) -> Result<Vec<u8>, String> {
    if !bytes.starts_with(b"P6") {
        return Err(format!("magic {:?}", String::from_utf8_lossy(&bytes[..2])));
    }
    // Four whitespace-separated header fields, then exactly one whitespace byte.
    let mut fields = Vec::new();
    let mut i = 0;
    while fields.len() < 4 {
        while bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if bytes[i] == b'#' {
            while bytes[i] != b'\n' {
                i += 1;
            }
            continue;
        }
        let start = i;
        while !bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        fields.push(String::from_utf8_lossy(&bytes[start..i]).into_owned());
    }
    if fields[1..] != [W.to_string(), H.to_string(), "255".to_string()] {
        return Err(format!("header {fields:?}"));
    }
    let data = &bytes[i + 1..];
    if data.len() != (3 * W * H) as usize {
        return Err(format!("{} data bytes", data.len()));
    }
    Ok(data.to_vec())
}

/// A PFM decoder: `PF`, size, negative scale = little endian, rows bottom-up.
fn decode_pfm(bytes: &[u8]) -> Vec<f32> {
    let header = format!("PF\n{W} {H}\n-1.0\n");
    assert!(bytes.starts_with(header.as_bytes()));
    let floats: Vec<f32> = bytes[header.len()..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect();
    let row = 3 * W as usize;
    floats.chunks_exact(row).rev().flatten().copied().collect()
}

fn decode_with_image_crate(path: &Path) -> Vec<u8> {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
        .into_raw()
}

#[test]
fn every_format_opens_in_independent_readers_with_the_same_pixels() {
    let dir = scratch("formats");
    render_all(&dir);
    let png = decode_with_image_crate(&dir.join("out.png"));
    assert_eq!(png.len(), (3 * W * H) as usize);
    // A real picture, not a blank one.
    assert!(png.chunks_exact(3).any(|p| p != &png[..3]));

    let tga = std::fs::read(dir.join("out.tga")).unwrap();
    assert_eq!(decode_tga(&tga).unwrap(), png, "TGA (spec decoder)");
    let ppm = std::fs::read(dir.join("out.ppm")).unwrap();
    assert_eq!(decode_ppm(&ppm).unwrap(), png, "PPM (spec decoder)");
    for ext in ["tga", "ppm", "bmp"] {
        let path = dir.join(format!("out.{ext}"));
        assert_eq!(decode_with_image_crate(&path), png, "{ext} (image crate)");
    }

    // HDR: the exr crate's reader and a PFM decoder agree on the linear
    // values, and those values quantise to the 8-bit images' bytes.
    let pfm = decode_pfm(&std::fs::read(dir.join("out.pfm")).unwrap());
    let exr = exr::prelude::read_first_rgba_layer_from_file(
        dir.join("out.exr"),
        |size, _| vec![0f32; 3 * size.width() * size.height()],
        |px: &mut Vec<f32>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let i = 3 * (pos.y() * W as usize + pos.x());
            px[i..i + 3].copy_from_slice(&[r, g, b]);
        },
    )
    .unwrap();
    assert_eq!(exr.layer_data.channel_data.pixels, pfm, "EXR vs PFM values");
    let bytes: Vec<u8> = pfm.iter().map(|&c| glint::output::to_byte(c)).collect();
    assert_eq!(bytes, png, "float values quantise to the 8-bit pixels");
    assert!(pfm.iter().any(|&c| c > 1.0), "HDR keeps values above 1");

    pillow_reads_the_same_pixels(&dir, &png);
}

/// Pillow (if available) opens every 8-bit file with the same pixels.
fn pillow_reads_the_same_pixels(dir: &Path, png: &[u8]) {
    let script = "import sys\nfrom PIL import Image\nfor p in sys.argv[1:]:\n    \
                  im = Image.open(p); im.load()\n    \
                  open(p + '.raw', 'wb').write(im.convert('RGB').tobytes())\n";
    let files: Vec<String> = ["png", "tga", "ppm", "bmp"]
        .iter()
        .map(|e| dir.join(format!("out.{e}")).to_string_lossy().into_owned())
        .collect();
    let run = Command::new("python3")
        .args(["-c", script])
        .args(&files)
        .output();
    let required = std::env::var("GLINT_REQUIRE_PILLOW").is_ok_and(|v| v == "1");
    match run {
        Ok(out) if out.status.success() => {
            for f in &files {
                let raw = std::fs::read(format!("{f}.raw")).unwrap();
                assert!(raw == png, "{f}: Pillow reads different pixels");
            }
        }
        Ok(out)
            if !required && String::from_utf8_lossy(&out.stderr).contains("No module named") =>
        {
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "skipped the Pillow check: python3 has no PIL (set GLINT_REQUIRE_PILLOW=1 to require it)");
        }
        Err(e) if !required => {
            use std::io::Write;
            let _ = writeln!(
                std::io::stderr(),
                "skipped the Pillow check: no python3 ({e})"
            );
        }
        other => panic!("Pillow could not open glint's images: {other:?}"),
    }
}

#[test]
fn unsupported_extension_is_refused_before_any_work() {
    let dir = scratch("bad-ext");
    // A scene that does not exist: the output name is checked first.
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["render", "x.txt", "-o", "out.xyz"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("out.xyz"), "{err}");
    assert!(err.contains(".png, .tga, .ppm, .bmp, .exr, .pfm"), "{err}");
    // A real, large render: refused before it starts.
    let out = Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .arg("-input")
        .arg(own_scene("whitted.txt"))
        .args(["-size", "4000", "4000", "-bounces", "9", "-shadows"])
        .args(["-output", "fine.png", "-normals", "bad.jpeg"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("bad.jpeg"));
    assert!(!dir.join("fine.png").exists());
    // The same request with a scene that does not exist is refused for the
    // normals' name, not the scene: the names are checked before the scene
    // is read, let alone rendered. (The time a refusal takes is measured by
    // `scripts/bench-refusals.sh`, not asserted.)
    let out = Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args(["-input", "missing.txt"])
        .args(["-size", "4000", "4000", "-bounces", "9", "-shadows"])
        .args(["-output", "fine.png", "-normals", "bad.jpeg"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("bad.jpeg") && !err.contains("missing.txt"),
        "{err}"
    );
}
