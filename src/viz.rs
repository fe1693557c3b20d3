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
//! | `optimized/...` | the same | the optimized estimate (`pgo-solve`), beside the input |
//! | `optimized/residuals` | LineStrips2D | every edge colored by its term of the cost f (log scale, blue to red); the terms in `residual` |
//! | `solver/NAME` | Scalars | one value per solver iteration on the timeline `iteration` |
//! | `spectrum/eigenvalues`, `spectrum/penalized_eigenvalues`, `spectrum/rotation_eigenvalues` | BarChart | the smallest eigenvalues of W, W(λ*), M, ascending |
//! | `spectrum/near_zero` | Scalars | eigenvalues of W(λ*) at zero (`szep` beside it) |
//! | `report/graph`, `report/spectrum`, `report/certificate` | TextLog | one-line summaries; the certificate's numbers also as components |

use crate::graph::PoseGraph;
use crate::weights::{Weights, edge_weights};
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
            }
            v
        });
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

/// Formats a number for the text entries: shortest round-trip form.
fn num(v: f64) -> String {
    if v.is_finite() {
        let mut out = Vec::new();
        crate::io::format_f64(v, &mut out);
        String::from_utf8_lossy(&out).into_owned()
    } else {
        v.to_string()
    }
}

fn point(x: f64, y: f64) -> [f32; 2] {
    [x as f32, y as f32]
}

/// Whether an edge counts as odometry: consecutive ids (|id_i − id_j| = 1).
pub fn is_odometry(graph: &PoseGraph, e: &crate::graph::Edge) -> bool {
    graph.ids[e.i].abs_diff(graph.ids[e.j]) == 1
}

/// Length of the heading arrows: half the median length of the edges' translation
/// measurements (1 when there is none).
pub fn heading_length(graph: &PoseGraph) -> f64 {
    let mut lengths: Vec<f64> = graph
        .edges
        .iter()
        .map(|e| e.measurement.x.hypot(e.measurement.y))
        .filter(|l| l.is_finite() && *l > 0.0)
        .collect();
    if lengths.is_empty() {
        return 1.0;
    }
    lengths.sort_by(f64::total_cmp);
    0.5 * lengths[lengths.len() / 2]
}

/// The entities of a graph under `root`: poses, headings, odometry, loop closures.
pub fn graph_entities(root: &str, graph: &PoseGraph) -> Vec<Entity> {
    let positions: Vec<[f32; 2]> = graph.poses.iter().map(|p| point(p.x, p.y)).collect();
    let length = heading_length(graph);
    let vectors = graph
        .poses
        .iter()
        .map(|p| point(length * p.theta.cos(), length * p.theta.sin()))
        .collect();
    let column = |f: &dyn Fn(&crate::graph::Pose2) -> f64| graph.poses.iter().map(f).collect();
    let mut entities = vec![
        Entity::fixed(
            format!("{root}/poses"),
            Item::Points {
                positions: positions.clone(),
                color: POSE_COLOR,
                radius: POINT_RADIUS,
            },
        )
        .with(
            "pose_id",
            graph.ids.iter().map(|&id| f64::from(id)).collect(),
        )
        .with("x", column(&|p| p.x))
        .with("y", column(&|p| p.y))
        .with("theta", column(&|p| p.theta)),
        Entity::fixed(
            format!("{root}/headings"),
            Item::Arrows {
                origins: positions,
                vectors,
                color: HEADING_COLOR,
                radius: LINE_RADIUS,
            },
        ),
    ];
    for (name, odometry, color) in [
        ("odometry", true, ODOMETRY_COLOR),
        ("loop_closures", false, LOOP_CLOSURE_COLOR),
    ] {
        let edges: Vec<_> = graph
            .edges
            .iter()
            .filter(|e| is_odometry(graph, e) == odometry)
            .collect();
        let strips = edges
            .iter()
            .map(|e| {
                let (a, b) = (graph.poses[e.i], graph.poses[e.j]);
                [point(a.x, a.y), point(b.x, b.y)]
            })
            .collect();
        entities.push(
            Entity::fixed(
                format!("{root}/{name}"),
                Item::Strips {
                    strips,
                    colors: vec![color],
                    radius: LINE_RADIUS,
                },
            )
            .with(
                "from",
                edges.iter().map(|e| f64::from(graph.ids[e.i])).collect(),
            )
            .with(
                "to",
                edges.iter().map(|e| f64::from(graph.ids[e.j])).collect(),
            ),
        );
    }
    entities
}

