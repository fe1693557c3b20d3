//! Links the tools (`src/bin`) as position-dependent executables on Linux with glibc.
//!
//! A position-independent executable of this size carries about 30 000 relative relocations
//! (vtables, static strings, panic locations), which the dynamic loader applies at every start,
//! writing into a hundred pages of `.data.rel.ro`: 0.2 to 0.3 ms of each process, a tenth of a
//! 9-pose 3D solve and 5% of an 800-pose planar one, in tools that users run once per file in
//! shell pipelines. Linked at a fixed address, the linker resolves them once. The code is
//! compiled position-independent as before (only the link changes), so the library and the
//! Python extension are untouched; the executables lose address-space randomization of their
//! own image (their stack, heap and libraries keep it).

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let env = std::env::var("CARGO_CFG_TARGET_ENV").unwrap_or_default();
    if os == "linux" && env == "gnu" {
        println!("cargo:rustc-link-arg-bins=-no-pie");
    }
}
