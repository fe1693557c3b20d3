//! The reader on arbitrary bytes as `fuzz.g2o`: see `tests/oracle/mod.rs` for what is checked.
#![no_main]

#[path = "../../tests/oracle/mod.rs"]
mod oracle;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    oracle::check_reader(data, "fuzz.g2o");
});