/// "N poses, M edges (K odometry, L loop closures)".
pub fn graph_summary(graph: &PoseGraph) -> String {
    let odometry = graph.edges.iter().filter(|e| is_odometry(graph, e)).count();
    format!(
        "{} poses, {} edges ({odometry} odometry, {} loop closures)",
        graph.num_poses(),
        graph.edges.len(),
        graph.edges.len() - odometry
    )
}

/// Position of `value` on the residual color scale, in [0, 1]: logarithmic between the smallest
/// positive residual and the largest (at most twelve decades); zero and below map to 0.
pub fn residual_position(value: f64, min_positive: f64, max: f64) -> f64 {
    if !(value > 0.0 && max > min_positive && min_positive > 0.0) {
        return 0.0;
    }
    let lo = min_positive.max(max * 1e-12).log10();
    let hi = max.log10();
    ((value.log10() - lo) / (hi - lo)).clamp(0.0, 1.0)
}

/// The color at position `t` ∈ [0, 1] of [`RESIDUAL_SCALE`], interpolated linearly.
pub fn scale_color(t: f64) -> Rgb {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let segments = (RESIDUAL_SCALE.len() - 1) as f64;
    let x = t * segments;
    let k = (x.floor() as usize).min(RESIDUAL_SCALE.len() - 2);
    let f = x - k as f64;
    let (a, b) = (RESIDUAL_SCALE[k], RESIDUAL_SCALE[k + 1]);
    std::array::from_fn(|c| {
        (f64::from(a[c]) + f * (f64::from(b[c]) - f64::from(a[c]))).round() as u8
    })
}

/// Every edge of `graph`, in input order, colored by its term of the cost f.
pub fn residual_entity(
    path: &str,
    graph: &PoseGraph,
    weights: &[crate::weights::EdgeWeight],
) -> Entity {
    let residuals: Vec<f64> = graph
        .edges
        .iter()
        .zip(weights)
        .map(|(e, w)| crate::matrix::edge_cost(e, *w, &graph.poses))
        .collect();
    let max = residuals.iter().copied().fold(0.0, f64::max);
    let min_positive = residuals
        .iter()
        .copied()
        .filter(|r| *r > 0.0)
        .fold(f64::INFINITY, f64::min);
    let colors = residuals
        .iter()
        .map(|&r| scale_color(residual_position(r, min_positive, max)))
        .collect();
    let strips = graph
        .edges
        .iter()
        .map(|e| {
            let (a, b) = (graph.poses[e.i], graph.poses[e.j]);
            [point(a.x, a.y), point(b.x, b.y)]
        })
        .collect();
    Entity::fixed(
        path,
        Item::Strips {
            strips,
            colors,
            radius: RESIDUAL_LINE_RADIUS,
        },
    )
    .with(
        "from",
        graph
            .edges
            .iter()
            .map(|e| f64::from(graph.ids[e.i]))
            .collect(),
    )
    .with(
        "to",
        graph
            .edges
            .iter()
            .map(|e| f64::from(graph.ids[e.j]))
            .collect(),
    )
    .with("residual", residuals)
}

fn flag(b: bool) -> f64 {
    if b { 1.0 } else { 0.0 }
}

