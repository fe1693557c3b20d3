//! Logging to the [rerun](https://rerun.io) viewer: what the `--rerun-save PATH.rrd`,
//! `--rerun-connect[=URL]` and `--rerun-spawn` flags of every tool record.
//!
//! The tools hold a [`Recorder`] and call it at a few points (the graph as read, the optimized
//! estimate, the certificate, the spectrum, solver iterations). A recorder started without any
//! of the flags does nothing, and so does every call on it; the flags never change the tool's
//! other outputs. What is logged is computed here by code that does not depend on rerun (and so
//! is tested in every build); the cargo feature `rerun` (on by default) adds the backend that
//! turns it into rerun archetypes and sends them. Without the feature the flags are still
//! accepted: `--rerun-save` is then an error (exit status 2) and the viewer flags a warning.
//!
//! Entity paths (README, "Viewing in rerun"); everything but the solver iterations is static:
//!
//! | path | archetype | what |
//! |---|---|---|
//! | `graph/poses` | Points2D | the poses as read (or generated), one point each; exact values in the components `pose_id`, `x`, `y`, `theta` |
//! | `graph/headings` | Arrows2D | each pose's heading |
//! | `graph/odometry` | LineStrips2D | edges with \|id_i − id_j\| = 1, one 2-point strip each; their ids in `from`, `to` |
//! | `graph/loop_closures` | LineStrips2D | the other edges, in another color |
//! | `graph/poses`, `graph/headings`, `graph/odometry`, `graph/loop_closures` of a 3D graph | Points3D, Arrows3D (each pose's x axis), LineStrips3D | the same in 3D; exact values `pose_id`, `x`, `y`, `z`, `qx`, `qy`, `qz`, `qw` |
//! | `graph/landmarks`, `graph/observations` | Points2D, LineStrips2D | landmarks and the rays of their observations |
//! | `optimized/...` | the same | the optimized estimate (`pgo-solve`), beside the input |
//! | `optimized/residuals` | LineStrips2D (LineStrips3D) | every edge colored by its term of the cost f (log scale, blue to red); the terms in `residual` |
//! | `optimized/landmark_residuals` | LineStrips2D | observation rays colored by their terms of f |
//! | `optimized/rejected` | LineStrips2D | `--robust`: the edges GNC rejected, red; r_e² in `residual` |
//! | `robust/weights` | LineStrips2D | `--robust`: every edge colored by its GNC weight (red 0 to blue 1) at each step of the timeline `gnc_iteration`; the weights in `weight` |
//! | `solver/NAME` | Scalars | one value per solver iteration on the timeline `iteration` |
//! | `spectrum/eigenvalues`, `spectrum/penalized_eigenvalues`, `spectrum/rotation_eigenvalues` | BarChart | the smallest eigenvalues of W, W(λ*), M, ascending |
//! | `spectrum/near_zero` | Scalars | eigenvalues of W(λ*) at zero (`szep` beside it) |
//! | `report/graph`, `report/spectrum`, `report/certificate` | TextLog | one-line summaries; the certificate's numbers also as components |

use crate::graph::PoseGraph;
use crate::graph3::Graph3;
use crate::problem::weights::{Weights, edge_weights};
use std::cell::Cell;
use std::rc::Rc;

/// The viewer's local address, where `--rerun-connect` without a URL sends the recording.
pub const DEFAULT_CONNECT_URL: &str = "rerun+http://127.0.0.1:9876/proxy";

/// How long a tool waits at its end for a viewer to take the recording.
pub const VIEWER_TIMEOUT_SECONDS: u64 = 5;

/// Where a recording goes: the `--rerun-*` flags.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Target {
    /// Write the recording to this `.rrd` file.
    pub save: Option<String>,
    /// Stream it to the viewer at this URL.
    pub connect: Option<String>,
    /// Start a viewer and stream to it.
    pub spawn: bool,
}

impl Target {
    /// True when no flag asks for a recording.
    pub fn is_empty(&self) -> bool {
        self.save.is_none() && self.connect.is_none() && !self.spawn
    }
}

/// An RGB color.
pub type Rgb = [u8; 3];

