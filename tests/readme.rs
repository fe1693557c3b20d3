//! Every shell example of README.md runs, as a user would run it.
//!
//! The examples are the fenced code blocks whose info string is `sh`. A block right after a line
//! `<!-- not run: REASON -->` is not run (builds, viewers, long runs). In the others, every line
//! (continued with a trailing `\`) that is not blank or a comment is one command, run by bash
//! (with `pipefail`) in one temporary directory, in README order, with:
//! - the built tools first on `PATH` (cargo builds every binary of the package before its
//!   integration tests);
//! - a copy of `datasets/` (the bundled graphs) in the working directory;
//! - `DATA` set to the directory of the public data sets: `PGO_DATASETS_DIR` if set, else
//!   `../shared/datasets` relative to the repository root (docs/datasets.md). A command that
//!   names `$DATA/FILE` for a FILE that is not there is skipped, with a message on stderr; the
//!   bundled graphs are always there, so their examples always run.
//!
//! `cargo run [OPTIONS] [--bin TOOL] -- ARGS` runs `TOOL ARGS` (TOOL defaults to the package's
//! `default-run`); any other cargo command must be in a block that is not run. A trailing comment
//! `# exit N` gives the expected exit status; it is 0 otherwise. A command fails on another
//! status, on a panic message, or after 300 s.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const TOOLS: [&str; 6] = [
    "pgo-convert",
    "pgo-solve",
    "pgo-certify",
    "pgo-spectrum",
    "pgo-simulate",
    "pgo-eval",
];

const TIMEOUT: Duration = Duration::from_secs(300);

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The directory of the built tools.
fn bin_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_BIN_EXE_pgo-solve"))
        .parent()
        .unwrap()
        .to_path_buf();
    for tool in TOOLS {
        let exe = dir.join(format!("{tool}{}", std::env::consts::EXE_SUFFIX));
        assert!(exe.is_file(), "{} is not built", exe.display());
    }
    dir
}

/// The public data sets: `PGO_DATASETS_DIR`, else `../shared/datasets` beside the repository.
fn datasets_dir() -> PathBuf {
    let dir = match std::env::var_os("PGO_DATASETS_DIR") {
        Some(d) => PathBuf::from(d),
        None => root().join("../shared/datasets"),
    };
    std::fs::canonicalize(&dir).unwrap_or(dir)
}

/// The package's `default-run` binary, from Cargo.toml.
fn default_run() -> String {
    let manifest = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    manifest
        .lines()
        .find_map(|l| {
            let (key, value) = l.split_once('=')?;
            (key.trim() == "default-run").then(|| value.trim().trim_matches('"').to_string())
        })
        .expect("Cargo.toml has no default-run")
}

/// A block of README.md.
#[derive(Debug)]
struct Block {
    /// 1-based line of the opening fence.
    line: usize,
    /// Why it is not run, if it is not.
    not_run: Option<String>,
    commands: Vec<Example>,
}

/// One command of a block.
#[derive(Debug, Clone)]
struct Example {
    /// 1-based line where it starts.
    line: usize,
    /// The command as written (without its comment).
    written: String,
    /// What runs: `written`, with `cargo run ... -- ARGS` turned into `TOOL ARGS`.
    command: String,
    /// Expected exit status.
    status: i32,
}

/// Splits a command line into the command and its trailing comment: the first `#` outside
/// quotes that starts a word.
fn split_comment(line: &str) -> (&str, Option<&str>) {
    let (mut single, mut double) = (false, false);
    let mut prev = ' ';
    for (k, c) in line.char_indices() {
        match c {
            '\'' if !double => single = !single,
            '"' if !single => double = !double,
            '#' if !single && !double && prev.is_whitespace() => {
                return (line[..k].trim_end(), Some(line[k + 1..].trim()));
            }
            _ => {}
        }
        prev = c;
    }
    (line.trim_end(), None)
}

/// The status a comment `exit N...` announces.
fn expected_status(comment: Option<&str>) -> i32 {
    comment
        .and_then(|c| c.strip_prefix("exit "))
        .and_then(|rest| {
            let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
            digits.parse().ok()
        })
        .unwrap_or(0)
}