/// `report/certificate`: the verdict, the cost and the proven bound.
pub fn certificate_entity(c: &Certificate) -> Entity {
    let gap = c.cost - c.lower_bound;
    let relative = gap / c.cost.abs().max(1.0);
    let verdict = if c.certified {
        "certified optimal"
    } else if c.szep {
        "NOT certified (the SZEP holds but the bound exceeds the tolerance)"
    } else {
        "NOT certified (no SZEP: null-space estimate)"
    };
    let text = format!(
        "{verdict}: cost {}, proven lower bound {}, suboptimality <= {} ({} relative); {} eigenvalue{} of W(lambda*) at zero",
        num(c.cost),
        num(c.lower_bound),
        num(gap),
        num(relative),
        c.near_zero,
        if c.near_zero == 1 { "" } else { "s" }
    );
    Entity::fixed(
        "report/certificate",
        Item::Text {
            text,
            warning: !c.certified,
        },
    )
    .with("cost", vec![c.cost])
    .with("lower_bound", vec![c.lower_bound])
    .with("suboptimality_bound", vec![gap])
    .with("relative_suboptimality_bound", vec![relative])
    .with("certified", vec![flag(c.certified)])
    .with("szep", vec![flag(c.szep)])
    .with("near_zero", vec![c.near_zero as f64])
}

/// `spectrum/...` and `report/spectrum`.
pub fn spectrum_entities(s: &Spectrum<'_>) -> Vec<Entity> {
    let mut text = format!(
        "SZEP {}: {} eigenvalue{} of W(lambda*) at zero",
        if s.szep { "holds" } else { "fails" },
        s.near_zero,
        if s.near_zero == 1 { "" } else { "s" }
    );
    if let Some(bound) = s.lower_bound {
        text += &format!("; proven lower bound on f*: {}", num(bound));
    }
    let mut v: Vec<Entity> = [
        ("spectrum/eigenvalues", s.eigenvalues),
        ("spectrum/penalized_eigenvalues", s.penalized_eigenvalues),
        ("spectrum/rotation_eigenvalues", s.rotation_eigenvalues),
    ]
    .into_iter()
    .map(|(path, values)| Entity::fixed(path, Item::Bars(values.to_vec())))
    .collect();
    v.push(
        Entity::fixed("spectrum/near_zero", Item::Scalar(s.near_zero as f64))
            .with("szep", vec![flag(s.szep)]),
    );
    let mut report = Entity::fixed(
        "report/spectrum",
        Item::Text {
            text,
            warning: !s.szep,
        },
    )
    .with("near_zero", vec![s.near_zero as f64])
    .with("szep", vec![flag(s.szep)]);
    if let Some(bound) = s.lower_bound {
        report = report.with("lower_bound", vec![bound]);
    }
    v.push(report);
    v
}

/// An entity path part from a value's name: ASCII letters, digits and `_` kept, others `_`.
fn path_part(name: &str) -> String {
    let part: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if part.is_empty() { "_".into() } else { part }
}

/// `solver/NAME` at `step` of the `iteration` timeline, one per value.
pub fn iteration_entities(step: u64, values: &[(&str, f64)]) -> Vec<Entity> {
    values
        .iter()
        .map(|&(name, value)| Entity {
            path: format!("solver/{}", path_part(name)),
            item: Item::Scalar(value),
            values: Vec::new(),
            when: When::Iteration(step),
        })
        .collect()
}

/// Without the cargo feature `rerun`: nothing can be recorded.
#[cfg(not(feature = "rerun"))]
mod backend {
    use super::{Entity, Target};
    use crate::error::Error;

    /// Uninhabited: a recorder never has one in this build.
    pub enum Inner {}

    impl Inner {
        pub fn start(tool: &'static str, target: &Target) -> crate::Result<Option<Inner>> {
            if let Some(path) = &target.save {
                return Err(Error::Invalid(format!(
                    "--rerun-save {path}: this build of pgo has no rerun support (it was built without the cargo feature `rerun`, which is on by default)"
                )));
            }
            eprintln!(
                "{tool}: warning: {} ignored: this build of pgo has no rerun support (cargo feature `rerun`)",
                if target.spawn {
                    "--rerun-spawn"
                } else {
                    "--rerun-connect"
                }
            );
            Ok(None)
        }

        pub fn emit(&self, _entity: &Entity) {
            match *self {}
        }

