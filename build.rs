//! Links the tools (`src/bin`) on Linux with glibc: position-dependent, and without the default
//! feature `rerun` statically.
//!
//! A position-independent executable of this size carries about 30 000 relative relocations
//! (vtables, static strings, panic locations), which the dynamic loader applies at every start,
//! writing into a hundred pages of `.data.rel.ro`: 0.2 to 0.3 ms of each process, a tenth of a
//! 9-pose 3D solve and 5% of an 800-pose planar one, in tools that users run once per file in
//! shell pipelines. Linked at a fixed address, the linker resolves them once. The code is
//! compiled position-independent as before (only the link changes), so the library and the
//! Python extension are untouched; the executables lose address-space randomization of their
//! own image (their stack, heap and libraries keep it).
//!
//! Loading the shared libraries themselves (libc, libm, libgcc_s: their mappings, symbol
//! binding, and libgcc_s's CPU-feature constructor, whose `cpuid` instructions each leave a
//! virtual machine for several microseconds) costs a further 0.6 to 1.1 ms of every process on
//! a virtual machine (whole process, static against dynamic: tinyGrid3D 0.75 of the time, MIT
//! and CSAIL 0.87-0.89, the files of seconds the same). Rust links statically only with the
//! `crt-static` target feature, which Cargo cannot give the tools alone: in a build without
//! `--target` it reaches the procedural macros too, which cannot be built with it. So the link
//! is made static here instead: `-static` for the C driver (static start files, no dynamic
//! loader), and the libraries rustc names for a dynamic link (`-lgcc_s -lutil -lrt -lpthread -lm
//! -ldl -lc`) found first in a directory of one-line linker scripts that name the static
//! archives instead, `libgcc_eh.a` for `libgcc_s` as rustc does under `crt-static`.
//!
//! Left dynamic: builds with `rerun` (its network code resolves host names through glibc's
//! NSS, which a static glibc loads at run time from the shared libraries anyway) or with
//! `clarabel-sdp` (the system OpenBLAS), cross builds, systems without the static archives
//! (`cc -print-file-name` does not find them: glibc's static libraries are a separate package
//! on some distributions), and any build with `PGO_LINK=dynamic` in the environment. A build
//! with rustc's own `crt-static` is left to rustc.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The libraries rustc's standard library asks of a dynamic glibc link, each with the static
/// archives that replace it. One that a later rustc adds would reach the static link as a
/// shared library: the link succeeds and the tool crashes at its start (tried with `-lz`), which
/// the tests, which build and run the tools, show at once.
const STATIC_ARCHIVES: [(&str, &[&str]); 7] = [
    ("gcc_s", &["libgcc_eh.a", "libgcc.a"]),
    ("util", &["libutil.a"]),
    ("rt", &["librt.a"]),
    ("pthread", &["libpthread.a"]),
    ("m", &["libm.a"]),
    ("dl", &["libdl.a"]),
    ("c", &["libc.a"]),
];

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=PGO_LINK");
    let var = |name: &str| std::env::var(name).unwrap_or_default();
    // With `crt-static` (RUSTFLAGS and `--target`) rustc links a static PIE itself, which a
    // position-dependent link would break.
    let crt_static = var("CARGO_CFG_TARGET_FEATURE")
        .split(',')
        .any(|f| f == "crt-static");
    if var("CARGO_CFG_TARGET_OS") != "linux" || var("CARGO_CFG_TARGET_ENV") != "gnu" || crt_static {
        return;
    }
    println!("cargo:rustc-link-arg-bins=-no-pie");
    let dynamic = var("PGO_LINK") == "dynamic"
        || std::env::var_os("CARGO_FEATURE_RERUN").is_some()
        || std::env::var_os("CARGO_FEATURE_CLARABEL_SDP").is_some()
        || var("TARGET") != var("HOST");
    if dynamic {
        return;
    }
    let out = PathBuf::from(var("OUT_DIR")).join("static-libs");
    if write_scripts(&out).is_some() {
        println!("cargo:rustc-link-arg-bins=-static");
        println!("cargo:rustc-link-arg-bins=-L{}", out.display());
    }
}

/// Writes `lib<name>.so` for each library of [`STATIC_ARCHIVES`] into `dir`: a linker script
/// `INPUT(...)` of the static archives' paths as the C compiler finds them. `None` (and no
/// static link) where one of them is missing.
fn write_scripts(dir: &Path) -> Option<()> {
    let cc = std::env::var("RUSTC_LINKER").unwrap_or_else(|_| "cc".into());
    let find = |archive: &str| -> Option<PathBuf> {
        let output = Command::new(&cc)
            .arg(format!("-print-file-name={archive}"))
            .output();
        let path = PathBuf::from(String::from_utf8(output.ok()?.stdout).ok()?.trim());
        // Not found, the driver prints the bare name back; a path the script's syntax would
        // have to quote is left to the dynamic link.
        let plain = !path
            .to_string_lossy()
            .contains(|c: char| c.is_whitespace() || "()\"".contains(c));
        (path.is_absolute() && path.is_file() && plain).then_some(path)
    };
    let mut scripts = Vec::new();
    for (name, archives) in STATIC_ARCHIVES {
        let paths = archives
            .iter()
            .map(|a| find(a))
            .collect::<Option<Vec<_>>>()?;
        let list: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
        scripts.push((
            format!("lib{name}.so"),
            format!("INPUT({})\n", list.join(" ")),
        ));
    }
    std::fs::create_dir_all(dir).ok()?;
    for (file, text) in scripts {
        std::fs::write(dir.join(file), text).ok()?;
    }
    Some(())
}