/// `cargo run [OPTIONS] [--bin TOOL] -- ARGS` as `TOOL ARGS`.
fn translate_cargo(command: &str, line: usize, default_run: &str) -> String {
    let words: Vec<&str> = command.split_whitespace().collect();
    assert_eq!(
        words.get(1).copied(),
        Some("run"),
        "README.md:{line}: `{command}` builds with cargo: put it in a block marked <!-- not run: REASON -->"
    );
    let (options, args) = match command.split_once(" -- ") {
        Some((options, args)) => (options, args.trim()),
        None => (command, ""),
    };
    let options: Vec<&str> = options.split_whitespace().collect();
    assert!(
        !options.contains(&"--example"),
        "README.md:{line}: `{command}` runs a cargo example: put it in a block that is not run"
    );
    let tool = options
        .iter()
        .position(|w| *w == "--bin")
        .map(|k| options[k + 1].to_string())
        .unwrap_or_else(|| default_run.to_string());
    assert!(
        TOOLS.contains(&tool.as_str()),
        "README.md:{line}: `{command}` runs {tool}, which is not one of the tools"
    );
    format!("{tool} {args}").trim_end().to_string()
}

fn parse_readme(text: &str, default_run: &str) -> Vec<Block> {
    let lines: Vec<&str> = text.lines().collect();
    let mut blocks = Vec::new();
    let mut k = 0;
    while k < lines.len() {
        let Some(info) = lines[k].trim_start().strip_prefix("```") else {
            k += 1;
            continue;
        };
        let open = k;
        let mut body = Vec::new();
        k += 1;
        while k < lines.len() && !lines[k].trim_start().starts_with("```") {
            body.push((k + 1, lines[k]));
            k += 1;
        }
        k += 1;
        if info.trim() != "sh" {
            continue;
        }
        let not_run = open
            .checked_sub(1)
            .and_then(|p| lines[p].trim().strip_prefix("<!-- not run:"))
            .map(|rest| {
                let reason = rest.strip_suffix("-->").unwrap_or(rest).trim();
                assert!(
                    !reason.is_empty(),
                    "README.md:{open}: a block that is not run needs a reason"
                );
                reason.to_string()
            });
        let mut commands = Vec::new();
        let mut pending: Option<(usize, String)> = None;
        for (n, raw) in body {
            let (start, joined) = match pending.take() {
                Some((start, mut acc)) => {
                    acc.push(' ');
                    acc.push_str(raw.trim());
                    (start, acc)
                }
                None => (n, raw.trim().to_string()),
            };
            if let Some(head) = joined.strip_suffix('\\') {
                pending = Some((start, head.trim_end().to_string()));
                continue;
            }
            if joined.is_empty() || joined.starts_with('#') {
                continue;
            }
            let (written, comment) = split_comment(&joined);
            let command = if written.starts_with("cargo ") && not_run.is_none() {
                translate_cargo(written, start, default_run)
            } else {
                written.to_string()
            };
            commands.push(Example {
                line: start,
                written: written.to_string(),
                command,
                status: expected_status(comment),
            });
        }
        assert!(
            pending.is_none(),
            "README.md:{open}: block ends with a `\\`"
        );
        blocks.push(Block {
            line: open + 1,
            not_run,
            commands,
        });
    }
    blocks
}

/// The public data set files a command names as `$DATA/FILE` (or `"$DATA"/FILE`).
fn public_files(command: &str) -> Vec<String> {
    let mut files = Vec::new();
    for marker in ["$DATA/", "\"$DATA\"/", "${DATA}/"] {
        for (k, _) in command.match_indices(marker) {
            let name: String = command[k + marker.len()..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || "._-*".contains(*c))
                .collect();
            files.push(name);
        }
    }
    files
}

/// Why a command cannot run here, if it cannot: a public data set it needs is absent.
fn missing_data(command: &str, data: &Path) -> Option<String> {
    if !command.contains("DATA") {
        return None;
    }
    if !data.is_dir() {
        return Some(format!("no data set directory {}", data.display()));
    }
    public_files(command)
        .into_iter()
        .find(|f| !f.contains('*') && !data.join(f).is_file())
        .map(|f| format!("public data set {f} not found in {}", data.display()))
}

/// Output of one command.
struct Run {
    status: Option<i32>,
    stdout: String,
    stderr: String,
    timed_out: bool,
}

