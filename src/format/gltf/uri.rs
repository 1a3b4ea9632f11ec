//! Buffer URIs: `data:` URIs and relative paths that stay inside the
//! file's folder.

use crate::format::diagnostic::quote;
use std::path::{Component, Path, PathBuf};

/// The bytes of a buffer URI: a base64 `data:` URI, or a file read by
/// `external` (percent-decoded first).
pub(super) fn read_uri(
    uri: &str,
    external: &mut dyn FnMut(&str) -> Result<Vec<u8>, String>,
) -> Result<Vec<u8>, String> {
    use base64::Engine as _;
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, data) = rest
            .split_once(";base64,")
            .ok_or_else(|| "a data: URI that is not base64".to_owned())?;
        return base64::engine::general_purpose::STANDARD
            .decode(data.trim_end())
            .map_err(|e| format!("a data: URI with bad base64 ({e})"));
    }
    let path = percent_decode(uri)?;
    check_relative(&path)?;
    external(&path)
}

/// A relative path that stays inside its folder: no scheme, no root, no
/// `..`.
fn check_relative(uri: &str) -> Result<(), String> {
    let inside = !uri.is_empty()
        && !uri.contains(':')
        && !uri.starts_with('/')
        && !uri.starts_with('\\')
        && Path::new(uri)
            .components()
            .all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
    if inside {
        Ok(())
    } else {
        Err(format!("{} (a path outside the file's folder)", quote(uri)))
    }
}

/// `%XX` escapes decoded (URIs of files with spaces, etc.).
pub(super) fn percent_decode(uri: &str) -> Result<String, String> {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = b
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("{} (a bad %-escape)", quote(uri)))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| format!("{} (not UTF-8 once decoded)", quote(uri)))
}

/// The file a relative buffer URI names, which must lie inside `folder`.
pub(super) fn resolve_uri(folder: &Path, uri: &str) -> Result<PathBuf, String> {
    check_relative(uri)?;
    let p = folder.join(uri);
    // Symbolic links may still lead out.
    if let (Ok(base), Ok(real)) = (folder.canonicalize(), p.canonicalize()) {
        if !real.starts_with(&base) {
            return Err(format!("{} (leads outside the file's folder)", quote(uri)));
        }
    }
    Ok(p)
}