        pub fn observer(
            &self,
            _next_step: std::rc::Rc<std::cell::Cell<u64>>,
        ) -> crate::progress::Observer {
            match *self {}
        }

        pub fn finish(self) -> crate::Result<()> {
            match self {}
        }
    }
}

#[cfg(feature = "rerun")]
mod backend {
    use super::{Entity, Item, Target, VIEWER_TIMEOUT_SECONDS, When};
    use crate::error::Error;
    use rerun::external::re_uri::ProxyUri;
    use rerun::sink::{BinaryStreamSink, BinaryStreamStorage, GrpcSink, LogSink};
    use rerun::{RecordingStream, RecordingStreamBuilder};
    use std::cell::{Cell, RefCell};
    use std::collections::BTreeSet;
    use std::rc::Rc;
    use std::time::Duration;

    /// A recording in progress.
    pub struct Inner {
        tool: String,
        sink: Sink,
        /// The `.rrd` file: its path, the temporary file it is written to, the encoder's buffer.
        save: Option<(String, tempfile::NamedTempFile, BinaryStreamStorage)>,
        /// URLs of the viewers streamed to.
        viewers: Vec<String>,
    }

    /// Logs entities; cheap to clone (for [`super::Recorder::observe`]).
    #[derive(Clone)]
    pub struct Sink {
        rec: RecordingStream,
        /// The first logging error: the recording is then incomplete.
        error: Rc<RefCell<Option<String>>>,
        /// Entity paths logged (for the blueprint).
        paths: Rc<RefCell<BTreeSet<String>>>,
    }

    fn invalid(message: String) -> Error {
        Error::Invalid(message)
    }

    impl Inner {
        pub fn start(tool: &'static str, target: &Target) -> crate::Result<Option<Inner>> {
            // Check everything that can be an error before starting anything.
            let connect = match &target.connect {
                Some(url) => Some(url.parse::<ProxyUri>().map_err(|e| {
                    invalid(format!(
                        "--rerun-connect={url}: not the address of a rerun viewer ({e}); expected e.g. {}",
                        super::DEFAULT_CONNECT_URL
                    ))
                })?),
                None => None,
            };
            let file = match &target.save {
                Some(path) => {
                    let target_path = std::path::Path::new(path);
                    let dir = match target_path.parent() {
                        Some(d) if !d.as_os_str().is_empty() => d,
                        _ => std::path::Path::new("."),
                    };
                    let tmp = tempfile::Builder::new()
                        .prefix(".pgo-")
                        .suffix(".rrd.tmp")
                        .tempfile_in(dir)
                        .map_err(|e| invalid(format!("--rerun-save {path}: {e}")))?;
                    Some((path.clone(), tmp))
                }
                None => None,
            };
            let rec = RecordingStreamBuilder::new(tool)
                .enabled(true)
                .buffered()
                .map_err(|e| invalid(format!("cannot start the rerun recording: {e}")))?;

            let mut sinks: Vec<Box<dyn LogSink>> = Vec::new();
            let save = file.map(|(path, tmp)| {
                let (sink, storage) = BinaryStreamSink::new(rec.clone());
                sinks.push(Box::new(sink));
                (path, tmp, storage)
            });
            let mut viewers: Vec<(String, ProxyUri)> = Vec::new();
            if target.spawn {
                match spawn_viewer() {
                    Ok(()) => {
                        let url = super::DEFAULT_CONNECT_URL.to_string();
                        if let Ok(uri) = url.parse::<ProxyUri>() {
                            viewers.push((url, uri));
                        }
                    }
                    Err(e) => eprintln!("{tool}: warning: cannot start the rerun viewer: {e}"),
                }
            }
            if let (Some(uri), Some(url)) = (connect, &target.connect)
                && !viewers.iter().any(|(_, u)| *u == uri)
            {
                viewers.push((url.clone(), uri));
            }
            for (_, uri) in &viewers {
                sinks.push(Box::new(GrpcSink::new(uri.clone())));
            }
            if sinks.is_empty() {
                return Ok(None);
            }
            rec.set_sinks(sinks);
            Ok(Some(Inner {
                tool: tool.to_string(),
                sink: Sink {
                    rec,
                    error: Rc::default(),
                    paths: Rc::default(),
                },
                save,
                viewers: viewers.into_iter().map(|(url, _)| url).collect(),
            }))
        }

