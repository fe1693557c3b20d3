//! The `--rerun-*` flags of every tool, in the build at hand (with or without the cargo feature
//! `rerun`): they never change the other outputs, a failed save is exit status 2 and writes
//! nothing. The contents of recordings are checked by `tests/interop/test_rerun.py`, which reads
//! them back with rerun's own reader.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn toy() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("datasets/paper_toy.g2o")
}

/// Each tool with arguments that work on the toy graph (deterministic outputs).
fn cases() -> Vec<(&'static str, &'static str, Vec<String>)> {
    let toy = toy().display().to_string();
    let s = |v: &[&str]| v.iter().map(|a| a.to_string()).collect::<Vec<_>>();
    vec![
        (
            "pgo-convert",
            env!("CARGO_BIN_EXE_pgo-convert"),
            s(&["--stats", &toy]),
        ),
        (
            "pgo-solve",
            env!("CARGO_BIN_EXE_pgo-solve"),
            s(&[&toy, "--weights", "unit", "--json", "--no-timings"]),
        ),
        (
            "pgo-spectrum",
            env!("CARGO_BIN_EXE_pgo-spectrum"),
            s(&[&toy, "--weights", "unit", "-k", "3"]),
        ),
        (
            "pgo-simulate",
            env!("CARGO_BIN_EXE_pgo-simulate"),
            s(&["-n", "7", "--seed", "2"]),
        ),
    ]
}

fn run(exe: &str, args: &[String], extra: &[&str], dir: &Path) -> Output {
    Command::new(exe)
        .args(args)
        .args(extra)
        .current_dir(dir)
        .output()
        .unwrap()
}

fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_save_into_a_missing_directory_is_exit_2_before_any_output() {
    for (tool, exe, args) in cases() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("missing/x.rrd");
        let out = run(
            exe,
            &args,
            &["--rerun-save", target.to_str().unwrap()],
            dir.path(),
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{tool}: {stderr}");
        assert!(out.stdout.is_empty(), "{tool}");
        assert!(
            stderr.contains(&format!("{tool}: error: --rerun-save {}", target.display())),
            "{tool}: {stderr}"
        );
        assert!(files(dir.path()).is_empty(), "{tool}");
    }
}

#[cfg(feature = "rerun")]
#[test]
fn every_tool_saves_a_recording_and_its_outputs_do_not_change() {
    for (tool, exe, args) in cases() {
        let dir = tempfile::tempdir().unwrap();
        let plain = run(exe, &args, &[], dir.path());
        let recorded = run(exe, &args, &["--rerun-save", "r.rrd"], dir.path());
        assert_eq!(plain.status.code(), recorded.status.code(), "{tool}");
        assert_eq!(plain.stdout, recorded.stdout, "{tool}");
        assert_eq!(plain.stderr, recorded.stderr, "{tool}");
        let bytes = std::fs::read(dir.path().join("r.rrd")).unwrap();
        assert!(bytes.starts_with(b"RRF2"), "{tool}: not an .rrd file");
        assert_eq!(
            files(dir.path()),
            ["r.rrd"],
            "{tool}: no temporary file left"
        );
    }
}

#[cfg(not(feature = "rerun"))]
#[test]
fn without_the_feature_save_is_an_error_and_viewers_a_warning() {
    for (tool, exe, args) in cases() {
        let dir = tempfile::tempdir().unwrap();
        let saved = run(exe, &args, &["--rerun-save", "r.rrd"], dir.path());
        assert_eq!(saved.status.code(), Some(2), "{tool}");
        assert!(saved.stdout.is_empty(), "{tool}");
        assert!(
            String::from_utf8_lossy(&saved.stderr).contains("no rerun support"),
            "{tool}"
        );
        assert!(files(dir.path()).is_empty(), "{tool}");

        let plain = run(exe, &args, &[], dir.path());
        for flag in ["--rerun-connect", "--rerun-spawn"] {
            let out = run(exe, &args, &[flag], dir.path());
            assert_eq!(plain.status.code(), out.status.code(), "{tool} {flag}");
            assert_eq!(plain.stdout, out.stdout, "{tool} {flag}");
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(
                stderr.contains(&format!("{tool}: warning: {flag} ignored")),
                "{tool} {flag}: {stderr}"
            );
        }
    }
}