fn run(command: &str, cwd: &Path, path: &str, data: &Path, logs: &Path) -> Run {
    let out_path = logs.join("stdout");
    let err_path = logs.join("stderr");
    let mut cmd = Command::new("bash");
    cmd.arg("-c")
        .arg(format!("set -o pipefail\n{command}"))
        .current_dir(cwd)
        .env("PATH", path)
        .env("DATA", data)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out_path).unwrap())
        .stderr(std::fs::File::create(&err_path).unwrap());
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        cmd.process_group(0);
    }
    let mut child = cmd.spawn().expect("bash");
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > TIMEOUT {
            timed_out = true;
            // The whole pipeline: bash leads its own process group.
            #[cfg(unix)]
            let _ = Command::new("kill")
                .args(["-KILL", "--", &format!("-{}", child.id())])
                .status();
            let _ = child.kill();
            break child.wait().unwrap();
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Run {
        status: status.code(),
        stdout: String::from_utf8_lossy(&std::fs::read(&out_path).unwrap()).into_owned(),
        stderr: String::from_utf8_lossy(&std::fs::read(&err_path).unwrap()).into_owned(),
        timed_out,
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        if entry.file_type().unwrap().is_file() {
            std::fs::copy(entry.path(), to.join(entry.file_name())).unwrap();
        }
    }
}

fn tail(text: &str, lines: usize) -> String {
    let all: Vec<&str> = text.lines().collect();
    all[all.len().saturating_sub(lines)..].join("\n")
}

#[test]
fn readme_examples_run() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let blocks = parse_readme(&readme, &default_run());
    let runnable: Vec<&Example> = blocks
        .iter()
        .filter(|b| b.not_run.is_none())
        .flat_map(|b| &b.commands)
        .collect();
    assert!(
        runnable.len() >= 10,
        "only {} runnable examples found in README.md",
        runnable.len()
    );

    let work = tempfile::tempdir().unwrap();
    let logs = tempfile::tempdir().unwrap();
    copy_dir(&root().join("datasets"), &work.path().join("datasets"));
    let path = std::env::join_paths(std::iter::once(bin_dir()).chain(std::env::split_paths(
        &std::env::var_os("PATH").unwrap_or_default(),
    )))
    .unwrap();
    let path = path.to_str().unwrap().to_string();
    let data = datasets_dir();

    let mut stderr = std::io::stderr();
    let (mut ran, mut skipped, mut failures) = (0, 0, Vec::new());
    let mut first: Option<(Example, Run)> = None;
    for block in &blocks {
        if let Some(reason) = &block.not_run {
            writeln!(stderr, "README.md:{}: block not run ({reason})", block.line).unwrap();
            continue;
        }
        for example in &block.commands {
            if let Some(why) = missing_data(&example.command, &data) {
                // Loud: written past the test harness's capture.
                writeln!(
                    stderr,
                    "README.md:{}: SKIPPED ({why}): {}",
                    example.line, example.written
                )
                .unwrap();
                skipped += 1;
                continue;
            }
            let out = run(&example.command, work.path(), &path, &data, logs.path());
            ran += 1;
            let problem = if out.timed_out {
                Some(format!("no exit after {} s", TIMEOUT.as_secs()))
            } else if out.status != Some(example.status) {
                Some(format!(
                    "exit status {:?}, expected {}",
                    out.status, example.status
                ))
            } else if out.stderr.contains("panicked") {
                Some("panicked".to_string())
            } else {
                None
            };
            if let Some(problem) = problem {
                failures.push(format!(
                    "README.md:{}: {problem}\n  $ {}\n--- stderr (end)\n{}\n--- stdout (end)\n{}",
                    example.line,
                    example.command,
                    tail(&out.stderr, 15),
                    tail(&out.stdout, 5)
                ));
            }
            if first.is_none() {
                first = Some((example.clone(), out));
            }
        }
    }
    writeln!(
        stderr,
        "README.md: {ran} examples run, {skipped} skipped for want of public data sets"
    )
    .unwrap();
    assert!(
        failures.is_empty(),
        "{} README example(s) failed:\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );

    // The first command is the main job: a certified solve of a bundled graph, reporting the
    // cost, the proven bound and the verdict.
    let (example, out) = first.expect("no example ran");
    let first_runnable = runnable[0];
    assert_eq!(
        example.line, first_runnable.line,
        "the first example did not run"
    );
    assert!(
        example.command.starts_with("pgo-solve datasets/"),
        "README.md:{}: the first example should solve a bundled graph: {}",
        example.line,
        example.written
    );
    for needle in ["cost", "lower bound", "certified optimal"] {
        assert!(
            out.stderr.contains(needle),
            "README.md:{}: the first example's report lacks '{needle}':\n{}",
            example.line,
            out.stderr
        );
    }
}