pub const POSE_COLOR: Rgb = [200, 200, 200];
pub const HEADING_COLOR: Rgb = [120, 210, 120];
pub const ODOMETRY_COLOR: Rgb = [90, 150, 240];
pub const LOOP_CLOSURE_COLOR: Rgb = [250, 140, 40];
/// Landmarks (issue 13) and the rays of their observations.
pub const LANDMARK_COLOR: Rgb = [225, 70, 200];
pub const OBSERVATION_COLOR: Rgb = [150, 150, 150];
/// Edges rejected by `--robust` (issue 14).
pub const REJECTED_COLOR: Rgb = [255, 30, 30];

/// The residual color scale, from the smallest term (first) to the largest (last).
pub const RESIDUAL_SCALE: [Rgb; 5] = [
    [60, 90, 255],
    [40, 200, 220],
    [110, 220, 70],
    [250, 200, 30],
    [240, 40, 40],
];

/// Sizes in UI points (independent of the graph's scale and of zooming).
const POINT_RADIUS: f32 = 1.0;
const LINE_RADIUS: f32 = 0.75;
const RESIDUAL_LINE_RADIUS: f32 = 1.25;
/// Observation rays: thinner than the edges, so that a landmark seen from many poses does not
/// hide the trajectory.
const OBSERVATION_RADIUS: f32 = 0.35;
const LANDMARK_RADIUS: f32 = 2.0;

/// The data of one entity, independent of rerun.
#[derive(Debug, Clone, PartialEq)]
pub enum Item {
    Points {
        positions: Vec<[f32; 2]>,
        color: Rgb,
        radius: f32,
    },
    Arrows {
        origins: Vec<[f32; 2]>,
        vectors: Vec<[f32; 2]>,
        color: Rgb,
        radius: f32,
    },
    /// Two-point strips; one color for all, or one per strip.
    Strips {
        strips: Vec<[[f32; 2]; 2]>,
        colors: Vec<Rgb>,
        radius: f32,
    },
    /// The 3D counterparts (3D graphs, issue 15): rerun's Points3D, Arrows3D, LineStrips3D.
    Points3 {
        positions: Vec<[f32; 3]>,
        color: Rgb,
        radius: f32,
    },
    Arrows3 {
        origins: Vec<[f32; 3]>,
        vectors: Vec<[f32; 3]>,
        color: Rgb,
        radius: f32,
    },
    Strips3 {
        strips: Vec<[[f32; 3]; 2]>,
        colors: Vec<Rgb>,
        radius: f32,
    },
    Bars(Vec<f64>),
    Scalar(f64),
    Text {
        text: String,
        warning: bool,
    },
}

/// When an entity's data holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum When {
    /// Always (rerun's static data).
    Static,
    /// At this step of the `iteration` timeline.
    Iteration(u64),
    /// At this GNC iteration (`pgo-solve --robust`), the `gnc_iteration` timeline.
    GncIteration(u64),
}

/// One logging call: the data at `path`, with exact values as extra components.
#[derive(Debug, Clone, PartialEq)]
pub struct Entity {
    pub path: String,
    pub item: Item,
    /// Named f64 columns logged beside the archetype (rerun `AnyValues`).
    pub values: Vec<(&'static str, Vec<f64>)>,
    pub when: When,
}

impl Entity {
    fn fixed(path: impl Into<String>, item: Item) -> Self {
        Entity {
            path: path.into(),
            item,
            values: Vec::new(),
            when: When::Static,
        }
    }

    fn with(mut self, name: &'static str, values: Vec<f64>) -> Self {
        self.values.push((name, values));
        self
    }
}

/// The certificate of an estimate, as `pgo-solve` (and later `pgo-certify`) reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Certificate {
    /// f at the estimate.
    pub cost: f64,
    /// Proven lower bound on f*.
    pub lower_bound: f64,
    pub certified: bool,
    pub szep: bool,
    /// Eigenvalues of W(λ*) at zero.
    pub near_zero: usize,
}

/// What `pgo-spectrum` computes: eigenvalue lists (ascending) and the SZEP.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spectrum<'a> {
    pub eigenvalues: &'a [f64],
    pub penalized_eigenvalues: &'a [f64],
    pub rotation_eigenvalues: &'a [f64],
    pub near_zero: usize,
    pub szep: bool,
    /// The proven lower bound on f* from λ*, if computed.
    pub lower_bound: Option<f64>,
}

/// Records what a tool computes, to an `.rrd` file and/or a viewer; does nothing when no
/// `--rerun-*` flag was given.
pub struct Recorder {
    inner: Option<backend::Inner>,
    /// The next step of the `iteration` timeline for [`Recorder::observe`].
    next_step: Rc<Cell<u64>>,
}

