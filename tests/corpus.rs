//! The malformed-input corpus (`tests/malformed/`) and the tolerated-layout corpus
//! (`tests/tolerated/`), run through every tool that reads a graph (`pgo::cli::commands()`).
//!
//! Malformed: each file gives `PATH:LINE:COL: error: MESSAGE` (the line, column and message of
//! `tests/malformed/cases.tsv`, counted by hand), one line on stderr, nothing on stdout, exit
//! status 2, and an existing output file is left untouched and no other file appears.
//!
//! Tolerated (decided by docs/formats.md §7.1 and README "Lenient about layout, strict about values"):
//! CRLF, tabs and runs of spaces, a UTF-8 BOM, no final newline, comments (whole-line and
//! trailing), blank lines, vertices after edges, FIX first, other spellings of the same numbers
//! (`+1`, `.5`, `1E0`, `7.`, leading zeros in ids), unknown tags (warning), EQUIV with
//! `--ignore-equiv` (warning; without it an error, in the malformed corpus), TORO
//! tags and a TORO file holding g2o-order information (read in g2o order with a warning, like
//! GTSAM's w20000.txt). Each is the graph of `clean.g2o`, so every tool must exit as on
//! `clean.g2o` and write the same bytes, with exactly the warnings listed.

mod common;

use common::{Dir, Tool, input_tools, run_tool, s, text};
use std::path::{Path, PathBuf};

fn corpus(dir: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join(dir)
}

/// The rows of a `cases.tsv`: tab-separated fields, `#` lines are comments.
fn table(dir: &str) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(corpus(dir).join("cases.tsv")).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| l.split('\t').map(str::to_string).collect())
        .collect()
}

fn flags(field: &str) -> Vec<&str> {
    if field == "-" {
        vec![]
    } else {
        field.split(' ').collect()
    }
}

/// Every file of a corpus directory is listed in its table, and every row names a file.
fn assert_table_complete(dir: &str, rows: &[Vec<String>], extra: &[&str]) {
    let mut files: Vec<String> = std::fs::read_dir(corpus(dir))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "cases.tsv" && !extra.contains(&n.as_str()))
        .collect();
    files.sort();
    let mut listed: Vec<String> = rows.iter().map(|r| r[0].clone()).collect();
    listed.sort();
    assert_eq!(files, listed, "{dir}/cases.tsv and the files beside it");
}

#[test]
fn every_malformed_input_is_an_error_at_its_place_from_every_tool() {
    let rows = table("malformed");
    assert_table_complete("malformed", &rows, &[]);
    assert!(rows.len() >= 40, "{}", rows.len());
    let tools = input_tools();
    for row in &rows {
        let [name, flag_field, at, message] = &row[..] else {
            panic!("malformed/cases.tsv: bad row {row:?}");
        };
        let content = std::fs::read(corpus("malformed").join(name)).unwrap();
        for tool in &tools {
            let dir = Dir::new();
            let input = dir.file(name, &content);
            // The output's extension is the input's, so that no tool converts formats.
            let output = dir.file(&format!("out-{name}"), b"precious\n");
            let out = run_tool(tool, &input, Some(&output), &flags(flag_field));
            let err = text(&out.stderr);
            let what = format!("{} {name}", tool.name);
            assert_eq!(out.status.code(), Some(2), "{what}: {err}");
            assert_eq!(
                err,
                format!("{}:{at}: error: {message}\n", s(&input)),
                "{what}"
            );
            assert!(out.stdout.is_empty(), "{what}: {}", text(&out.stdout));
            assert_eq!(std::fs::read(&output).unwrap(), b"precious\n", "{what}");
            let mut want = vec![name.clone(), format!("out-{name}")];
            want.sort();
            assert_eq!(dir.entries(), want, "{what}");

            // The same on stdin (the format then comes from the tags).
            let mut args: Vec<&str> = vec!["-"; tool.inputs];
            args.extend(flags(flag_field));
            let out = common::run_with_stdin(&tool.name, &args, Some(&content));
            assert_eq!(out.status.code(), Some(2), "{what} on stdin");
            assert_eq!(
                text(&out.stderr),
                format!("<stdin>:{at}: error: {message}\n"),
                "{what} on stdin"
            );
            assert!(out.stdout.is_empty(), "{what} on stdin");
        }
    }
}

/// The first line of `content` whose tag is a 3D tag the planar reader stops at, and the tag.
fn first_3d_tag(content: &[u8]) -> (usize, String) {
    let text = String::from_utf8_lossy(content);
    text.lines()
        .enumerate()
        .find_map(|(k, l)| {
            let tag = l.split_whitespace().next()?;
            [
                "VERTEX_SE3:QUAT",
                "EDGE_SE3:QUAT",
                "VERTEX3",
                "EDGE3",
                "VERTEX_TRACKXYZ",
            ]
            .contains(&tag)
            .then(|| (k + 1, tag.to_string()))
        })
        .unwrap()
}

