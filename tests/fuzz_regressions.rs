//! Replays the inputs in `tests/fuzz-regressions/TARGET/` through the checks of the fuzz target
//! TARGET (`tests/oracle/mod.rs`, shared with `fuzz/fuzz_targets/`), so that what a fuzzer once
//! found stays fixed in plain `cargo test`, without cargo-fuzz, and through the readers' checks
//! (those of the reader fuzz targets, `crates/pgo-io/tests/oracle/mod.rs`; the file layer replays
//! its own inputs in `crates/pgo-io/tests/fuzz-regressions/`). Add a minimized input
//! (`cargo fuzz tmin`) under its target's directory; see README "Fuzzing".

#[path = "oracle/mod.rs"]
mod oracle;
#[path = "../crates/pgo-io/tests/oracle/mod.rs"]
mod reader_oracle;

use std::path::Path;

/// What a fuzz target runs on an input.
type Check = fn(&[u8]);

/// The fuzz targets of this package and their checks (the reader targets are pgo-io's).
const TARGETS: [(&str, Check); 1] = [("solve", oracle::check_solve)];

#[test]
fn every_fuzz_regression_input_passes_its_targets_checks() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-regressions");
    let mut count = 0;
    for entry in std::fs::read_dir(&root).unwrap() {
        let dir = entry.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        let target = dir.file_name().unwrap().to_string_lossy().into_owned();
        let Some((_, check)) = TARGETS.iter().find(|(t, _)| *t == target) else {
            panic!("{}: no fuzz target of that name", dir.display());
        };
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        for file in files {
            let data = std::fs::read(&file).unwrap();
            eprintln!("{}", file.display());
            check(&data);
            // The readers' checks run on every input, whatever target found it.
            reader_oracle::check_reader(&data, "fuzz.txt");
            count += 1;
        }
    }
    assert!(count > 0, "no regression inputs in {}", root.display());
}
