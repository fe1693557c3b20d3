//! Replays the inputs in `tests/fuzz-regressions/TARGET/` through the checks of the fuzz target
//! TARGET (`tests/oracle/mod.rs`, shared with `fuzz/fuzz_targets/`), so that what a fuzzer once
//! found stays fixed in plain `cargo test`, without cargo-fuzz. Add a minimized input
//! (`cargo fuzz tmin`) under its target's directory; see README "Fuzzing".

#[path = "oracle/mod.rs"]
mod oracle;

use std::path::Path;

/// What a fuzz target runs on an input.
type Check = fn(&[u8]);

/// The fuzz targets and their checks.
const TARGETS: [(&str, Check); 4] = [
    ("read_g2o", |d| oracle::check_reader(d, "fuzz.g2o")),
    ("read_toro", |d| oracle::check_reader(d, "fuzz.graph")),
    ("read_auto", |d| oracle::check_reader(d, "fuzz.txt")),
    ("solve", oracle::check_solve),
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
            oracle::check_reader(&data, "fuzz.txt");
            count += 1;
        }
    }
    assert!(count > 0, "no regression inputs in {}", root.display());
}
