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

/// FORMATS.md §3.1, written out independently of the library: TORO -> g2o is
/// g2o = (T0, T1, T4, T2, T5, T3).
pub fn toro_to_g2o(t: [f64; 6]) -> [f64; 6] {
    [t[0], t[1], t[4], t[2], t[5], t[3]]
}

pub fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}
