//! Reading an input file with bounds: only regular files and pipes, at most
//! [`limits::max_input_bytes`] of them, and an allocation failure becomes an
//! error instead of an abort.
//!
//! `std::fs::read` of `/dev/zero` never ends (it grows its buffer until the
//! process dies), and a 100 GB file would be read whole before the parser saw
//! a byte of it.

use crate::limits;
use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

/// Reads `path` whole, within the memory available now.
pub(crate) fn read_input(path: &Path) -> io::Result<Vec<u8>> {
    let available = limits::available_memory();
    read_with_limit(path, limits::max_input_bytes(available), available)
}

/// Reads `path` whole if it is a regular file or a pipe of at most `limit`
/// bytes; `available` is only quoted in the message.
pub(crate) fn read_with_limit(path: &Path, limit: u64, available: u64) -> io::Result<Vec<u8>> {
    let meta = std::fs::metadata(path)?;
    if let Some(kind) = refused_kind(&meta.file_type()) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("it is {kind}, not a regular file"),
        ));
    }
    let too_large = || {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "it is larger than the {} glint reads with {} of memory available \
                 (1/{} of it)",
                size(limit),
                size(available),
                limits::INPUT_MEMORY_FACTOR
            ),
        )
    };
    if meta.is_file() && meta.len() > limit {
        return Err(too_large());
    }
    let out_of_memory = |n: u64| {
        io::Error::new(
            io::ErrorKind::OutOfMemory,
            format!("out of memory reading {} of it", size(n)),
        )
    };
    let mut buf: Vec<u8> = Vec::new();
    // The size is only a hint: a file may grow, and pipes report 0.
    let hint = usize::try_from(meta.len().min(limit)).unwrap_or(0);
    buf.try_reserve(hint)
        .map_err(|_| out_of_memory(hint as u64))?;
    let mut reader = File::open(path)?.take(limit.saturating_add(1));
    let mut chunk = vec![0u8; 64 * 1024];
    loop {
        let n = match reader.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        // `try_reserve` grows geometrically, like `push`, but reports
        // failure (e.g. under `ulimit -v`) instead of aborting.
        buf.try_reserve(n)
            .map_err(|_| out_of_memory(buf.len() as u64 + n as u64))?;
        buf.extend_from_slice(&chunk[..n]);
    }
    if buf.len() as u64 > limit {
        return Err(too_large());
    }
    Ok(buf)
}

/// What kind of non-file `ft` is, if it is one glint refuses: devices
/// (`/dev/zero` would never end). Pipes are read, with the cap; a directory
/// fails to read with the system's own "Is a directory".
fn refused_kind(ft: &std::fs::FileType) -> Option<&'static str> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_char_device() {
            return Some("a character device");
        }
        if ft.is_block_device() {
            return Some("a block device");
        }
        if ft.is_socket() {
            return Some("a socket");
        }
    }
    None
}

/// A byte count for messages: `812 bytes`, `3.2 MiB`, `1.5 GiB`.
pub(crate) fn size(bytes: u64) -> String {
    const KIB: f64 = 1024.0;
    let b = bytes as f64;
    if b < KIB {
        format!("{bytes} bytes")
    } else if b < KIB * KIB {
        format!("{:.1} KiB", b / KIB)
    } else if b < KIB * KIB * KIB {
        format!("{:.1} MiB", b / (KIB * KIB))
    } else {
        format!("{:.1} GiB", b / (KIB * KIB * KIB))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_and_directories_are_refused_without_reading() {
        for (p, kind) in [("/dev/zero", "character device"), ("/", "Is a directory")] {
            let e = read_input(Path::new(p)).unwrap_err();
            assert!(e.to_string().contains(kind), "{p}: {e}");
        }
    }

    #[test]
    fn files_over_the_limit_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("big.txt");
        std::fs::write(&p, vec![b'x'; 1000]).unwrap();
        assert_eq!(read_with_limit(&p, 1000, 1 << 30).unwrap().len(), 1000);
        let e = read_with_limit(&p, 999, 20_000).unwrap_err();
        assert!(e.to_string().contains("larger than the 999 bytes"), "{e}");
        assert!(e.to_string().contains("19.5 KiB of memory"), "{e}");
    }

    #[test]
    fn sizes_read_naturally() {
        assert_eq!(size(812), "812 bytes");
        assert_eq!(size(3 << 20), "3.0 MiB");
        assert_eq!(size(3 << 30), "3.0 GiB");
    }
}
