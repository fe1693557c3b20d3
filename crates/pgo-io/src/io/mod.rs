//! Reading and writing pose graphs in the g2o and TORO text formats, losslessly: planar ones
//! ([`read`], [`write`]) and 3D ones ([`read3`], [`write3`], docs/formats.md §10), and either
//! ([`read_any_path`]).
//!
//! How the established tools read and write these files, quirks included, is recorded in
//! `docs/formats.md`; this module follows its §7 recommendations: lenient about layout (comments, blank
//! lines, CRLF, tabs, runs of spaces, a BOM, no final newline, vertices after edges), strict about
//! values (every number finite and exactly representable, every id a valid `int`), loud about
//! anything it skips, and exact on output (shortest round-trip floats, so g2o -> TORO -> g2o
//! gives back every bit).

mod block;
pub mod g2o;
pub mod lexer;
mod options;
mod reader;
pub mod reader3;
pub mod toro;
pub mod trajectory;
mod writer;

pub use options::ReadOptions;
pub use reader::{ReadReport, read, read_path};
pub use reader3::read3;
pub use writer::{
    ConstantLines, Estimate, Pending, Staged, WriteOptions, check_output, constant_lines,
    constant_lines3, format_f64, hand_replaced_files_to, remove_temporary_files, stage_graph,
    stages, write, write_atomic, write_bytes_path, write_path, write_path_prepared,
    write_path_with, write3, write3_path, write3_path_prepared,
};

use crate::error::ParseErrorKind;
use crate::graph::{NoiseKind, PoseGraph};
use crate::graph3::Graph3;
use std::fmt;
use std::io::Read;

/// A graph of either dimension, as [`read_any`] and [`read_any_path`] return it.
#[derive(Debug, Clone, PartialEq)]
pub enum AnyGraph {
    /// A planar graph, read exactly as [`read`] reads it.
    Planar(PoseGraph),
    /// A 3D graph ([`read3`]).
    Spatial(Graph3),
}

/// Reads a planar or a 3D graph from a path (stdin for `-`): the planar reader first, exactly
/// as [`read_path`] (so planar files give the same graph, warnings and errors); if it stops at a
/// 3D tag ([`ParseErrorKind::ThreeD`]), the whole input is read again by [`read3`]. Input that
/// can be read only once (stdin, a FIFO such as a shell's `<(zcat graph.g2o.gz)`, a device) is
/// read once, as [`read_any_stream`] reads it.
pub fn read_any_path(path: &str, options: &ReadOptions) -> crate::Result<(AnyGraph, ReadReport)> {
    if path == "-" {
        let stdin = std::io::stdin();
        return read_any_stream(stdin.lock(), "<stdin>", options);
    }
    let io = |e| crate::Error::io(path, e);
    let mut file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() && !meta.is_dir() {
        return read_any_stream(file, path, options);
    }
    match read_path(path, options) {
        Err(crate::Error::Parse(e)) if matches!(e.kind, ParseErrorKind::ThreeD { .. }) => {
            let (graph, report) = match reader::mapped(&file, &meta) {
                Some(map) => read3(&map, path, options)?,
                None => {
                    let mut bytes = Vec::new();
                    file.read_to_end(&mut bytes).map_err(io)?;
                    read3(&bytes, path, options)?
                }
            };
            Ok((AnyGraph::Spatial(graph), report))
        }
        other => other.map(|(g, r)| (AnyGraph::Planar(g), r)),
    }
}

/// [`read_any_path`] on input read once (`name` is what messages call it): the planar reader
/// streams it, and a copy of what it consumed is kept (up to [`TEE_MAX`] bytes) for the 3D
/// reader, which reads that and the rest.
pub fn read_any_stream<R: Read>(
    input: R,
    name: &str,
    options: &ReadOptions,
) -> crate::Result<(AnyGraph, ReadReport)> {
    let mut tee = Tee {
        inner: input,
        kept: Vec::new(),
        complete: true,
    };
    match read(&mut tee, name, options) {
        Err(crate::Error::Parse(e))
            if matches!(e.kind, ParseErrorKind::ThreeD { .. }) && tee.complete =>
        {
            let mut bytes = std::mem::take(&mut tee.kept);
            tee.inner
                .read_to_end(&mut bytes)
                .map_err(|e| crate::Error::io(name, e))?;
            let (graph, report) = read3(&bytes, name, options)?;
            Ok((AnyGraph::Spatial(graph), report))
        }
        other => other.map(|(g, r)| (AnyGraph::Planar(g), r)),
    }
}