impl Recorder {
    /// A recorder that records nothing.
    pub fn disabled() -> Self {
        Recorder {
            inner: None,
            next_step: Rc::new(Cell::new(0)),
        }
    }

    /// Starts recording for `tool` (its name is the recording's application id) to `target`.
    /// Does nothing when `target` is empty. A `.rrd` path whose directory cannot be written is
    /// an error now, before the tool does any work; a viewer that cannot be started is a
    /// warning.
    pub fn start(tool: &'static str, target: &Target) -> crate::Result<Self> {
        let mut recorder = Recorder::disabled();
        if !target.is_empty() {
            recorder.inner = backend::Inner::start(tool, target)?;
        }
        Ok(recorder)
    }

    /// Whether anything is recorded.
    pub fn is_enabled(&self) -> bool {
        self.inner.is_some()
    }

    fn emit(&self, entities: impl FnOnce() -> Vec<Entity>) {
        if let Some(inner) = &self.inner {
            for entity in entities() {
                inner.emit(&entity);
            }
        }
    }

    /// The graph as read (or generated): `graph/...` and `report/graph`.
    pub fn graph(&self, graph: &PoseGraph) {
        self.emit(|| {
            let mut v = graph_entities("graph", graph);
            v.push(Entity::fixed(
                "report/graph",
                Item::Text {
                    text: graph_summary(graph),
                    warning: false,
                },
            ));
            v
        });
    }

    /// The optimized estimate (`optimized/...`) and its residuals under the weights `policy`.
    pub fn optimized(&self, graph: &PoseGraph, policy: Weights) {
        self.emit(|| {
            let mut v = graph_entities("optimized", graph);
            if let Ok(weights) = edge_weights(graph, policy) {
                v.push(residual_entity("optimized/residuals", graph, &weights));
                if !graph.landmarks.is_empty() {
                    v.push(landmark_residual_entity(
                        "optimized/landmark_residuals",
                        graph,
                        &weights,
                    ));
                }
            }
            v
        });
    }

    /// A 3D graph as read (or generated): `graph/...` (3D entities) and `report/graph`.
    pub fn graph3(&self, graph: &Graph3) {
        self.emit(|| {
            let mut v = graph3_entities("graph", graph);
            v.push(Entity::fixed(
                "report/graph",
                Item::Text {
                    text: graph3_summary(graph),
                    warning: false,
                },
            ));
            v
        });
    }

    /// A 3D estimate (`optimized/...`) and its residuals: each edge's term of SE-Sync's f
    /// under its weights (`unit`: τ = κ = 1).
    pub fn optimized3(&self, graph: &Graph3, unit: bool) {
        self.emit(|| {
            let mut v = graph3_entities("optimized", graph);
            if let Ok(weights) = crate::se3::problem::weights3(graph, unit) {
                v.push(residual3_entity("optimized/residuals", graph, &weights));
            }
            v
        });
    }

    /// What `--robust` found, on the estimate `graph` ([`robust_entities`]): the rejected
    /// edges, and every edge's GNC weight at each GNC iteration.
    pub fn robust(
        &self,
        graph: &PoseGraph,
        rejected: &[bool],
        residuals: &[f64],
        weights_by_iteration: &[&[f64]],
    ) {
        self.emit(|| robust_entities(graph, rejected, residuals, weights_by_iteration));
    }

    /// The certificate: `report/certificate`, text and values.
    pub fn certificate(&self, c: &Certificate) {
        self.emit(|| vec![certificate_entity(c)]);
    }

    /// Eigenvalues and the SZEP: `spectrum/...` and `report/spectrum`.
    pub fn spectrum(&self, s: &Spectrum<'_>) {
        self.emit(|| spectrum_entities(s));
    }

    /// One solver iteration at `step` of the `iteration` timeline: each value goes to
    /// `solver/NAME` (e.g. `("cost", f)`, `("gradient_norm", g)`, `("rank", r)`,
    /// `("trust_region_radius", delta)`).
    pub fn iteration(&self, step: u64, values: &[(&str, f64)]) {
        self.emit(|| iteration_entities(step, values));
    }

    /// Runs `body`, recording the iterations that solvers report inside it through
    /// [`crate::progress::iteration`]. Steps of the `iteration` timeline count the reported
    /// iterations of the whole run, so several solves (components, restarts) follow one another.
    pub fn observe<T>(&self, body: impl FnOnce() -> T) -> T {
        match &self.inner {
            Some(inner) => crate::progress::observe(inner.observer(self.next_step.clone()), body),
            None => body(),
        }
    }