/// The malformed 3D corpus (`tests/malformed3d/`): the tools that read 3D files (pgo-convert,
/// pgo-solve, pgo-certify) report each at the place and with the message of
/// `tests/malformed3d/cases.tsv`; every other tool refuses it at its first 3D tag (it handles
/// planar graphs only). Status 2, one line on
/// stderr, nothing on stdout, an existing output left untouched.
#[test]
fn every_malformed_3d_input_is_an_error_at_its_place() {
    let rows = table("malformed3d");
    assert_table_complete("malformed3d", &rows, &[]);
    assert!(rows.len() >= 12, "{}", rows.len());
    for row in &rows {
        let [name, flag_field, at, message] = &row[..] else {
            panic!("malformed3d/cases.tsv: bad row {row:?}");
        };
        let content = std::fs::read(corpus("malformed3d").join(name)).unwrap();
        for tool in input_tools() {
            let dir = Dir::new();
            let input = dir.file(name, &content);
            let output = dir.file(&format!("out-{name}"), b"precious\n");
            let out = run_tool(&tool, &input, Some(&output), &flags(flag_field));
            let what = format!("{} {name}", tool.name);
            let expected = if [
                "pgo-convert",
                "pgo-solve",
                "pgo-certify",
                "pgo-spectrum",
                "pgo-eval",
            ]
            .contains(&tool.name.as_str())
            {
                format!("{}:{at}: error: {message}\n", s(&input))
            } else {
                let (line, tag) = first_3d_tag(&content);
                format!(
                    "{}:{line}:1: error: 3D pose graph (tag {tag}): this tool handles planar SE(2) graphs only (pgo-solve and pgo-certify solve and certify 3D files, pgo-spectrum prints their spectra, pgo-eval compares them; pgo-convert reads, writes and describes them)\n",
                    s(&input)
                )
            };
            assert_eq!(out.status.code(), Some(2), "{what}");
            assert_eq!(text(&out.stderr), expected, "{what}");
            assert!(out.stdout.is_empty(), "{what}");
            assert_eq!(std::fs::read(&output).unwrap(), b"precious\n", "{what}");
        }
    }
}

/// Files that cannot be read or written: a missing input, a directory, an output in a missing
/// directory. Every tool: status 2, one line naming the path, nothing written.
#[test]
fn unreadable_inputs_and_unwritable_outputs_are_errors_from_every_tool() {
    let clean = std::fs::read(corpus("tolerated").join("clean.g2o")).unwrap();
    for tool in input_tools() {
        let dir = Dir::new();
        let input = dir.file("in.g2o", &clean);
        let missing = dir.path("missing.g2o");
        let cases = [
            (
                missing.clone(),
                dir.path("out.g2o"),
                s(&missing).to_string(),
            ),
            (
                dir.0.path().to_path_buf(),
                dir.path("out.g2o"),
                s(dir.0.path()).to_string(),
            ),
            (
                input.clone(),
                dir.path("no/such/dir/out.g2o"),
                "no/such/dir/out.g2o".into(),
            ),
        ];
        for (input_path, output, named) in cases {
            if !tool.writes && output.ends_with("no/such/dir/out.g2o") {
                continue;
            }
            let out = run_tool(&tool, &input_path, Some(&output), &[]);
            let err = text(&out.stderr);
            let what = format!("{} {}", tool.name, input_path.display());
            assert_eq!(out.status.code(), Some(2), "{what}: {err}");
            assert_eq!(err.lines().count(), 1, "{what}: {err}");
            assert!(
                err.starts_with(&format!("{}: error: ", tool.name)),
                "{what}: {err}"
            );
            assert!(err.contains(&named), "{what}: {err}");
            assert_eq!(dir.entries(), ["in.g2o"], "{what}");
        }
    }
}

/// A tool's run on one input: exit status, stdout, the output file, the warnings on stderr.
struct Run {
    code: Option<i32>,
    stdout: Vec<u8>,
    written: Option<Vec<u8>>,
    warnings: Vec<String>,
}

fn run_on(tool: &Tool, name: &str, content: &[u8], extra: &[&str]) -> Run {
    let dir = Dir::new();
    let input = dir.file(name, content);
    let output = dir.path("out.g2o");
    // Deterministic reports: no timings where the tool prints them.
    let mut flags = extra.to_vec();
    if tool.name == "pgo-solve" {
        flags.push("--no-timings");
    }
    let out = run_tool(tool, &input, Some(&output), &flags);
    let prefix = format!("{}:", s(&input));
    let warnings = text(&out.stderr)
        .lines()
        .filter(|l| l.contains(": warning: "))
        .map(|l| {
            l.strip_prefix(&prefix)
                .unwrap_or_else(|| panic!("{l}"))
                .to_string()
        })
        .collect();
    Run {
        code: out.status.code(),
        stdout: out.stdout,
        written: std::fs::read(&output).ok(),
        warnings,
    }
}

#[test]
fn tolerated_layouts_give_the_same_result_as_the_clean_file_from_every_tool() {
    let rows = table("tolerated");
    assert_table_complete("tolerated", &rows, &["clean.g2o"]);
    let clean = std::fs::read(corpus("tolerated").join("clean.g2o")).unwrap();
    for tool in input_tools() {
        let reference = run_on(&tool, "clean.g2o", &clean, &[]);
        // Exit 1 is a verdict, not an error: pgo-certify on vertices that are not optimal.
        let expected = if tool.name == "pgo-certify" { 1 } else { 0 };
        assert_eq!(reference.code, Some(expected), "{}", tool.name);
        assert!(reference.warnings.is_empty());
        for row in &rows {
            let (name, warnings, extra) = match &row[..] {
                [name, warnings] => (name, warnings, vec![]),
                [name, warnings, extra] => (name, warnings, flags(extra)),
                _ => panic!("tolerated/cases.tsv: bad row {row:?}"),
            };
            let content = std::fs::read(corpus("tolerated").join(name)).unwrap();
            let run = run_on(&tool, name, &content, &extra);
            let what = format!("{} {name}", tool.name);
            assert_eq!(run.code, reference.code, "{what}");
            assert_eq!(text(&run.stdout), text(&reference.stdout), "{what}");
            assert_eq!(run.written, reference.written, "{what}");
            let want: Vec<String> = match warnings.as_str() {
                "-" => vec![],
                w => w.split(" ;; ").map(str::to_string).collect(),
            };
            assert_eq!(run.warnings, want, "{what}");
        }
    }
}
