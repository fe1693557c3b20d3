//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The public data sets, `../shared/datasets` relative to the repository root.
pub fn datasets_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/datasets");
    assert!(
        dir.join("MANIFEST.tsv").is_file(),
        "the public data sets are expected in {} (../shared/datasets relative to the repository root)",
        dir.display()
    );
    dir
}

/// One row of MANIFEST.tsv.
#[derive(Debug, Clone)]
pub struct ManifestEntry {
    pub file: String,
    pub format: String,
    pub poses: usize,
    pub edges: usize,
    pub bytes: u64,
    pub notes: String,
}

pub fn manifest() -> Vec<ManifestEntry> {
    let text = std::fs::read_to_string(datasets_dir().join("MANIFEST.tsv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (file, format, poses, edges, bytes, notes) = (
        col("file"),
        col("format"),
        col("poses"),
        col("edges"),
        col("bytes"),
        col("notes"),
    );
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            ManifestEntry {
                file: f[file].to_string(),
                format: f[format].to_string(),
                poses: f[poses].parse().unwrap(),
                edges: f[edges].parse().unwrap(),
                bytes: f[bytes].parse().unwrap(),
                notes: f[notes].to_string(),
            }
        })
        .collect()
}

/// A deliberately naive reader, independent of the library: split on whitespace, parse with
/// `str::parse`, keep the six noise values in file order.
#[derive(Debug, Default)]
pub struct Naive {
    pub vertices: Vec<(u32, [f64; 3])>,
    pub edges: Vec<(u32, u32, [f64; 3], [f64; 6])>,
    pub fixed: Vec<u32>,
}

pub fn naive_read(bytes: &[u8]) -> Naive {
    let text = String::from_utf8_lossy(bytes);
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let mut g = Naive::default();
    let f = |t: &str| t.parse::<f64>().unwrap();
    for line in text.lines() {
        let t: Vec<&str> = line.split_whitespace().collect();
        match t.first().copied() {
            Some("VERTEX_SE2" | "VERTEX2" | "VERTEX") => {
                g.vertices
                    .push((t[1].parse().unwrap(), [f(t[2]), f(t[3]), f(t[4])]));
            }
            Some("EDGE_SE2" | "EDGE2" | "EDGE") => {
                let mut n = [0.0; 6];
                for k in 0..6 {
                    n[k] = f(t[6 + k]);
                }
                g.edges.push((
                    t[1].parse().unwrap(),
                    t[2].parse().unwrap(),
                    [f(t[3]), f(t[4]), f(t[5])],
                    n,
                ));
            }
            Some("FIX") => g
                .fixed
                .extend(t[1..].iter().map(|s| s.parse::<u32>().unwrap())),
            _ => {}
        }
    }
    g
}

/// docs/formats.md §3.1, written out independently of the library: TORO -> g2o is
/// g2o = (T0, T1, T4, T2, T5, T3).
pub fn toro_to_g2o(t: [f64; 6]) -> [f64; 6] {
    [t[0], t[1], t[4], t[2], t[5], t[3]]
}

pub fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

// ---------------------------------------------------------------------------------------------
// Running the tools.

use std::path::Path;
use std::process::{Command, Output, Stdio};

/// A built binary of this package by name (cargo builds every binary before the integration
/// tests, next to the `deps/` directory the test executable runs from).
pub fn bin(name: &str) -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let dir = exe.parent().unwrap().parent().unwrap();
    let path = dir.join(format!("{name}{}", std::env::consts::EXE_SUFFIX));
    assert!(path.is_file(), "{} is not built", path.display());
    path
}

/// A tool that reads a graph file, as the tests drive it.
#[derive(Debug, Clone)]
pub struct Tool {
    pub name: String,
    /// How many positional arguments it takes (each is given the input file).
    pub inputs: usize,
    /// Whether it has `-o/--output`.
    pub writes: bool,
    /// Whether it has `--weights` (it evaluates the objective).
    pub weighs: bool,
}

