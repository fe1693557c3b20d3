//! The TORO 2D format (docs/formats.md §3): `VERTEX2 id x y θ` (or `VERTEX`),
//! `EDGE2 i j dx dy dθ ff fs ss rr fr sr` (or `EDGE`; information in TORO's order, see
//! [`crate::graph::SymMat3::from_toro`]) and `EQUIV a b` (vertex merging: not implemented, an
//! error unless [`ReadOptions::ignore_equiv`](super::ReadOptions::ignore_equiv)).

/// Vertex tag pgo writes; TORO reads `VERTEX` too.
pub const VERTEX: &str = "VERTEX2";
/// Edge tag pgo writes; TORO reads `EDGE` too.
pub const EDGE: &str = "EDGE2";
/// Vertex tags TORO reads.
pub const VERTEX_TAGS: &[&str] = &["VERTEX2", "VERTEX"];
/// Edge tags TORO reads.
pub const EDGE_TAGS: &[&str] = &["EDGE2", "EDGE"];
/// Vertex equivalence (merge) constraint, as in GTSAM's w100.graph. TORO collapses the edge
/// between the two vertices (composing and fusing the edges of the second into the first, a
/// linearized approximation), which is not a pose graph problem pgo can certify.
pub const EQUIV: &str = "EQUIV";
/// 3D tags (docs/formats.md §3.4).
pub const THREE_D: &[&str] = &["VERTEX3", "EDGE3"];
/// Landmark tags of GTSAM's TORO-like files (docs/formats.md §5.2, §9.1).
/// (`LANDMARK2` is CPL-SLAM's landmark edge, read in [`super::g2o`].)
pub const LANDMARK: &[&str] = &["BR", "LANDMARK", "VERTEX_POINT2"];
