//! High-dynamic-range output: `.exr` and `.pfm` keep linear, unclamped 32-bit
//! floats, the right way up, written through the same atomic path as the
//! 8-bit formats.

use crate::common;
use crate::common::scratch;
use glint::math::Vec3;
use glint::output::write_rgb;
use std::path::Path;

/// A 4x3 image whose top row is bright (above 1), whose left column is red,
/// with negative and tiny values too, and every pixel different.
fn pixels() -> (u32, u32, Vec<Vec3>) {
    let (w, h) = (4u32, 3u32);
    let mut px = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let base = Vec3::new(x as f32 * 0.25, y as f32 * 0.5, 1e-6 * (x + 1) as f32);
            let p = match (x, y) {
                (_, 0) => base + Vec3::new(7.5, 123.25, 1e4),
                (0, _) => Vec3::new(1.0, -0.5, 0.0) + base,
                _ => base,
            };
            px.push(p);
        }
    }
    (w, h, px)
}

/// Reads a PFM: header, then rows bottom to top; returns rows top first.
pub(crate) fn read_pfm(path: &Path) -> (u32, u32, Vec<Vec3>) {
    let bytes = std::fs::read(path).unwrap();
    // Three header lines, each ended by one newline.
    let mut ends = bytes.iter().enumerate().filter(|(_, b)| **b == b'\n');
    let header_end = ends.nth(2).unwrap().0 + 1;
    let header = std::str::from_utf8(&bytes[..header_end]).unwrap();
    let lines: Vec<&str> = header.lines().collect();
    assert_eq!(lines[0], "PF", "colour PFM");
    let dims: Vec<u32> = lines[1]
        .split_whitespace()
        .map(|s| s.parse().unwrap())
        .collect();
    let scale: f32 = lines[2].parse().unwrap();
    assert!(scale < 0.0, "little-endian data has a negative scale");
    let (w, h) = (dims[0], dims[1]);
    let data = &bytes[header_end..];
    assert_eq!(data.len(), (w * h * 12) as usize);
    let floats: Vec<f32> = data
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let bottom_up: Vec<Vec3> = floats
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    let top_down = bottom_up
        .chunks_exact(w as usize)
        .rev()
        .flatten()
        .copied()
        .collect();
    (w, h, top_down)
}

/// Reads an EXR's first RGB(A) layer with the `exr` crate; rows top first.
fn read_exr(path: &Path) -> (u32, u32, Vec<Vec3>) {
    let img = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![Vec3::ZERO; res.width() * res.height()]),
        |(w, px): &mut (usize, Vec<Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
        },
    )
    .unwrap();
    let size = img.layer_data.size;
    let (_, px) = img.layer_data.channel_data.pixels;
    (size.width() as u32, size.height() as u32, px)
}

#[test]
fn pfm_round_trips_exactly_and_is_bottom_up_on_disk() {
    let dir = scratch("pfm");
    let (w, h, px) = pixels();
    let path = dir.join("a.pfm");
    write_rgb(&path, w, h, &px).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.starts_with(b"PF\n4 3\n-1.0\n"));
    // The first pixel stored is the bottom-left one of the frame.
    let first = f32::from_le_bytes(bytes[12..16].try_into().unwrap());
    assert_eq!(first, px[(2 * w) as usize].x);
    let (rw, rh, back) = read_pfm(&path);
    assert_eq!((rw, rh), (w, h));
    assert_eq!(
        back, px,
        "every value, above 1 and below 0, is kept exactly"
    );
    // Top row of the frame is the top of the image.
    assert!(back[..w as usize].iter().all(|p| p.y > 100.0));
}

#[test]
fn exr_round_trips_as_32_bit_float_rgb() {
    let dir = scratch("exr");
    let (w, h, px) = pixels();
    let path = dir.join("a.exr");
    write_rgb(&path, w, h, &px).unwrap();
    let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
    let channels = &meta.headers[0].channels.list;
    let names: Vec<String> = channels.iter().map(|c| c.name.to_string()).collect();
    assert_eq!(names, ["B", "G", "R"], "RGB only, stored alphabetically");
    assert!(channels
        .iter()
        .all(|c| c.sample_type == exr::meta::attribute::SampleType::F32));
    let (rw, rh, back) = read_exr(&path);
    assert_eq!((rw, rh), (w, h));
    assert_eq!(back, px);
    assert!(back[..w as usize].iter().all(|p| p.x >= 7.5));
    assert!(back[w as usize..].iter().all(|p| p.x < 7.5));
}

#[test]
fn hdr_writes_replace_atomically_and_leave_no_temporary_file() {
    let dir = scratch("hdr-atomic");
    let (w, h, px) = pixels();
    for ext in ["exr", "pfm"] {
        let path = dir.join(format!("b.{ext}"));
        std::fs::write(&path, b"old").unwrap();
        // A size that does not match the pixels fails and keeps the old file.
        assert!(write_rgb(&path, w + 1, h, &px).is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        write_rgb(&path, w, h, &px).unwrap();
        assert_ne!(std::fs::read(&path).unwrap(), b"old");
    }
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
}

/// A rendered frame goes out unclamped: the file holds exactly the frame's
/// colour plane, including the values above 1 an 8-bit file would clip.
#[test]
fn rendered_frame_is_written_unclamped() {
    let dir = scratch("hdr-render");
    let scene = common::own_scene("whitted.txt");
    let mut job = glint::job::Job::new(scene, 24, 16);
    job.shading.shadows = true;
    job.shading.bounces = 3;
    job.shading.shade_back = true;
    job.set_output(glint::job::Output::Colour(dir.join("whitted.pfm")));
    let report = job.run().unwrap();
    let (_, _, pfm) = read_pfm(&dir.join("whitted.pfm"));
    assert_eq!(pfm, report.frame.color);
    job.set_output(glint::job::Output::Colour(dir.join("whitted.exr")));
    let report = job.run().unwrap();
    let (_, _, exr) = read_exr(&dir.join("whitted.exr"));
    assert_eq!(exr, report.frame.color);
    assert!(report.frame.color.iter().any(|c| c.max_element() > 1.0));
}
