//! Outputs as a user meets them on a bad day: an output that cannot be written is refused before
//! the input is even read; a write that fails at the end still leaves the report; an interrupt
//! (SIGINT, SIGTERM) while the output is written leaves no hidden temporary file and ends the
//! tool by that signal; a pipe closed by the reader (`| head`) ends it with status 141, silently;
//! and the progress display, forced with `--progress` (stderr is no terminal here), shows the
//! phases on stderr without changing a byte of stdout or of the files.

mod common;

use common::{Dir, bin, s, text};
use std::process::{Command, Stdio};

/// Files of `dir` whose name starts with `.pgo-` (the writers' temporary files).
fn temporaries(dir: &std::path::Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".pgo-"))
        .collect()
}

#[test]
fn an_unwritable_output_is_refused_before_the_input_is_read() {
    // The input is garbage: had it been read first, its error would be the one reported.
    let garbage = std::fs::read(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed/garbage.bin"),
    )
    .unwrap();
    let dir = Dir::new();
    let input = dir.file("in.bin", &garbage);
    let missing = dir.path("no/such/dir/out.g2o");
    let directory = dir.path("sub");
    std::fs::create_dir(&directory).unwrap();
    for (output, says) in [
        (s(&missing).to_string(), "directory"),
        (s(&directory).to_string(), "is a directory"),
        (format!("{}/", s(&directory)), "is a directory"),
    ] {
        for (tool, args) in [
            ("pgo-solve", vec![s(&input), "-o", &output]),
            ("pgo-solve", vec![s(&input), "--json", "-o", &output]),
            ("pgo-convert", vec![s(&input), "-o", &output]),
            ("pgo-simulate", vec!["-n", "5", "-o", &output]),
        ] {
            let out = common::run_with_stdin(tool, &args, None);
            let err = text(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{tool} {args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{tool} {args:?}: {err}");
            assert!(
                err.starts_with(&format!("{tool}: error: {output}: ")),
                "{tool} {args:?}: {err}"
            );
            assert!(err.contains(says), "{tool} {args:?}: {err}");
            assert!(
                !err.contains(".pgo-"),
                "{tool}: the temporary name shows: {err}"
            );
            assert!(out.stdout.is_empty(), "{tool} {args:?}");
        }
    }
    let mut left = dir.entries();
    left.sort();
    assert_eq!(left, ["in.bin", "sub"]);
    assert!(temporaries(dir.0.path()).is_empty());
}

#[cfg(target_os = "linux")]
#[test]
fn a_write_that_fails_at_the_end_keeps_the_report() {
    // /dev/full passes every check (a device is written in place) and fails the write with
    // ENOSPC: the report comes first, then the error naming the path, exit status 2.
    let toy = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/paper_toy.g2o");
    if !std::path::Path::new("/dev/full").exists() {
        eprintln!("no /dev/full: skipped");
        return;
    }
    let out = common::run_with_stdin(
        "pgo-solve",
        &[
            toy,
            "--weights",
            "unit",
            "--json",
            "--no-timings",
            "-o",
            "/dev/full",
        ],
        None,
    );
    assert_eq!(out.status.code(), Some(2));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(report["cost"].as_f64().unwrap() > 0.0, "{report}");
    assert_eq!(
        text(&out.stderr),
        "pgo-solve: error: /dev/full: No space left on device (os error 28)\n"
    );
    // The text report on stderr, then the error.
    let out = common::run_with_stdin(
        "pgo-solve",
        &[toy, "--weights", "unit", "--no-timings", "-o", "/dev/full"],
        None,
    );
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(err.contains("  lower bound "), "{err}");
    assert!(
        err.ends_with("pgo-solve: error: /dev/full: No space left on device (os error 28)\n"),
        "{err}"
    );
}

/// Runs `pgo-simulate` writing a large graph into `dir`, signals it as soon as its temporary
/// file holds data, and returns how it ended; `None` if it finished before the signal could be
/// sent (the caller tries a larger graph).
#[cfg(unix)]
fn interrupt_while_writing(
    dir: &std::path::Path,
    poses: usize,
    signal: i32,
) -> Option<std::process::ExitStatus> {
    use std::os::unix::process::CommandExt;
    let output = dir.join("big.g2o");
    let mut command = Command::new(bin("pgo-simulate"));
    command
        .args(["-n", &poses.to_string(), "--loop-probability", "0", "-q"])
        .arg("-o")
        .arg(&output)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    // The tool keeps a signal it inherits ignored (as `nohup` and `cmd &` in a script intend),
    // and a test run from a background job inherits SIGINT ignored: started here as from an
    // interactive shell, with the signal's default action.
    // SAFETY: signal(2) only, between fork and exec.
    unsafe {
        command.pre_exec(move || {
            libc::signal(signal, libc::SIG_DFL);
            Ok(())
        });
    }
    let mut child = command.spawn().unwrap();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "pgo-simulate failed");
            std::fs::remove_file(&output).unwrap();
            return None;
        }
        let writing = std::fs::read_dir(dir).unwrap().any(|e| {
            let e = e.unwrap();
            e.file_name().to_string_lossy().starts_with(".pgo-")
                && e.metadata().is_ok_and(|m| m.len() > 0)
        });
        if writing {
            // SAFETY: kill(2) on our own child's pid.
            assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
            return Some(child.wait().unwrap());
        }
        std::thread::yield_now();
    }
}

