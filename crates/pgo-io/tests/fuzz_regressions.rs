//! Replays the inputs in `tests/fuzz-regressions/TARGET/` through the checks of the reader fuzz
//! target TARGET (`tests/oracle/mod.rs`, shared with `fuzz/fuzz_targets/`), so that what a fuzzer
//! once found stays fixed in plain `cargo test`, without cargo-fuzz. Add a minimized input
//! (`cargo fuzz tmin`) under its target's directory; see the root README, "Fuzzing".

#[path = "oracle/mod.rs"]
mod oracle;

use std::path::Path;

/// The reader fuzz targets and the file name each reads its input as.
const TARGETS: [(&str, &str); 3] = [
    ("read_g2o", "fuzz.g2o"),
    ("read_toro", "fuzz.graph"),
    ("read_auto", "fuzz.txt"),
];

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
        let Some((_, name)) = TARGETS.iter().find(|(t, _)| *t == target) else {
            panic!("{}: no reader fuzz target of that name", dir.display());
        };
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        for file in files {
            let data = std::fs::read(&file).unwrap();
            eprintln!("{}", file.display());
            oracle::check_reader(&data, name);
            // The format from the tags, whatever target found it.
            oracle::check_reader(&data, "fuzz.txt");
            count += 1;
        }
    }
    assert!(count > 0, "no regression inputs in {}", root.display());
}

/// The fuzzers' seeds (`fuzz/seeds/`, planar and 3D) pass the same checks, under every name.
#[test]
fn every_fuzz_seed_passes_the_reader_checks() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds");
    let mut count = 0;
    for entry in std::fs::read_dir(&root).unwrap() {
        let data = std::fs::read(entry.unwrap().path()).unwrap();
        for (_, name) in TARGETS {
            oracle::check_reader(&data, name);
        }
        count += 1;
    }
    assert!(count >= 9, "{count} seeds");
}
