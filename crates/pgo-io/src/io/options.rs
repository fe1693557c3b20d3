//! What the reader is told, in a module of its own that the reader and the block parser
//! ([`super::block`]) both import: the reader drives the block parser, never the other way.

use super::{Dialect, Format};

/// How to read a file.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// The format; `None`: by extension, else by the first pose tag.
    pub format: Option<Format>,
    /// The dialect; `None`: by the edge tags (see
    /// [`ReadReport::dialect_reason`](super::ReadReport::dialect_reason)).
    pub dialect: Option<Dialect>,
    /// Unknown tags are errors instead of warnings (EQUIV lines too, even with `ignore_equiv`).
    pub strict: bool,
    /// TORO's `EQUIV a b` lines (merge two vertices, which pgo does not implement) are skipped
    /// with a warning instead of being an error: the graph read is then the file's without them.
    pub ignore_equiv: bool,
    /// Accept noise matrices that are not positive definite.
    pub allow_indefinite: bool,
}
