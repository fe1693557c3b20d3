//! The one-way rule of ARCHITECTURE.md, held against the code: every `crate::ROOM` path in the
//! code of a room (comments left out) names a room on a lower floor, and the files of one room
//! do not import each other in a loop.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The floors of ARCHITECTURE.md, bottom first: a room may use only rooms on lower floors.
const FLOORS: &[&[&str]] = &[
    // The file layer (pgo-io, re-exported as crate::graph, graph3, io, stats and vertigo) and the
    // leaves.
    &["graph", "graph3", "progress", "vertigo"],
    &["error"],
    &["io"],
    &["stats"],
    &["linalg"],
    &["problem", "simulate", "eval"],
    &["certify"],
    &["staircase", "dual", "refine", "se3"],
    &["spectrum"],
    &["solve", "viz"],
    &["robust"],
    &["cli"],
];

fn floor(room: &str) -> Option<usize> {
    FLOORS.iter().position(|f| f.contains(&room))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The code of a file without its comments (line comments and doc comments).
fn code(path: &Path) -> String {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| match l.find("//") {
            Some(k) => &l[..k],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every identifier that follows `prefix` in `text`.
fn paths_after<'a>(text: &'a str, prefix: &str) -> Vec<&'a str> {
    text.match_indices(prefix)
        .filter(|(k, _)| {
            // A whole word: not `foocrate::`.
            *k == 0
                || !text.as_bytes()[k - 1].is_ascii_alphanumeric() && text.as_bytes()[k - 1] != b'_'
        })
        .map(|(k, _)| {
            let rest = &text[k + prefix.len()..];
            let end = rest
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(rest.len());
            &rest[..end]
        })
        .filter(|s| !s.is_empty())
        .collect()
}

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The room of a file under src/: its folder, or its stem for a file at the top.
fn room(file: &Path) -> String {
    let rel = file.strip_prefix(src()).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

#[test]
fn every_import_goes_down_a_floor() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut violations = Vec::new();
    let mut unknown = BTreeSet::new();
    for file in &files {
        let from = room(file);
        if from == "lib" || from == "bin" {
            continue;
        }
        let Some(f) = floor(&from) else {
            unknown.insert(from);
            continue;
        };
        for to in paths_after(&code(file), "crate::") {
            if to == from || matches!(to, "Result" | "Error") {
                continue;
            }
            match floor(to) {
                Some(t) if t < f => {}
                Some(_) => violations.push(format!("{} uses crate::{to}", file.display())),
                None => {
                    unknown.insert(to.to_string());
                }
            }
        }
    }
    assert!(unknown.is_empty(), "rooms not on any floor: {unknown:?}");
    assert!(
        violations.is_empty(),
        "imports that do not go down:\n{}",
        violations.join("\n")
    );
}

#[test]
fn the_files_of_a_room_import_each_other_in_no_loop() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    // Edges between the files of one folder: `crate::ROOM::FILE` and `super::FILE`.
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for file in &files {
        let rel = file.strip_prefix(src()).unwrap();
        if rel.components().count() != 2 {
            continue;
        }
        let folder = room(file);
        let stem = file.file_stem().unwrap().to_string_lossy().to_string();
        let text = code(file);
        let mut targets: Vec<&str> = paths_after(&text, &format!("crate::{folder}::"));
        if stem != "mod" {
            targets.extend(paths_after(&text, "super::"));
        } else {
            targets.extend(paths_after(&text, "self::"));
        }
        let node = format!("{folder}/{stem}");
        for t in targets {
            if src().join(&folder).join(format!("{t}.rs")).exists() && t != stem {
                edges
                    .entry(node.clone())
                    .or_default()
                    .insert(format!("{folder}/{t}"));
            }
        }
    }
    // Depth-first search for a back edge.
    fn visit(
        n: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for m in edges.get(n).into_iter().flatten() {
            match state.get(m.as_str()) {
                Some(1) => {
                    let k = stack.iter().position(|s| s == m).unwrap();
                    return Some(stack[k..].to_vec());
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(m, edges, state, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in edges.keys() {
        if !state.contains_key(n.as_str())
            && let Some(cycle) = visit(n, &edges, &mut state, &mut Vec::new())
        {
            panic!("files import each other in a loop: {}", cycle.join(" -> "));
        }
    }
}