#[cfg(unix)]
#[test]
fn an_interrupt_while_writing_leaves_no_temporary_file() {
    use std::os::unix::process::ExitStatusExt;
    for signal in [libc::SIGINT, libc::SIGTERM] {
        let dir = Dir::new();
        let mut poses = 200_000;
        let status = loop {
            if let Some(status) = interrupt_while_writing(dir.0.path(), poses, signal) {
                break status;
            }
            // It finished first: a larger graph writes for longer.
            poses *= 2;
            assert!(poses <= 3_200_000, "never caught the write in progress");
        };
        // Ended by the signal itself (the shell shows 128 + signal: 130, 143).
        assert_eq!(status.signal(), Some(signal), "{status:?}");
        assert!(
            temporaries(dir.0.path()).is_empty(),
            "signal {signal}: {:?}",
            dir.entries()
        );
        // The output is either not there or complete (the signal came after the rename).
        let output = dir.path("big.g2o");
        if let Ok(written) = std::fs::read(&output) {
            assert_eq!(
                written.iter().filter(|&&c| c == b'\n').count(),
                2 * poses - 1
            );
        }
    }
}

#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_the_tool_with_status_141_silently() {
    use std::io::Read;
    let dir = Dir::new();
    let graph = dir.path("g.g2o");
    let made = Command::new(bin("pgo-simulate"))
        .args(["-n", "20000", "--loop-probability", "0", "-q", "-o"])
        .arg(&graph)
        .status()
        .unwrap();
    assert!(made.success());
    // Each writes megabytes to stdout; the reader takes a few bytes and closes the pipe.
    let runs: [(&str, Vec<&str>); 3] = [
        (
            "pgo-simulate",
            vec!["-n", "20000", "--loop-probability", "0"],
        ),
        ("pgo-convert", vec![s(&graph), "-q"]),
        ("pgo-solve", vec![s(&graph), "--no-timings", "-q"]),
    ];
    for (tool, args) in runs {
        let mut child = Command::new(bin(tool))
            .args(&args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut head = [0u8; 64];
        child.stdout.take().unwrap().read_exact(&mut head).unwrap();
        // The pipe's read end is closed here (dropped above).
        let out = child.wait_with_output().unwrap();
        assert_eq!(
            out.status.code(),
            Some(141),
            "{tool}: {}",
            text(&out.stderr)
        );
        let err = text(&out.stderr);
        assert!(!err.contains("error"), "{tool}: {err}");
        assert!(!err.contains("panicked"), "{tool}: {err}");
    }
}

