//! Golden-file tests: each line of `tests/golden/cases.txt` is `NAME<TAB>COMMAND`; the command
//! runs in `tests/golden/` (so paths in it and in its messages are relative to that directory)
//! and its exit status, stdout and stderr must equal `tests/golden/expected/NAME.out`.
//! `<FILE` as the last word feeds FILE on stdin. The commands must leave no file behind.
//!
//! After an intended change of output, regenerate with `PGO_BLESS=1 cargo test --test golden`
//! and review the diff (`git diff tests/golden`) before committing it.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn tool(name: &str) -> &'static str {
    match name {
        "pgo-convert" => env!("CARGO_BIN_EXE_pgo-convert"),
        "pgo-simulate" => env!("CARGO_BIN_EXE_pgo-simulate"),
        "pgo-solve" => env!("CARGO_BIN_EXE_pgo-solve"),
        "pgo-spectrum" => env!("CARGO_BIN_EXE_pgo-spectrum"),
        "pgo-certify" => env!("CARGO_BIN_EXE_pgo-certify"),
        other => panic!("unknown tool {other} in tests/golden/cases.txt"),
    }
}

fn listing(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    v.sort();
    v
}

fn transcript(dir: &Path, command: &str) -> String {
    let mut words: Vec<&str> = command.split_whitespace().collect();
    let stdin = match words.last() {
        Some(w) if w.starts_with('<') => {
            let file = &words.pop().unwrap()[1..];
            Stdio::from(std::fs::File::open(dir.join(file)).unwrap())
        }
        _ => Stdio::null(),
    };
    let out = Command::new(tool(words[0]))
        .args(&words[1..])
        .current_dir(dir)
        .stdin(stdin)
        .output()
        .unwrap();
    format!(
        "$ {command}\nstatus: {}\n--- stdout\n{}--- stderr\n{}",
        out.status.code().map_or("signal".into(), |c| c.to_string()),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn golden_outputs() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let cases = std::fs::read_to_string(dir.join("cases.txt")).unwrap();
    let bless = std::env::var_os("PGO_BLESS").is_some();
    if bless {
        std::fs::create_dir_all(dir.join("expected")).unwrap();
    }
    let before = listing(&dir);
    let mut failed = Vec::new();
    for line in cases
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
    {
        let (name, command) = line.split_once('\t').expect("NAME<TAB>COMMAND");
        let actual = transcript(&dir, command);
        let path = dir.join("expected").join(format!("{name}.out"));
        if bless {
            std::fs::write(&path, &actual).unwrap();
        } else {
            let expected = std::fs::read_to_string(&path).unwrap_or_default();
            if expected != actual {
                failed.push(format!(
                    "{name}:\n--- expected\n{expected}\n--- actual\n{actual}"
                ));
            }
        }
    }
    assert_eq!(listing(&dir), before, "a golden command left a file behind");
    assert!(
        failed.is_empty(),
        "golden outputs differ (if intended: PGO_BLESS=1 cargo test --test golden):\n{}",
        failed.join("\n")
    );
}