/// Bytes of input read once kept for the 3D reader while the planar reader streams it. Beyond
/// this the copy is dropped (memory stays bounded for planar input): a 3D tag that far into the
/// input (after 64 MB of other lines) is reported as the planar reader's error.
const TEE_MAX: usize = 64 << 20;

/// A reader that keeps a copy of what it reads, up to [`TEE_MAX`] bytes.
struct Tee<R> {
    inner: R,
    kept: Vec<u8>,
    /// Whether `kept` holds everything read so far.
    complete: bool,
}

impl<R: Read> Read for Tee<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        if self.complete {
            if self.kept.len() + n <= TEE_MAX {
                self.kept.extend_from_slice(&buf[..n]);
            } else {
                self.complete = false;
                self.kept = Vec::new();
            }
        }
        Ok(n)
    }
}

/// [`read_any_path`] on bytes in memory; `name` is the path used in messages.
pub fn read_any(
    bytes: &[u8],
    name: &str,
    options: &ReadOptions,
) -> crate::Result<(AnyGraph, ReadReport)> {
    match read(bytes, name, options) {
        Err(crate::Error::Parse(e)) if matches!(e.kind, ParseErrorKind::ThreeD { .. }) => {
            let (graph, report) = read3(bytes, name, options)?;
            Ok((AnyGraph::Spatial(graph), report))
        }
        other => other.map(|(g, r)| (AnyGraph::Planar(g), r)),
    }
}

/// A file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// g2o: `VERTEX_SE2`, `EDGE_SE2`, `FIX` (docs/formats.md §2).
    G2o,
    /// TORO: `VERTEX2`/`VERTEX`, `EDGE2`/`EDGE` (docs/formats.md §3).
    Toro,
}

impl Format {
    /// The format a file name suggests: `.g2o` is g2o, `.graph` is TORO; anything else (`.txt`,
    /// stdin) says nothing and the tags decide.
    pub fn from_extension(path: &str) -> Option<Format> {
        let ext = std::path::Path::new(path).extension()?.to_str()?;
        match ext.to_ascii_lowercase().as_str() {
            "g2o" => Some(Format::G2o),
            "graph" => Some(Format::Toro),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Format::G2o => "g2o",
            Format::Toro => "toro",
        }
    }

    /// The dialect files of this format use unless told otherwise.
    pub fn default_dialect(self) -> Dialect {
        match self {
            Format::G2o => Dialect::G2o,
            Format::Toro => Dialect::ToroInfo,
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How the six noise values of an edge line are to be read (docs/formats.md §7.2): their order and
/// whether they hold an information or a covariance matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Dialect {
    /// Information, g2o order `I11 I12 I13 I22 I23 I33` (g2o; GTSAM's readG2o).
    G2o,
    /// Information, TORO order `ff fs ss rr fr sr` (TORO, HOG-Man).
    ToroInfo,
    /// Covariance, TORO order (GTSAM's `.graph` files, read by `load2D` as covariances).
    ToroCov,
    /// Covariance, g2o order.
    G2oCov,
}

impl Dialect {
    pub const ALL: [Dialect; 4] = [
        Dialect::G2o,
        Dialect::ToroInfo,
        Dialect::ToroCov,
        Dialect::G2oCov,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Dialect::G2o => "g2o",
            Dialect::ToroInfo => "toro-info",
            Dialect::ToroCov => "toro-cov",
            Dialect::G2oCov => "g2o-cov",
        }
    }

    /// Whether the values are in TORO order (else g2o order).
    pub fn toro_order(self) -> bool {
        matches!(self, Dialect::ToroInfo | Dialect::ToroCov)
    }

    pub fn noise(self) -> NoiseKind {
        match self {
            Dialect::G2o | Dialect::ToroInfo => NoiseKind::Information,
            Dialect::ToroCov | Dialect::G2oCov => NoiseKind::Covariance,
        }
    }
}

impl fmt::Display for Dialect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