#[test]
fn forced_progress_shows_the_phases_on_stderr_and_changes_no_output() {
    let mit = common::datasets_dir().join("MIT.g2o");
    let toy = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/paper_toy.g2o");
    let run = |args: &[&str]| {
        Command::new(bin("pgo-solve"))
            .args(args)
            .stdin(Stdio::null())
            .output()
            .unwrap()
    };
    for (input, extra, phases) in [
        (
            s(&mit),
            &[][..],
            &[
                "reading ",
                "initialization (chordal)",
                "Newton: step 1, rank 1: cost ",
                "certificate",
            ][..],
        ),
        // The toy graph's relaxation is not exact: the staircase climbs.
        (
            toy,
            &["--weights", "unit", "--method", "staircase"][..],
            &["staircase rank 2", "certificate", "bound"][..],
        ),
        (
            toy,
            &["--weights", "unit"][..],
            &["dual SDP: iteration 1: gap ", "certificate"][..],
        ),
    ] {
        let dir = Dir::new();
        let (a, b) = (dir.path("a.g2o"), dir.path("b.g2o"));
        let mut args = vec![input, "--json", "--no-timings"];
        args.extend(extra);
        let plain = run(&[&args[..], &["-o", s(&a)]].concat());
        let shown = run(&[&args[..], &["-o", s(&b), "--progress"]].concat());
        assert!(plain.status.success() && shown.status.success());
        assert_eq!(plain.stdout, shown.stdout, "{input} {extra:?}");
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        // Not a terminal: nothing without --progress.
        assert!(plain.stderr.is_empty(), "{}", text(&plain.stderr));
        let err = text(&shown.stderr);
        assert!(err.lines().all(|l| l.starts_with("pgo-solve: ")), "{err}");
        for phase in phases {
            assert!(
                err.lines()
                    .any(|l| l.starts_with(&format!("pgo-solve: {phase}"))),
                "{input} {extra:?}: no '{phase}' in\n{err}"
            );
        }
        assert!(
            err.contains(&format!("pgo-solve: writing {}", s(&b))),
            "{err}"
        );
    }
    // -q and --progress contradict each other.
    let out = run(&[toy, "-q", "--progress"]);
    assert_eq!(out.status.code(), Some(2));
    // The other tools that compute show theirs too.
    for tool in ["pgo-certify", "pgo-spectrum"] {
        let out = Command::new(bin(tool))
            .args([toy, "--weights", "unit", "--progress"])
            .output()
            .unwrap();
        assert!(out.status.code().is_some_and(|c| c <= 1), "{tool}");
        let err = text(&out.stderr);
        assert!(
            err.starts_with(&format!("{tool}: reading {toy}\n")),
            "{err}"
        );
    }
}

/// pgo-solve writes its output file on the second core while the certificate is computed, from
/// the estimate it is about to certify, and puts it in place only where the solve ends there:
/// the file is the one written to stdout (never written ahead) byte for byte, and no temporary
/// file is left, where the estimate is kept (MIT, with and without a FIX pose) and where the
/// staircase moves it after (a generated graph whose relaxation is not exact at rank 1).
#[test]
fn the_output_written_ahead_of_the_certificate_is_the_one_written_after_it() {
    let dir = Dir::new();
    let mit = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("datasets/MIT.g2o");
    let mut fixed = std::fs::read(&mit).unwrap();
    fixed.extend_from_slice(b"FIX 3\n");
    let fixed = dir.file("mit-fix.g2o", &fixed);
    let noisy = dir.path("noisy.g2o");
    let simulate = Command::new(bin("pgo-simulate"))
        .args([
            "-n",
            "150",
            "--loop-model",
            "per-pose",
            "--loop-probability",
            "0.3",
        ])
        .args([
            "--rotation-noise",
            "gaussian:0.6",
            "--translation-noise",
            "gaussian:0.5",
        ])
        .args(["--seed", "1", "-q", "-o", s(&noisy)])
        .status()
        .unwrap();
    assert!(simulate.success());
    for (graph, climbs) in [(&mit, false), (&fixed, false), (&noisy, true)] {
        let file = dir.path("out.g2o");
        // Twice: the second rename replaces the first file.
        for _ in 0..2 {
            let run = Command::new(bin("pgo-solve"))
                .args([s(graph), "--json", "-q", "-o", s(&file)])
                .output()
                .unwrap();
            assert!(run.status.success(), "{}", text(&run.stderr));
            let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
            let rank = report["components"][0]["rank"].as_u64().unwrap();
            assert_eq!(rank > 1, climbs, "{}: rank {rank}", graph.display());
        }
        let stdout = Command::new(bin("pgo-solve"))
            .args([s(graph), "-q", "-o", "-"])
            .output()
            .unwrap();
        assert!(stdout.status.success());
        assert!(
            std::fs::read(&file).unwrap() == stdout.stdout,
            "{}",
            graph.display()
        );
        assert!(temporaries(dir.0.path()).is_empty(), "{:?}", dir.entries());
    }
}
