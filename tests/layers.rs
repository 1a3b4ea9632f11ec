//! The library's layer order, enforced: every reference from one top-level
//! module of `src/` to another (`use crate::…` lines, including grouped
//! `use crate::{a, b}`, and qualified paths `crate::x::…` in code, test code
//! included; comments are skipped) must point to a lower layer.
//!
//! The order is read from ARCHITECTURE.md itself (the first fenced block
//! under "## Layers": one layer a line, the top first, peers on one line), so
//! the document and the check cannot drift apart. Every module `lib.rs`
//! declares must be placed in it. The binaries (`src/bin/`) sit above all.

use std::collections::BTreeMap;
use std::path::Path;

/// Imports against the order that are known and being removed, as
/// (importer, imported). Keep this list small and explicit (empty today).
const KNOWN_EXCEPTIONS: &[(&str, &str)] = &[];

/// The layers of ARCHITECTURE.md, top first.
fn layers(text: &str) -> Vec<Vec<String>> {
    let mut lines = text.lines().skip_while(|l| !l.starts_with("## Layers"));
    lines.find(|l| l.trim_start().starts_with("```"));
    lines
        .take_while(|l| !l.trim_start().starts_with("```"))
        .map(|l| l.split('#').next().unwrap_or(""))
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(str::to_string).collect())
        .collect()
}

/// Module -> rank (0 the bottom layer).
fn ranks(layers: &[Vec<String>]) -> BTreeMap<String, usize> {
    let n = layers.len();
    let mut r = BTreeMap::new();
    for (i, layer) in layers.iter().enumerate() {
        for m in layer {
            assert!(
                r.insert(m.clone(), n - 1 - i).is_none(),
                "ARCHITECTURE.md places `{m}` twice"
            );
        }
    }
    r
}

/// The top-level modules `src/lib.rs` declares.
fn declared_modules(lib: &str) -> Vec<String> {
    lib.lines()
        .filter_map(|l| {
            let l = l.split("//").next().unwrap_or("").trim();
            let rest = l.strip_prefix("pub ").unwrap_or(l);
            let rest = rest.strip_prefix("pub(crate) ").unwrap_or(rest);
            let name = rest.strip_prefix("mod ")?.strip_suffix(';')?;
            Some(name.trim().to_string())
        })
        .collect()
}

/// One reference from a file of one module to another module.
#[derive(Debug)]
struct Edge {
    from: String,
    to: String,
    at: String,
}

/// The top-level modules a piece of code refers to through `crate::`, with
/// the byte offset of each reference.
fn referenced(code: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = code[from..].find("crate::") {
        let at = from + i;
        from = at + "crate::".len();
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let rest = &code[from..];
        if let Some(group) = rest.strip_prefix('{') {
            out.extend(grouped_items(group).into_iter().map(|m| (at, m)));
        } else {
            let name = identifier(rest);
            if !name.is_empty() {
                out.push((at, name));
            }
        }
    }
    out
}

fn identifier(s: &str) -> String {
    s.chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

/// The first path segment of each item of a `{…}` group, up to its closing
/// brace (items of inner groups are below their first segment).
fn grouped_items(group: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut depth = 0;
    let mut item_start = true;
    let mut rest = group;
    while let Some(c) = rest.chars().next() {
        if depth == 0 && item_start && (c.is_alphanumeric() || c == '_') {
            let name = identifier(rest);
            rest = &rest[name.len()..];
            if name != "self" {
                out.push(name);
            }
            item_start = false;
            continue;
        }
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => break,
            '}' => depth -= 1,
            ',' if depth == 0 => item_start = true,
            _ => {}
        }
        rest = &rest[c.len_utf8()..];
    }
    out
}

/// `text` with every `//` comment blanked out (line breaks kept).
fn without_comments(text: &str) -> String {
    text.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

fn edges_in(dir: &Path, root: &Path, out: &mut Vec<Edge>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let rel = path.strip_prefix(root).unwrap();
        if path.is_dir() {
            if rel != Path::new("bin") {
                edges_in(&path, root, out);
            }
            continue;
        }
        if path.extension().is_none_or(|e| e != "rs") || rel == Path::new("lib.rs") {
            continue;
        }
        let first = rel.components().next().unwrap().as_os_str();
        let from = first.to_str().unwrap().trim_end_matches(".rs").to_string();
        let code = without_comments(&std::fs::read_to_string(&path).unwrap());
        for (at, to) in referenced(&code) {
            if to != from {
                let line = code[..at].matches('\n').count() + 1;
                out.push(Edge {
                    from: from.clone(),
                    to,
                    at: format!("src/{}:{line}", rel.display()),
                });
            }
        }
    }
}

/// The references of `src/` that go against the order, as messages.
fn violations(arch: &str, root: &Path, exceptions: &[(&str, &str)]) -> Vec<String> {
    let rank = ranks(&layers(arch));
    let lib = std::fs::read_to_string(root.join("lib.rs")).unwrap();
    let mut bad = Vec::new();
    for m in declared_modules(&lib) {
        if !rank.contains_key(&m) {
            bad.push(format!(
                "module `{m}` is not placed in ARCHITECTURE.md's layers"
            ));
        }
    }
    let mut edges = Vec::new();
    edges_in(root, root, &mut edges);
    for e in &edges {
        let (Some(&f), Some(&t)) = (rank.get(&e.from), rank.get(&e.to)) else {
            continue; // unplaced modules are reported above
        };
        if t >= f && !exceptions.contains(&(e.from.as_str(), e.to.as_str())) {
            let how = if t == f { "a peer" } else { "an upper layer" };
            bad.push(format!(
                "{}: `{}` refers to `{}`, {how}",
                e.at, e.from, e.to
            ));
        }
    }
    for &(from, to) in exceptions {
        if !edges.iter().any(|e| e.from == from && e.to == to) {
            println!("note: the known exception {from} -> {to} is no longer needed: remove it");
        }
    }
    bad
}

#[test]
fn every_import_points_down_the_documented_layers() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let arch = std::fs::read_to_string(crate_dir.join("ARCHITECTURE.md")).unwrap();
    let order = layers(&arch);
    assert!(
        order.len() >= 5,
        "ARCHITECTURE.md's layer block was not found or is too short: {order:?}"
    );
    let bad = violations(&arch, &crate_dir.join("src"), KNOWN_EXCEPTIONS);
    assert!(
        bad.is_empty(),
        "imports against the layer order of ARCHITECTURE.md:\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_parser_sees_every_form_of_reference() {
    let names = |code: &str| -> Vec<String> {
        let code = without_comments(code);
        referenced(&code).into_iter().map(|(_, m)| m).collect()
    };
    assert_eq!(names("use crate::math::Vec3;"), ["math"]);
    assert_eq!(
        names("use crate::{math::Vec3, shape::{Shape, Sphere}, stats};"),
        ["math", "shape", "stats"]
    );
    assert_eq!(
        names("use crate::{\n    math::{\n        Vec3,\n    },\n    self,\n    shape::Shape,\n};"),
        ["math", "shape"]
    );
    assert_eq!(
        names("    let x = crate::accel::overlap::padded(&b, 1e-4);"),
        ["accel"]
    );
    assert_eq!(names("pub(in crate::shape) fn f() {}"), ["shape"]);
    assert!(names("use mycrate::math;").is_empty());
    assert!(names("/// see crate::render::Settings").is_empty());
    let arch = "# x\n## Layers\ntext\n```text\njob\nrender  # the loop\n\nmath stats\n```\n";
    assert_eq!(
        layers(arch),
        [vec!["job"], vec!["render"], vec!["math", "stats"]]
    );
}