/// Every tool of `pgo::cli::commands()` that reads a graph file (a required positional
/// argument); a new tool is picked up as soon as it is listed there.
pub fn input_tools() -> Vec<Tool> {
    let tools: Vec<Tool> = pgo::cli::commands()
        .into_iter()
        .map(|c| Tool {
            name: c.get_name().to_string(),
            inputs: c.get_positionals().filter(|a| a.is_required_set()).count(),
            writes: c.get_arguments().any(|a| a.get_long() == Some("output")),
            weighs: c.get_arguments().any(|a| a.get_long() == Some("weights")),
        })
        .filter(|t| t.inputs > 0)
        .collect();
    // The tools there are today; more may come.
    for name in ["pgo-convert", "pgo-solve", "pgo-spectrum"] {
        assert!(tools.iter().any(|t| t.name == name), "{name} missing");
    }
    tools
}

/// Runs `tool` on `input` (as every positional argument) with `flags`, writing to `output`
/// when the tool writes.
pub fn run_tool(tool: &Tool, input: &Path, output: Option<&Path>, flags: &[&str]) -> Output {
    let mut cmd = Command::new(bin(&tool.name));
    for _ in 0..tool.inputs {
        cmd.arg(input);
    }
    if let (true, Some(o)) = (tool.writes, output) {
        cmd.arg("--output").arg(o);
    }
    cmd.args(flags)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    cmd.output().unwrap()
}

/// Runs a binary with arguments and optional stdin.
pub fn run_with_stdin(name: &str, args: &[&str], stdin: Option<&[u8]>) -> Output {
    let mut child = Command::new(bin(name))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    {
        use std::io::Write;
        let mut input = child.stdin.take().unwrap();
        if let Some(bytes) = stdin {
            input.write_all(bytes).unwrap();
        }
    }
    child.wait_with_output().unwrap()
}

pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Whether a process ended by itself (not killed by a signal, e.g. an abort after a panic).
pub fn exited_normally(out: &Output) -> bool {
    out.status.code().is_some()
}

/// A temporary directory with helpers.
pub struct Dir(pub tempfile::TempDir);

impl Dir {
    pub fn new() -> Self {
        Dir(tempfile::tempdir().unwrap())
    }
    pub fn file(&self, name: &str, content: &[u8]) -> PathBuf {
        let p = self.0.path().join(name);
        std::fs::write(&p, content).unwrap();
        p
    }
    pub fn path(&self, name: &str) -> PathBuf {
        self.0.path().join(name)
    }
    pub fn entries(&self) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(self.0.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

// ---------------------------------------------------------------------------------------------
// Large generated inputs.

/// Writes a deterministic g2o text of about `mb` megabytes to `out`: a chain of vertices and
/// edges with varied number syntax, plus loop closures. Returns the number of lines written.
pub fn write_generated(mb: usize, out: &mut impl std::io::Write) -> std::io::Result<usize> {
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let n = mb * 11_500;
    let mut lines = 0;
    for k in 0..n {
        let r = next();
        writeln!(
            out,
            "VERTEX_SE2 {k} {}.{} -{}e-3 {}",
            r % 1000,
            r % 97,
            r % 5000,
            (r % 6283) as f64 / 1000.0
        )?;
        lines += 1;
    }
    for k in 0..n {
        let r = next();
        let j = if k + 1 < n && r % 5 != 0 {
            k + 1
        } else {
            (r as usize) % n
        };
        if j == k {
            continue;
        }
        writeln!(
            out,
            "EDGE_SE2 {k} {j} 1.{} 0.00{} -{}.5 {} 0 0 {} 0 {}",
            r % 1000,
            r % 89,
            r % 3,
            1 + r % 400,
            1 + r % 300,
            1 + r % 700
        )?;
        lines += 1;
    }
    Ok(lines)
}
