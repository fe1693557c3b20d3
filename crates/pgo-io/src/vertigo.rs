//! Vertigo's robust edge types (Sünderhauf and Protzel's switchable constraints, Olson and
//! Agarwal's max-mixtures; openslam_vertigo, docs/formats.md §9.2), kept beside the graph:
//!
//! - `VERTEX_SWITCH id value`: a switch variable;
//! - `EDGE_SWITCH_PRIOR id prior information`: its prior;
//! - `EDGE_SE2_SWITCHABLE i j s dx dy dθ I11 I12 I13 I22 I23 I33`: a loop closure gated by
//!   switch `s`;
//! - `EDGE_SE2_MAXMIX i j w dx dy dθ I11 I12 I13 I22 I23 I33`: a loop closure with the weight `w`
//!   of its null hypothesis.
//!
//! The reader takes the switchable and max-mixture edges into the graph as the loop closures they
//! measure (candidates for a robust back end) and keeps what the graph has no room for here,
//! switch variables, priors, the edges' kinds, so that the writers give every line back.

use crate::graph::VertexId;

/// g2o tag of a switch variable.
pub const VERTEX_SWITCH: &str = "VERTEX_SWITCH";
/// g2o tag of a switch prior.
pub const EDGE_SWITCH_PRIOR: &str = "EDGE_SWITCH_PRIOR";
/// g2o tag of a switchable loop closure.
pub const EDGE_SWITCHABLE: &str = "EDGE_SE2_SWITCHABLE";
/// g2o tag of a max-mixture loop closure.
pub const EDGE_MAXMIX: &str = "EDGE_SE2_MAXMIX";

/// What kind of line an edge came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EdgeKind {
    /// `EDGE_SE2` (or a TORO edge).
    Plain,
    /// `EDGE_SE2_SWITCHABLE`, with its switch's id.
    Switchable { switch: VertexId },
    /// `EDGE_SE2_MAXMIX`, with the weight of its null hypothesis.
    MaxMix { weight: f64 },
}

/// A `VERTEX_SWITCH` line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwitchVertex {
    pub id: VertexId,
    pub value: f64,
}

/// An `EDGE_SWITCH_PRIOR` line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwitchPrior {
    pub id: VertexId,
    pub prior: f64,
    pub information: f64,
}

/// Vertigo's lines of a file, beside its [`crate::PoseGraph`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Vertigo {
    /// The kind of every edge of the graph, in its order.
    pub kinds: Vec<EdgeKind>,
    /// Switch variables, in file order.
    pub switches: Vec<SwitchVertex>,
    /// Switch priors, in file order.
    pub priors: Vec<SwitchPrior>,
}

impl Vertigo {
    /// Edges of each kind: (switchable, max-mixture).
    pub fn counts(&self) -> (usize, usize) {
        let switchable = self
            .kinds
            .iter()
            .filter(|k| matches!(k, EdgeKind::Switchable { .. }))
            .count();
        let maxmix = self
            .kinds
            .iter()
            .filter(|k| matches!(k, EdgeKind::MaxMix { .. }))
            .count();
        (switchable, maxmix)
    }

    /// The kinds of the edges kept, `keep[k]` for edge k (switches and priors stay: a switch of
    /// a dropped edge is then a variable no edge uses, as Vertigo's own files can have).
    pub fn retain_edges(&mut self, keep: &[bool]) {
        let mut k = 0;
        self.kinds.retain(|_| {
            k += 1;
            keep[k - 1]
        });
    }
}