#[test]
fn default_run_is_the_solver() {
    assert_eq!(default_run(), "pgo-solve");
}

#[test]
fn parser_reads_commands_comments_and_markers() {
    let text = "intro\n\n```sh\ncargo run --release --bin pgo-certify -- a.g2o  # exit 1: no\n\
                pgo-convert a \\\n  --stats   # long\n# a comment\n\necho '# not a comment'\n```\n\
                <!-- not run: builds -->\n```sh\ncargo build --release\n```\n```text\nx\n```\n";
    let blocks = parse_readme(text, "pgo-solve");
    assert_eq!(blocks.len(), 2);
    let b = &blocks[0];
    assert_eq!((b.line, b.not_run.as_deref()), (3, None));
    let got: Vec<(usize, &str, i32)> = b
        .commands
        .iter()
        .map(|c| (c.line, c.command.as_str(), c.status))
        .collect();
    assert_eq!(
        got,
        [
            (4, "pgo-certify a.g2o", 1),
            (5, "pgo-convert a --stats", 0),
            (9, "echo '# not a comment'", 0)
        ]
    );
    assert_eq!(blocks[1].not_run.as_deref(), Some("builds"));
    assert_eq!(blocks[1].commands[0].command, "cargo build --release");
    assert_eq!(
        public_files("cat $DATA/M3500.g2o | x \"$DATA\"/w.graph"),
        ["M3500.g2o", "w.graph"]
    );
    assert_eq!(
        translate_cargo("cargo run --release -- x.g2o -o y.g2o", 1, "pgo-solve"),
        "pgo-solve x.g2o -o y.g2o"
    );
}

/// The field names the README's "JSON reports" section gives for `tool`: every backticked
/// lower-case identifier of its paragraph (values are in quotes, not backticks).
fn documented_fields(readme: &str, tool: &str) -> std::collections::BTreeSet<String> {
    let section = readme
        .split("### JSON reports")
        .nth(1)
        .expect("README.md has a section `### JSON reports`");
    let section = section.split("\n#").next().unwrap();
    let paragraph = section
        .split("\n\n")
        .find(|p| p.trim_start().starts_with(&format!("**{tool}")))
        .unwrap_or_else(|| panic!("README.md's JSON reports section has no paragraph for {tool}"));
    let paragraph = paragraph
        .split_once("**:")
        .map_or(paragraph, |(_, rest)| rest);
    paragraph
        .split('`')
        .skip(1)
        .step_by(2)
        .filter(|w| {
            !w.is_empty()
                && w.chars()
                    .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        })
        .map(str::to_string)
        .collect()
}

/// Every key of the JSON objects printed, at any depth.
fn printed_fields(json: &[u8], into: &mut std::collections::BTreeSet<String>) {
    fn keys(value: &serde_json::Value, into: &mut std::collections::BTreeSet<String>) {
        match value {
            serde_json::Value::Object(object) => {
                for (key, v) in object {
                    into.insert(key.clone());
                    keys(v, into);
                }
            }
            serde_json::Value::Array(items) => items.iter().for_each(|v| keys(v, into)),
            _ => {}
        }
    }
    for line in String::from_utf8_lossy(json).lines() {
        keys(&serde_json::from_str(line).unwrap(), into);
    }
}