    /// Ends the recording: writes the `.rrd` file (to a temporary file renamed into place, so a
    /// failure leaves no partial file; a failure is an error) and waits up to
    /// [`VIEWER_TIMEOUT_SECONDS`] for the viewers (a viewer that cannot be reached is a
    /// warning).
    pub fn finish(self) -> crate::Result<()> {
        match self.inner {
            Some(inner) => inner.finish(),
            None => Ok(()),
        }
    }
}

#[cfg(not(feature = "rerun"))]
#[path = "no_viewer.rs"]
mod backend;
#[cfg(feature = "rerun")]
#[path = "rerun_backend.rs"]
mod backend;
mod entities;

pub use entities::*;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, NoiseKind, Pose2, SymMat3};

    fn square() -> PoseGraph {
        let poses = vec![
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(1.0, 0.0, std::f64::consts::FRAC_PI_2),
            Pose2::new(1.0, 1.0, std::f64::consts::PI),
            Pose2::new(0.0, 1.0, -std::f64::consts::FRAC_PI_2),
        ];
        let edge = |i: usize, j: usize| Edge {
            i,
            j,
            measurement: Pose2::new(1.0, 0.0, std::f64::consts::FRAC_PI_2),
            noise: SymMat3([1.0, 0.0, 0.0, 1.0, 0.0, 1.0]),
        };
        PoseGraph {
            ids: vec![0, 1, 2, 3],
            poses,
            edges: vec![edge(0, 1), edge(1, 2), edge(2, 3), edge(3, 0)],
            fixed: Vec::new(),
            vertices_declared: true,
            noise: NoiseKind::Information,
            landmarks: Default::default(),
        }
    }

    #[test]
    fn graph_entities_split_odometry_and_loop_closures() {
        let g = square();
        let v = graph_entities("graph", &g);
        let paths: Vec<&str> = v.iter().map(|e| e.path.as_str()).collect();
        assert_eq!(
            paths,
            [
                "graph/poses",
                "graph/headings",
                "graph/odometry",
                "graph/loop_closures"
            ]
        );
        let Item::Points { positions, .. } = &v[0].item else {
            panic!("not points")
        };
        assert_eq!(positions.len(), 4);
        assert_eq!(positions[2], [1.0, 1.0]);
        let strips = |k: usize| match &v[k].item {
            Item::Strips { strips, .. } => strips.clone(),
            _ => panic!("not strips"),
        };
        assert_eq!(strips(2).len(), 3);
        assert_eq!(strips(3), vec![[[0.0, 1.0], [0.0, 0.0]]]);
        assert_eq!(v[3].values[0], ("from", vec![3.0]));
        assert_eq!(v[3].values[1], ("to", vec![0.0]));
        // Headings: half the median measurement length (1), along theta.
        let Item::Arrows { vectors, .. } = &v[1].item else {
            panic!("not arrows")
        };
        assert!((vectors[1][0]).abs() < 1e-7 && (vectors[1][1] - 0.5).abs() < 1e-7);
        assert_eq!(
            graph_summary(&g),
            "4 poses, 4 edges (3 odometry, 1 loop closures)"
        );
    }

    #[test]
    fn landmarks_are_points_and_rays_and_their_residuals_terms_of_the_cost() {
        use crate::graph::{LandmarkForm, Landmarks, Observation, SymMat2};
        let mut g = square();
        g.landmarks = Landmarks {
            ids: vec![10, 11],
            positions: vec![[0.5, 0.5], [2.0, 0.0]],
            observations: vec![
                // Pose 0 (identity) sees landmark 10 at (0.5, 0.5): residual 0.
                Observation {
                    pose: 0,
                    landmark: 0,
                    d: [0.5, 0.5],
                    information: SymMat2::IDENTITY,
                },
                // Pose 1 sees landmark 11 off by (0, 1) in its frame: residual ν·1 = 1.
                Observation {
                    pose: 1,
                    landmark: 1,
                    d: [1.0, 1.0],
                    information: SymMat2::IDENTITY,
                },
            ],
            declared: true,
            form: LandmarkForm::G2o,
        };
        g.poses[1] = crate::graph::Pose2::new(1.0, 0.0, 0.0);
        let v = graph_entities("graph", &g);
        let landmarks = v.iter().find(|e| e.path == "graph/landmarks").unwrap();
        let Item::Points {
            positions, color, ..
        } = &landmarks.item
        else {
            panic!("not points")
        };
        assert_eq!((positions.len(), *color), (2, LANDMARK_COLOR));
        let rays = v.iter().find(|e| e.path == "graph/observations").unwrap();
        let Item::Strips { strips, .. } = &rays.item else {
            panic!("not strips")
        };
        assert_eq!(strips[1], [[1.0, 0.0], [2.0, 0.0]]);
        let w = edge_weights(&g, Weights::Unit).unwrap();
        let e = landmark_residual_entity("optimized/landmark_residuals", &g, &w);
        let residual = &e.values.iter().find(|(n, _)| *n == "residual").unwrap().1;
        assert_eq!(residual, &vec![0.0, 1.0]);
        // Edge terms plus observation terms are the cost.
        let edges = residual_entity("optimized/residuals", &g, &w);
        let edge_total: f64 = edges
            .values
            .iter()
            .find(|(n, _)| *n == "residual")
            .unwrap()
            .1
            .iter()
            .sum();
        let x: Vec<crate::graph::Pose2> = g
            .poses
            .iter()
            .copied()
            .chain(
                g.landmarks
                    .positions
                    .iter()
                    .map(|&[x, y]| crate::graph::Pose2::new(x, y, 0.0)),
            )
            .collect();
        let total = edge_total + residual.iter().sum::<f64>();
        assert!((total - crate::problem::matrix::cost(&g, &w, &x)).abs() < 1e-12);
        assert!(graph_summary(&g).ends_with(", 2 landmarks, 2 observations"));
    }

    #[test]
    fn residuals_are_the_terms_of_the_cost() {
        let mut g = square();
        g.poses[2].x += 0.5; // breaks edges 1->2 and 2->3
        let w = edge_weights(&g, Weights::Unit).unwrap();
        let e = residual_entity("optimized/residuals", &g, &w);
        let residual = &e.values.iter().find(|(n, _)| *n == "residual").unwrap().1;
        let total: f64 = residual.iter().sum();
        assert!((total - crate::problem::matrix::cost(&g, &w, &g.poses)).abs() < 1e-12);
        assert_eq!(residual[0], 0.0);
        assert!(residual[1] > 0.0 && residual[2] > 0.0);
        let Item::Strips { colors, strips, .. } = &e.item else {
            panic!("not strips")
        };
        assert_eq!((colors.len(), strips.len()), (4, 4));
        assert_eq!(colors[0], RESIDUAL_SCALE[0]);
    }

    #[test]
    fn rejected_edges_apart_and_gnc_weights_per_iteration() {
        let g = square();
        // Edge 2 (ids 2 -> 3, from (1, 1) to (0, 1)) rejected; two GNC iterations.
        let rejected = [false, false, true, false];
        let residuals = [0.0, 0.0, 9.0, 0.0];
        let first = [1.0, 1.0, 0.5, 1.0];
        let last = [1.0, 1.0, 0.0, 1.0];
        let v = robust_entities(&g, &rejected, &residuals, &[&first, &last]);
        assert_eq!(v.len(), 3);
        assert_eq!(v[0].path, "optimized/rejected");
        assert_eq!(v[0].when, When::Static);
        let Item::Strips { strips, colors, .. } = &v[0].item else {
            panic!("not strips")
        };
        assert_eq!(strips, &vec![[[1.0f32, 1.0], [0.0, 1.0]]]);
        assert_eq!(colors, &vec![REJECTED_COLOR]);
        let column =
            |e: &Entity, name: &str| e.values.iter().find(|(n, _)| *n == name).unwrap().1.clone();
        assert_eq!(column(&v[0], "from"), vec![2.0]);
        assert_eq!(column(&v[0], "to"), vec![3.0]);
        assert_eq!(column(&v[0], "residual"), vec![9.0]);
        assert_eq!(
            (v[1].when, v[2].when),
            (When::GncIteration(1), When::GncIteration(2))
        );
        let Item::Strips { strips, colors, .. } = &v[1].item else {
            panic!("not strips")
        };
        assert_eq!(strips.len(), 4);
        // Weight 1 is the odometry blue; ½ halfway to red: (255+90)/2, (30+150)/2, (30+240)/2.
        assert_eq!(colors[0], ODOMETRY_COLOR);
        assert_eq!(colors[2], [173, 90, 135]);
        let Item::Strips { colors, .. } = &v[2].item else {
            panic!("not strips")
        };
        assert_eq!(colors[2], REJECTED_COLOR);
        assert_eq!(column(&v[2], "weight"), last.to_vec());
    }

    #[test]
    fn color_scale_ends_and_log_positions() {
        assert_eq!(scale_color(0.0), RESIDUAL_SCALE[0]);
        assert_eq!(scale_color(1.0), RESIDUAL_SCALE[4]);
        assert_eq!(scale_color(0.5), RESIDUAL_SCALE[2]);
        assert_eq!(scale_color(f64::NAN), RESIDUAL_SCALE[0]);
        assert_eq!(residual_position(10.0, 0.1, 1000.0), 0.5);
        assert_eq!(residual_position(0.0, 0.1, 1000.0), 0.0);
        assert_eq!(residual_position(5.0, 5.0, 5.0), 0.0);
    }

    #[test]
    fn iterations_and_reports() {
        let v = iteration_entities(7, &[("cost", 2.0), ("trust-region radius", 0.5)]);
        assert_eq!(v[0].path, "solver/cost");
        assert_eq!(v[1].path, "solver/trust_region_radius");
        assert_eq!(v[1].when, When::Iteration(7));
        let c = certificate_entity(&Certificate {
            cost: 2.0,
            lower_bound: 1.5,
            certified: false,
            szep: true,
            near_zero: 1,
        });
        let Item::Text { text, warning } = &c.item else {
            panic!("not text")
        };
        assert!(warning);
        assert!(text.contains("cost 2, proven lower bound 1.5, suboptimality <= 0.5"));
        let s = spectrum_entities(&Spectrum {
            eigenvalues: &[0.0, 1.0],
            penalized_eigenvalues: &[0.0, 0.0, 2.0],
            rotation_eigenvalues: &[3.0],
            near_zero: 2,
            szep: false,
            lower_bound: Some(0.25),
        });
        assert_eq!(s[1].item, Item::Bars(vec![0.0, 0.0, 2.0]));
        assert_eq!(s[3].item, Item::Scalar(2.0));
    }

    #[test]
    fn a_recorder_without_flags_records_nothing() {
        let r = Recorder::start("pgo-test", &Target::default()).unwrap();
        assert!(!r.is_enabled());
        r.graph(&square());
        assert_eq!(r.observe(|| 5), 5);
        r.finish().unwrap();
    }

    /// 3D graphs: one point and arrow per pose, edges split as in 2D, and the residuals the
    /// terms of f, summing to the solver's cost tr(XᵀQX) of the same poses (Q assembled in
    /// se3::problem, the terms here evaluated directly).
    #[test]
    fn graph3_entities_and_residuals_sum_to_the_cost() {
        use crate::simulate::space::{SpaceConfig, World3, simulate3};
        use crate::simulate::{RotationNoise, TranslationNoise};
        let sim = simulate3(&SpaceConfig {
            world: World3::Torus,
            n: 25,
            side: 10.0,
            loop_probability: 1.0,
            rotation_noise: RotationNoise::Gaussian { sigma: 0.1 },
            translation_noise: TranslationNoise::Gaussian { sigma: 0.2 },
            seed: 1,
        });
        let g = &sim.graph;
        let v = graph3_entities("graph", g);
        let Item::Points3 { positions, .. } = &v[0].item else {
            panic!("poses")
        };
        assert_eq!(positions.len(), 25);
        let Item::Arrows3 { vectors, .. } = &v[1].item else {
            panic!("headings")
        };
        assert_eq!(vectors.len(), 25);
        let count = |k: usize| match &v[k].item {
            Item::Strips3 { strips, .. } => strips.len(),
            _ => panic!("strips"),
        };
        assert_eq!(count(2), 24, "the odometry path");
        assert_eq!(count(2) + count(3), g.edges.len());
        let w = crate::se3::problem::weights3(g, false).unwrap();
        let e = residual3_entity("optimized/residuals", g, &w);
        let total: f64 = e
            .values
            .iter()
            .find(|(n, _)| *n == "residual")
            .unwrap()
            .1
            .iter()
            .sum();
        let problem = crate::se3::problem::Problem3::new(g, &w, 0);
        let truth: Vec<_> = g.poses.iter().map(crate::se3::rt_of).collect();
        let cost = problem.cost(&crate::se3::rounding::point_of(&problem, &truth));
        assert!((total - cost).abs() <= 1e-9 * cost, "{total} vs {cost}");
    }
}