        pub fn emit(&self, entity: &Entity) {
            self.sink.emit(entity);
        }

        /// Logs the iterations reported to it at the next steps of the `iteration` timeline.
        pub fn observer(&self, next_step: Rc<Cell<u64>>) -> crate::progress::Observer {
            let sink = self.sink.clone();
            Box::new(move |_solver_step, values| {
                let step = next_step.get();
                next_step.set(step + 1);
                for entity in super::iteration_entities(step, values) {
                    sink.emit(&entity);
                }
            })
        }

        pub fn finish(self) -> crate::Result<()> {
            let Inner {
                tool,
                sink,
                save,
                viewers,
            } = self;
            if let Err(e) = blueprint(&sink.paths.borrow()).send(
                &sink.rec,
                rerun::blueprint::BlueprintActivation {
                    make_active: true,
                    make_default: true,
                },
            ) {
                sink.note_error(format!("blueprint: {e}"));
            }
            let flushed = sink
                .rec
                .flush_with_timeout(Duration::from_secs(VIEWER_TIMEOUT_SECONDS));
            if let Err(e) = &flushed
                && !viewers.is_empty()
            {
                eprintln!(
                    "{tool}: warning: the rerun viewer at {} did not take the recording: {}",
                    viewers.join(", "),
                    first_line(&e.to_string())
                );
            }
            let error = sink.error.borrow().clone();
            let mut leftovers = None;
            let result = match save {
                None => Ok(()),
                Some((path, tmp, storage)) => {
                    let why = if let Some(e) = error {
                        Some(e)
                    } else if let (Err(e), true) = (&flushed, viewers.is_empty()) {
                        Some(e.to_string())
                    } else {
                        None
                    };
                    let result = match (why, storage.read()) {
                        (Some(why), _) => Err(invalid(format!(
                            "cannot save the rerun recording to {path}: {why}"
                        ))),
                        (None, None) => Err(invalid(format!(
                            "cannot save the rerun recording to {path}: it could not be encoded"
                        ))),
                        (None, Some(bytes)) => write_file(&path, tmp, &bytes),
                    };
                    leftovers = Some(storage);
                    result
                }
            };
            if flushed.is_ok() || viewers.is_empty() {
                // Closes the connections to the viewers cleanly (they keep the data only then).
                drop(leftovers);
                drop(sink);
            } else {
                // Dropping the stream would wait for the viewers without limit: they had their
                // chance above, and the process ends now.
                std::mem::forget(leftovers);
                std::mem::forget(sink);
            }
            result
        }
    }

    /// Starts the `rerun` executable on `PATH` as a viewer listening at the default port,
    /// unless something listens there already (a viewer: the recording goes to it). Unlike
    /// `rerun::spawn`, the viewer gets no stdin, stdout or stderr of ours, so that it neither
    /// writes into the tool's outputs nor holds a pipe open after the tool ends; it runs in its
    /// own process group, so that Ctrl-C on the tool leaves it open.
    fn spawn_viewer() -> Result<(), String> {
        use std::net::{Ipv4Addr, SocketAddr, TcpStream};
        use std::process::{Command, Stdio};
        let port = rerun::DEFAULT_SERVER_PORT;
        let address = SocketAddr::from((Ipv4Addr::LOCALHOST, port));
        if TcpStream::connect_timeout(&address, Duration::from_millis(200)).is_ok() {
            return Ok(());
        }
        let mut command = Command::new("rerun");
        command
            .arg(format!("--port={port}"))
            .arg("--expect-data-soon")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        #[cfg(unix)]
        {
            use std::os::unix::process::CommandExt;
            command.process_group(0);
        }
        match command.spawn() {
            Ok(_child) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(
                "no `rerun` executable on PATH (pip install rerun-sdk==0.36.3 provides it)".into(),
            ),
            Err(e) => Err(format!("rerun: {e}")),
        }
    }

