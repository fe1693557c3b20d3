//! Typed errors of the file layer. Every input error carries `PATH:LINE:COL` (docs/method.md §4);
//! tools print them on stderr and exit with status 2.

use std::fmt;
use thiserror::Error;

/// A place in an input file: 1-based line and column (columns count bytes after a UTF-8 BOM).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    pub path: String,
    pub line: usize,
    pub col: usize,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.path, self.line, self.col)
    }
}

/// What is wrong with an input line.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ParseErrorKind {
    #[error("{tag} takes {expected} fields after the tag ({layout}), found {found}")]
    FieldCount {
        tag: String,
        expected: usize,
        found: usize,
        layout: &'static str,
    },
    #[error("FIX takes one or more vertex ids, found none")]
    NoFixIds,
    #[error("expected a number, found '{token}'{hint}")]
    NotANumber { token: String, hint: &'static str },
    #[error("'{token}' is out of the range of a 64-bit float ({what})")]
    OutOfRange { token: String, what: &'static str },
    #[error("invalid vertex id '{token}': {reason}")]
    InvalidId { token: String, reason: &'static str },
    #[error("vertex {id} is declared twice (first at line {first_line})")]
    DuplicateVertex { id: u32, first_line: usize },
    #[error("edge refers to vertex {id}, which no vertex line declares")]
    UndeclaredVertex { id: u32 },
    #[error("FIX names vertex {id}, which is not in the graph")]
    UnknownFixed { id: u32 },
    #[error("self-loop: edge from vertex {id} to itself")]
    SelfLoop { id: u32 },
    #[error(
        "the {what} matrix is not positive definite (pivot {pivot} of its Cholesky factorization is not positive; read in dialect {dialect}){hint}; pass --allow-indefinite to accept it"
    )]
    NotPositiveDefinite {
        what: &'static str,
        pivot: usize,
        dialect: &'static str,
        hint: &'static str,
    },
    #[error(
        "3D pose graph (tag {tag}): this tool handles planar SE(2) graphs only (pgo-solve and pgo-certify solve and certify 3D files, pgo-spectrum prints their spectra, pgo-eval compares them; pgo-convert reads, writes and describes them)"
    )]
    ThreeD { tag: String },
    #[error(
        "this 3D type is not supported (tag {tag}): pgo reads 3D pose graphs as g2o's VERTEX_SE3:QUAT and EDGE_SE3:QUAT or TORO's VERTEX3 and EDGE3"
    )]
    Unsupported3D { tag: String },
    #[error(
        "planar and 3D tags in one file ({first} at line {first_line}, {tag} here): a file is a planar or a 3D pose graph, not both"
    )]
    MixedDimensions {
        first: String,
        first_line: usize,
        tag: String,
    },
    #[error(
        "3D lines of both forms in one file ({first} at line {first_line}, {tag} here): g2o's quaternions and TORO's Euler angles parametrize rotations, and their information, differently"
    )]
    Mixed3dForms {
        first: String,
        first_line: usize,
        tag: String,
    },
    #[error(
        "the {block} block of the information matrix is not positive definite (pivot {pivot} of its Cholesky factorization is not positive); pass --allow-indefinite to accept it"
    )]
    BlockNotPositiveDefinite { block: &'static str, pivot: usize },
    #[error(
        "the quaternion (qx qy qz qw) cannot be normalized (its norm is zero, or the sum of its squares underflows to zero or overflows): the rotation is q / |q|, as g2o reads it"
    )]
    BadQuaternion,
    #[error(
        "this landmark type is not supported (tag {tag}): pgo reads landmarks as g2o's VERTEX_XY and EDGE_SE2_XY (position observations) and CPL-SLAM's LANDMARK2"
    )]
    Landmark { tag: String },
    #[error(
        "landmark lines of both forms in one file ({first} at line {first_line}, {tag} here): g2o's VERTEX_XY/EDGE_SE2_XY share the poses' id space, CPL-SLAM's LANDMARK2/POINT2 have their own; convert one of them with pgo-convert --landmarks"
    )]
    MixedLandmarkForms {
        first: String,
        first_line: usize,
        tag: String,
    },
    #[error("vertex {id} is a landmark, where a pose is expected")]
    NotAPose { id: u32 },
    #[error("vertex {id} is a pose, where a landmark is expected")]
    NotALandmark { id: u32 },
    #[error("{tag} refers to landmark {id}, which no {vertex} line declares")]
    UndeclaredLandmark {
        tag: &'static str,
        id: u32,
        vertex: &'static str,
    },
    #[error("FIX names landmark {id}: pgo fixes poses only (the gauge is a pose's)")]
    FixedLandmark { id: u32 },
    #[error(
        "the landmark information matrix (I11 I12 I22) is not positive definite (pivot {pivot} of its Cholesky factorization is not positive); pass --allow-indefinite to accept it"
    )]
    LandmarkNotPositiveDefinite { pivot: usize },
    #[error(
        "unary priors are not supported (tag {tag}): pgo fixes the gauge itself; FIX lines are kept"
    )]
    Prior { tag: String },
    #[error(
        "EQUIV (TORO's vertex equivalence: merge two vertices) is not supported, and the graph without it is another problem; pass --ignore-equiv to skip EQUIV lines and solve that one"
    )]
    Equiv,
    #[error(
        "no line of the input was understood (unknown tag '{tag}' here, {lines} such line{s} in all): not a g2o (VERTEX_SE2, EDGE_SE2) or TORO (VERTEX2, EDGE2) pose graph",
        s = if *lines == 1 { "" } else { "s" }
    )]
    NothingUnderstood { tag: String, lines: usize },
    #[error("{}", if *empty {
        "the input is empty: no vertex or edge lines, no pose graph"
    } else {
        "no vertex or edge lines in the input: no pose graph"
    })]
    NoGraph { empty: bool },
    #[error("unknown tag '{tag}'")]
    UnknownTag { tag: String },
    #[error(
        "edge tags of both formats in one file ({first} at line {first_line}, {tag} here): pass --dialect to say how to read the information values"
    )]
    MixedTags {
        first: String,
        first_line: usize,
        tag: String,
    },
}

/// An input error at a location.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{location}: {kind}")]
pub struct ParseError {
    pub location: Location,
    pub kind: ParseErrorKind,
}

/// A warning at a location (unknown tags, skipped lines, guesses the reader made).
#[derive(Debug, Clone, PartialEq)]
pub struct Warning {
    pub location: Location,
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: warning: {}", self.location, self.message)
    }
}

/// Everything reading and writing can fail with.
#[derive(Debug, Error)]
pub enum Error {
    #[error(transparent)]
    Parse(#[from] ParseError),
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// A request that cannot be carried out (bad combination of flags, unwritable value...).
    #[error("{0}")]
    Invalid(String),
}

impl Error {
    pub fn io(path: impl Into<String>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;
