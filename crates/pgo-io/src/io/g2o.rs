//! The g2o 2D format (docs/formats.md §2): `VERTEX_SE2 id x y θ`,
//! `EDGE_SE2 i j dx dy dθ I11 I12 I13 I22 I23 I33` (information, upper triangle row by row) and
//! `FIX id ...`.

/// Vertex tag.
pub const VERTEX: &str = "VERTEX_SE2";
/// Edge tag.
pub const EDGE: &str = "EDGE_SE2";
/// Gauge-fixing line; several ids per line, anywhere in the file.
pub const FIX: &str = "FIX";

/// g2o tags of 3D types (docs/formats.md §2.6), rejected with a specific message.
pub const THREE_D: &[&str] = &[
    "VERTEX_SE3:QUAT",
    "EDGE_SE3:QUAT",
    "VERTEX_SE3:EXPMAP",
    "EDGE_SE3:EXPMAP",
    "VERTEX_TRACKXYZ",
    "EDGE_SE3_TRACKXYZ",
    "EDGE_SE3_PRIOR",
    "EDGE_SE3_XYZ_PRIOR",
    "PARAMS_SE3OFFSET",
    "EDGE_POINTXYZ",
    "EDGE_POINTXYZ_PRIOR",
];

/// g2o's 2D landmark vertex: `VERTEX_XY id x y` (docs/formats.md §2.1).
pub const LANDMARK_VERTEX: &str = "VERTEX_XY";
/// g2o's pose-landmark edge: `EDGE_SE2_XY pose point dx dy I11 I12 I22` (docs/formats.md §2.1).
pub const LANDMARK_EDGE: &str = "EDGE_SE2_XY";
/// CPL-SLAM's pose-landmark edge, landmark ids in their own id space (docs/formats.md §9.1):
/// `LANDMARK2 pose landmark dx dy I11 I12 I22`.
pub const LANDMARK2: &str = "LANDMARK2";
/// Landmark positions beside `LANDMARK2` lines: `POINT2 id x y`, pgo's layout (CPL-SLAM's reader
/// skips `POINT2` lines, docs/formats.md §9.1), so that written estimates carry the positions.
pub const POINT2: &str = "POINT2";

/// g2o tags of the other 2D landmark types (docs/formats.md §2.1), rejected with a specific
/// message.
pub const LANDMARK: &[&str] = &[
    "EDGE_SE2_POINTXY",
    "EDGE_POINTXY",
    "EDGE_PRIOR_XY",
    "EDGE_BEARING_SE2_XY",
    "EDGE_SE2_XY_CALIB",
    "EDGE_SE2_POINTXY_OFFSET",
    "EDGE_SE2_TWOPOINTSXY",
    "EDGE_SE2_LOTSOFXY",
];

/// g2o tags of unary priors on poses (`EDGE_SE2_PRIOR` is a common misspelling g2o itself does
/// not register).
pub const PRIOR: &[&str] = &["EDGE_PRIOR_SE2", "EDGE_PRIOR_SE2_XY", "EDGE_SE2_PRIOR"];