    fn first_line(s: &str) -> &str {
        s.lines().next().unwrap_or("")
    }

    /// Writes `bytes` to the temporary file and renames it to `path` (mode 0644 on Unix).
    fn write_file(path: &str, tmp: tempfile::NamedTempFile, bytes: &[u8]) -> crate::Result<()> {
        use std::io::Write;
        let fail =
            |e: std::io::Error| invalid(format!("cannot save the rerun recording to {path}: {e}"));
        let mut file = tmp.as_file();
        file.write_all(bytes)
            .and_then(|_| file.flush())
            .map_err(fail)?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(tmp.path(), std::fs::Permissions::from_mode(0o644))
                .map_err(fail)?;
        }
        tmp.persist(path).map_err(|e| fail(e.error))?;
        Ok(())
    }

    /// The viewer layout: the 2D views of what was logged on top (input, optimized, residuals),
    /// the solver's iterations, the spectra and the reports below.
    fn blueprint(paths: &BTreeSet<String>) -> rerun::blueprint::Blueprint {
        use rerun::blueprint::{
            BarChartView, Blueprint, BlueprintPanel, ContainerLike, Grid, Horizontal,
            SelectionPanel, Spatial2DView, TextLogView, TimePanel, TimeSeriesView, Vertical,
        };
        let has = |prefix: &str| paths.iter().any(|p| p.starts_with(prefix));
        let mut top: Vec<ContainerLike> = Vec::new();
        if has("graph/") {
            top.push(
                Spatial2DView::new("graph as read")
                    .with_origin("/graph")
                    .into(),
            );
        }
        if has("optimized/") {
            top.push(
                Spatial2DView::new("optimized")
                    .with_origin("/optimized")
                    .with_contents(["+ $origin/**", "- /optimized/residuals"])
                    .into(),
            );
            top.push(
                Spatial2DView::new("residuals (cost terms, log scale)")
                    .with_origin("/optimized")
                    .with_contents(["+ /optimized/residuals"])
                    .into(),
            );
        }
        let mut bottom: Vec<ContainerLike> = Vec::new();
        // One plot per solver value: each gets its own scale.
        let series: Vec<ContainerLike> = paths
            .iter()
            .filter_map(|p| p.strip_prefix("solver/"))
            .map(|name| {
                TimeSeriesView::new(name)
                    .with_origin(format!("/solver/{name}"))
                    .into()
            })
            .collect();
        if !series.is_empty() {
            bottom.push(Grid::new(series).with_name("solver iterations").into());
        }
        for (path, name) in [
            ("spectrum/eigenvalues", "eigenvalues of W"),
            (
                "spectrum/penalized_eigenvalues",
                "eigenvalues of W(lambda*)",
            ),
            ("spectrum/rotation_eigenvalues", "eigenvalues of M"),
        ] {
            if paths.contains(path) {
                bottom.push(
                    BarChartView::new(name)
                        .with_origin(format!("/{path}"))
                        .into(),
                );
            }
        }
        if has("report/") {
            bottom.push(TextLogView::new("report").with_origin("/report").into());
        }
        let rows: Vec<ContainerLike> = [top, bottom]
            .into_iter()
            .filter(|row| !row.is_empty())
            .map(|row| Horizontal::new(row).into())
            .collect();
        let shares = if rows.len() == 2 {
            vec![3.0, 1.0]
        } else {
            vec![1.0]
        };
        // The views get the room: the side panels start collapsed (a click opens them).
        let collapsed = rerun::blueprint::components::PanelState::Collapsed;
        Blueprint::new(Vertical::new(rows).with_row_shares(shares))
            .with_blueprint_panel(BlueprintPanel::from_state(collapsed))
            .with_selection_panel(SelectionPanel::from_state(collapsed))
            .with_time_panel(TimePanel::new().with_state(collapsed))
    }

    fn rgb([r, g, b]: [u8; 3]) -> rerun::Color {
        rerun::Color::from_rgb(r, g, b)
    }

    impl Sink {
        fn note_error(&self, message: String) {
            let mut slot = self.error.borrow_mut();
            if slot.is_none() {
                *slot = Some(message);
            }
        }

        pub fn emit(&self, entity: &Entity) {
            let rec = &self.rec;
            rec.reset_time();
            let is_static = match entity.when {
                When::Static => true,
                When::Iteration(step) => {
                    rec.set_time_sequence("iteration", i64::try_from(step).unwrap_or(i64::MAX));
                    false
                }
            };
            let path = entity.path.as_str();
            let result = match &entity.item {
                Item::Points {
                    positions,
                    color,
                    radius,
                } => self.log(
                    path,
                    is_static,
                    &rerun::Points2D::new(positions.iter().copied())
                        .with_colors([rgb(*color)])
                        .with_radii([rerun::Radius::new_ui_points(*radius)]),
                ),
                Item::Arrows {
                    origins,
                    vectors,
                    color,
                    radius,
                } => self.log(
                    path,
                    is_static,
                    &rerun::Arrows2D::from_vectors(vectors.iter().copied())
                        .with_origins(origins.iter().copied())
                        .with_colors([rgb(*color)])
                        .with_radii([rerun::Radius::new_ui_points(*radius)]),
                ),
                Item::Strips {
                    strips,
                    colors,
                    radius,
                } => self.log(
                    path,
                    is_static,
                    &rerun::LineStrips2D::new(strips.iter().copied())
                        .with_colors(colors.iter().map(|c| rgb(*c)))
                        .with_radii([rerun::Radius::new_ui_points(*radius)]),
                ),
                Item::Bars(values) => {
                    self.log(path, is_static, &rerun::BarChart::new(values.clone()))
                }
                Item::Scalar(value) => self.log(path, is_static, &rerun::Scalars::new([*value])),
                Item::Text { text, warning } => self.log(
                    path,
                    is_static,
                    &rerun::TextLog::new(text.as_str()).with_level(if *warning {
                        rerun::TextLogLevel::WARN
                    } else {
                        rerun::TextLogLevel::INFO
                    }),
                ),
            };
            let result = result.and_then(|()| {
                if entity.values.is_empty() {
                    return Ok(());
                }
                let mut any = rerun::AnyValues::default();
                for (name, values) in &entity.values {
                    any = any.with_component::<rerun::components::Scalar>(*name, values.clone());
                }
                self.log(path, is_static, &any)
            });
            if let Err(e) = result {
                self.note_error(format!("{path}: {e}"));
            }
            self.paths.borrow_mut().insert(entity.path.clone());
        }

        fn log(
            &self,
            path: &str,
            is_static: bool,
            archetype: &impl rerun::AsComponents,
        ) -> rerun::RecordingStreamResult<()> {
            if is_static {
                self.rec.log_static(path, archetype)
            } else {
                self.rec.log(path, archetype)
            }
        }
    }
}

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
    fn residuals_are_the_terms_of_the_cost() {
        let mut g = square();
        g.poses[2].x += 0.5; // breaks edges 1->2 and 2->3
        let w = edge_weights(&g, Weights::Unit).unwrap();
        let e = residual_entity("optimized/residuals", &g, &w);
        let residual = &e.values.iter().find(|(n, _)| *n == "residual").unwrap().1;
        let total: f64 = residual.iter().sum();
        assert!((total - crate::matrix::cost(&g, &w, &g.poses)).abs() < 1e-12);
        assert_eq!(residual[0], 0.0);
        assert!(residual[1] > 0.0 && residual[2] > 0.0);
        let Item::Strips { colors, strips, .. } = &e.item else {
            panic!("not strips")
        };
        assert_eq!((colors.len(), strips.len()), (4, 4));
        assert_eq!(colors[0], RESIDUAL_SCALE[0]);
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
}
