//! The solve path of `pgo-solve` on tiny graphs (at most 8 poses): see `tests/oracle/mod.rs`.
#![no_main]

#[path = "../../tests/oracle/mod.rs"]
mod oracle;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    oracle::check_solve(data);
});