/// The README's list of `--json` fields is what the tools print, both ways: no field printed
/// that the README does not name, and no field named that none of these runs prints (each run
/// chosen to bring out the optional fields: refinement, a reader's warning, a graph that is not
/// certified, both methods, an estimate that certifies itself).
#[test]
fn json_reports_are_documented() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let with_warning = dir.path().join("warning.g2o");
    let mut text = std::fs::read_to_string(root().join("datasets/MIT.g2o")).unwrap();
    text.push_str("UNKNOWN_TAG 1 2 3\n");
    std::fs::write(&with_warning, text).unwrap();
    // A pose-landmark graph: a triangle of poses, each observing one landmark.
    let landmarks = dir.path().join("landmarks.g2o");
    std::fs::write(
        &landmarks,
        "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 1.5707963267948966\nVERTEX_SE2 2 1 1 3.141592653589793\n\
         VERTEX_XY 7 0.5 0.5\n\
         EDGE_SE2 0 1 1 0 1.5707963267948966 1 0 0 1 0 1\n\
         EDGE_SE2 1 2 1 0 1.5707963267948966 1 0 0 1 0 1\n\
         EDGE_SE2_XY 0 7 0.5 0.5 1 0 1\nEDGE_SE2_XY 1 7 0.5 0.5 1 0 1\nEDGE_SE2_XY 2 7 0.5 0.5 1 0 1\n",
    )
    .unwrap();
    let landmarks = landmarks.to_str().unwrap();
    // A 3D triangle whose measurements do not quite close, for pgo-spectrum's 3D report.
    let three_d = dir.path().join("three_d.g2o");
    let info = "1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1";
    std::fs::write(
        &three_d,
        format!(
            "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\nVERTEX_SE3:QUAT 2 1 1 0 0 0 0 1\n\
             EDGE_SE3:QUAT 0 1 1 0 0 0 0 0.1 1 {info}\n\
             EDGE_SE3:QUAT 1 2 0 1 0.1 0 0 0 1 {info}\n\
             EDGE_SE3:QUAT 2 0 -1 -1 0 0.1 0 0 1 {info}\n"
        ),
    )
    .unwrap();
    let three_d = three_d.to_str().unwrap();
    // MIT with 5 false loop closures, for --robust.
    let corrupted = dir.path().join("corrupted.g2o");
    let out = Command::new(bin_dir().join("pgo-simulate"))
        .current_dir(root())
        .args([
            "--corrupt",
            "datasets/MIT.g2o",
            "--outliers",
            "5",
            "--seed",
            "1",
            "-o",
        ])
        .arg(&corrupted)
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let corrupted = corrupted.to_str().unwrap();
    let solved = dir.path().join("solved.g2o");
    let (mit, toy) = ("datasets/MIT.g2o", "datasets/paper_toy.g2o");
    let warning = with_warning.to_str().unwrap();
    let solved_path = solved.to_str().unwrap();
    // (tool, input, flags): each chosen to bring out optional fields.
    let runs: [(&str, &[(&str, &str)]); 5] = [
        (
            "pgo-solve",
            &[
                (mit, "--refine -o /dev/null --marginals /dev/null"),
                (mit, "--method staircase --refine"),
                (warning, "--no-timings"),
                (toy, "--weights unit"),
                (landmarks, ""),
                (corrupted, "--robust tls"),
            ],
        ),
        (
            "pgo-certify",
            &[
                (mit, ""),
                (mit, "--estimate SOLVED"),
                (warning, ""),
                (toy, "--weights unit"),
                (landmarks, ""),
            ],
        ),
        (
            "pgo-spectrum",
            &[
                (mit, "-k 3"),
                (warning, "-k 3"),
                (toy, "--weights unit"),
                (landmarks, ""),
                (three_d, "-k 3"),
            ],
        ),
        (
            "pgo-convert",
            &[
                (mit, "--stats"),
                (warning, "--stats"),
                (landmarks, "--stats"),
            ],
        ),
        (
            "pgo-eval",
            &[
                (mit, "SOLVED"),
                (mit, "SOLVED --no-align --delta 900"),
                (three_d, "THREE_D"),
            ],
        ),
    ];
    let out = Command::new(bin_dir().join("pgo-solve"))
        .current_dir(root())
        .args([mit, "-o", solved_path])
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    for (tool, cases) in runs {
        let mut printed = std::collections::BTreeSet::new();
        for (input, flags) in cases {
            let flags = flags
                .replace("SOLVED", solved_path)
                .replace("THREE_D", three_d);
            let out = Command::new(bin_dir().join(tool))
                .current_dir(root())
                .arg(input)
                .args(flags.split_whitespace())
                .arg("--json")
                .output()
                .unwrap();
            assert!(
                matches!(out.status.code(), Some(0 | 1)),
                "{tool} {input} {flags}: {out:?}"
            );
            printed_fields(&out.stdout, &mut printed);
        }
        let documented = documented_fields(&readme, tool);
        let undocumented: Vec<_> = printed.difference(&documented).collect();
        let never_printed: Vec<_> = documented.difference(&printed).collect();
        assert!(
            undocumented.is_empty(),
            "{tool} --json prints fields README.md's JSON reports section does not name: {undocumented:?}"
        );
        assert!(
            never_printed.is_empty(),
            "README.md's JSON reports section names {tool} fields no run printed: {never_printed:?}"
        );
    }
}
