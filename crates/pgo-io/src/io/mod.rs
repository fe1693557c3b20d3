//! Reading and writing planar pose graphs in the g2o and TORO text formats, losslessly.
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
pub mod toro;
mod writer;

pub use options::ReadOptions;
pub use reader::{ReadReport, read, read_path};
pub use writer::{
    Pending, WriteOptions, check_output, format_f64, remove_temporary_files, write,
    write_bytes_path, write_path,
};

use crate::graph::NoiseKind;
use std::fmt;

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
