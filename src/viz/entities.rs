//! What the tools record, as plain [`Entity`] values computed without rerun (so tested in every
//! build): the graph, the estimate and its residuals, the certificate, the spectrum, the solver
//! iterations.

use super::{
    Certificate, Entity, HEADING_COLOR, Item, LANDMARK_COLOR, LANDMARK_RADIUS, LINE_RADIUS,
    LOOP_CLOSURE_COLOR, OBSERVATION_COLOR, OBSERVATION_RADIUS, ODOMETRY_COLOR, POINT_RADIUS,
    POSE_COLOR, REJECTED_COLOR, RESIDUAL_LINE_RADIUS, RESIDUAL_SCALE, Rgb, Spectrum, When,
};
use crate::graph::PoseGraph;
use crate::graph3::Graph3;

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
    entities.extend(landmark_entities(root, graph));
    entities
}

/// The landmarks of a graph under `root` (none without landmarks): `landmarks` as points of
/// their own color, `observations` as thin rays from each observing pose to the landmark.
pub fn landmark_entities(root: &str, graph: &PoseGraph) -> Vec<Entity> {
    let marks = &graph.landmarks;
    if marks.is_empty() {
        return Vec::new();
    }
    let positions = marks.positions.iter().map(|&[x, y]| point(x, y)).collect();
    let rays = marks
        .observations
        .iter()
        .map(|o| {
            let (a, [x, y]) = (graph.poses[o.pose], marks.positions[o.landmark]);
            [point(a.x, a.y), point(x, y)]
        })
        .collect();
    vec![
        Entity::fixed(
            format!("{root}/landmarks"),
            Item::Points {
                positions,
                color: LANDMARK_COLOR,
                radius: LANDMARK_RADIUS,
            },
        )
        .with(
            "landmark_id",
            marks.ids.iter().map(|&id| f64::from(id)).collect(),
        )
        .with("x", marks.positions.iter().map(|p| p[0]).collect())
        .with("y", marks.positions.iter().map(|p| p[1]).collect()),
        Entity::fixed(
            format!("{root}/observations"),
            Item::Strips {
                strips: rays,
                colors: vec![OBSERVATION_COLOR],
                radius: OBSERVATION_RADIUS,
            },
        )
        .with(
            "pose",
            marks
                .observations
                .iter()
                .map(|o| f64::from(graph.ids[o.pose]))
                .collect(),
        )
        .with(
            "landmark",
            marks
                .observations
                .iter()
                .map(|o| f64::from(marks.ids[o.landmark]))
                .collect(),
        ),
    ]
}

/// The observation rays colored by their terms ν |l_k − p_i − r_i d_ik|² of the cost (the
/// weights after the edges' in `weights`), on the scale of [`residual_entity`].
pub fn landmark_residual_entity(
    path: &str,
    graph: &PoseGraph,
    weights: &[crate::problem::weights::EdgeWeight],
) -> Entity {
    let marks = &graph.landmarks;
    let residuals: Vec<f64> = marks
        .observations
        .iter()
        .zip(&weights[graph.edges.len()..])
        .map(|(o, w)| {
            crate::problem::matrix::observation_cost(
                o,
                *w,
                graph.poses[o.pose],
                marks.positions[o.landmark],
            )
        })
        .collect();
    let strips = marks
        .observations
        .iter()
        .map(|o| {
            let (a, [x, y]) = (graph.poses[o.pose], marks.positions[o.landmark]);
            [point(a.x, a.y), point(x, y)]
        })
        .collect();
    let (poses, landmarks) = marks
        .observations
        .iter()
        .map(|o| {
            (
                f64::from(graph.ids[o.pose]),
                f64::from(marks.ids[o.landmark]),
            )
        })
        .unzip();
    colored_strips(
        path,
        strips,
        residuals,
        [("pose", poses), ("landmark", landmarks)],
    )
}

/// Line strips colored by their residuals on the scale of [`residual_entity`] (logarithmic
/// between the smallest positive and the largest), with the ids of their two ends and the
/// residuals as values.
fn colored_strips(
    path: &str,
    strips: Vec<[[f32; 2]; 2]>,
    residuals: Vec<f64>,
    ends: [(&'static str, Vec<f64>); 2],
) -> Entity {
    let colors = residual_colors(&residuals);
    let [(a, from), (b, to)] = ends;
    Entity::fixed(
        path,
        Item::Strips {
            strips,
            colors,
            radius: RESIDUAL_LINE_RADIUS,
        },
    )
    .with(a, from)
    .with(b, to)
    .with("residual", residuals)
}

/// The color of each residual on the scale of [`residual_entity`]: logarithmic between the
/// smallest positive residual and the largest ([`residual_position`], [`scale_color`]).
pub fn residual_colors(residuals: &[f64]) -> Vec<Rgb> {
    let max = residuals.iter().copied().fold(0.0, f64::max);
    let min_positive = residuals
        .iter()
        .copied()
        .filter(|r| *r > 0.0)
        .fold(f64::INFINITY, f64::min);
    residuals
        .iter()
        .map(|&r| scale_color(residual_position(r, min_positive, max)))
        .collect()
}

fn point3(t: [f64; 3]) -> [f32; 3] {
    t.map(|v| v as f32)
}

/// Whether a 3D edge counts as odometry: consecutive ids, as in 2D.
pub fn is_odometry3(graph: &Graph3, e: &crate::graph3::Edge3) -> bool {
    graph.ids[e.i].abs_diff(graph.ids[e.j]) == 1
}

/// The entities of a 3D graph under `root`, the planar ones' counterparts: `poses`
/// (Points3D, exact values `pose_id`, `x`, `y`, `z` and the rotation as the unit quaternion
/// `qx`, `qy`, `qz`, `qw`), `headings` (each pose's x axis R_i e_x as an arrow, half the median
/// measured translation long), `odometry` and `loop_closures` (2-point strips with `from`,
/// `to`).
pub fn graph3_entities(root: &str, graph: &Graph3) -> Vec<Entity> {
    let positions: Vec<[f32; 3]> = graph.poses.iter().map(|p| point3(p.translation)).collect();
    let mut lengths: Vec<f64> = graph
        .edges
        .iter()
        .map(|e| {
            let [x, y, z] = e.measurement.translation;
            (x * x + y * y + z * z).sqrt()
        })
        .filter(|l| l.is_finite() && *l > 0.0)
        .collect();
    lengths.sort_by(f64::total_cmp);
    let length = lengths.get(lengths.len() / 2).map_or(1.0, |l| 0.5 * l);
    let rotations: Vec<_> = graph
        .poses
        .iter()
        .map(|p| p.rotation.unit_quaternion())
        .collect();
    let vectors = rotations
        .iter()
        .map(|q| {
            let x = q * nalgebra::Vector3::x();
            point3([length * x.x, length * x.y, length * x.z])
        })
        .collect();
    let column = |f: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..graph.num_poses()).map(f).collect() };
    let quaternion = |k: usize| {
        let q = rotations[k].quaternion();
        [q.i, q.j, q.k, q.w]
    };
    let mut entities = vec![
        Entity::fixed(
            format!("{root}/poses"),
            Item::Points3 {
                positions: positions.clone(),
                color: POSE_COLOR,
                radius: POINT_RADIUS,
            },
        )
        .with(
            "pose_id",
            graph.ids.iter().map(|&id| f64::from(id)).collect(),
        )
        .with("x", column(&|k| graph.poses[k].translation[0]))
        .with("y", column(&|k| graph.poses[k].translation[1]))
        .with("z", column(&|k| graph.poses[k].translation[2]))
        .with("qx", column(&|k| quaternion(k)[0]))
        .with("qy", column(&|k| quaternion(k)[1]))
        .with("qz", column(&|k| quaternion(k)[2]))
        .with("qw", column(&|k| quaternion(k)[3])),
        Entity::fixed(
            format!("{root}/headings"),
            Item::Arrows3 {
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
        let (strips, from, to) = edge_strips3(graph, |e| is_odometry3(graph, e) == odometry);
        entities.push(
            Entity::fixed(
                format!("{root}/{name}"),
                Item::Strips3 {
                    strips,
                    colors: vec![color],
                    radius: LINE_RADIUS,
                },
            )
            .with("from", from)
            .with("to", to),
        );
    }
    entities
}

/// The strip of each kept 3D edge between its poses' positions, with the ids of its ends.
fn edge_strips3(
    graph: &Graph3,
    keep: impl Fn(&crate::graph3::Edge3) -> bool,
) -> (Vec<[[f32; 3]; 2]>, Vec<f64>, Vec<f64>) {
    let mut strips = Vec::new();
    let (mut from, mut to) = (Vec::new(), Vec::new());
    for e in graph.edges.iter().filter(|e| keep(e)) {
        strips.push([
            point3(graph.poses[e.i].translation),
            point3(graph.poses[e.j].translation),
        ]);
        from.push(f64::from(graph.ids[e.i]));
        to.push(f64::from(graph.ids[e.j]));
    }
    (strips, from, to)
}

/// Every edge of a 3D graph, in input order, colored by its term of SE-Sync's f
/// ([`crate::se3::problem::edge_term`]) on the planar scale ([`residual_colors`]).
pub fn residual3_entity(
    path: &str,
    graph: &Graph3,
    weights: &[crate::se3::problem::Weight3],
) -> Entity {
    let residuals: Vec<f64> = graph
        .edges
        .iter()
        .zip(weights)
        .map(|(e, w)| crate::se3::problem::edge_term(e, *w, &graph.poses))
        .collect();
    let (strips, from, to) = edge_strips3(graph, |_| true);
    Entity::fixed(
        path,
        Item::Strips3 {
            colors: residual_colors(&residuals),
            strips,
            radius: RESIDUAL_LINE_RADIUS,
        },
    )
    .with("from", from)
    .with("to", to)
    .with("residual", residuals)
}

/// "N poses, M edges (K odometry, L loop closures), 3D".
pub fn graph3_summary(graph: &Graph3) -> String {
    let odometry = graph
        .edges
        .iter()
        .filter(|e| is_odometry3(graph, e))
        .count();
    format!(
        "{} poses, {} edges ({odometry} odometry, {} loop closures), 3D",
        graph.num_poses(),
        graph.edges.len(),
        graph.edges.len() - odometry,
    )
}

/// "N poses, M edges (K odometry, L loop closures)".
pub fn graph_summary(graph: &PoseGraph) -> String {
    let odometry = graph.edges.iter().filter(|e| is_odometry(graph, e)).count();
    let marks = &graph.landmarks;
    format!(
        "{} poses, {} edges ({odometry} odometry, {} loop closures){}",
        graph.num_poses(),
        graph.edges.len(),
        graph.edges.len() - odometry,
        if marks.is_empty() {
            String::new()
        } else {
            format!(
                ", {} landmarks, {} observations",
                marks.len(),
                marks.observations.len()
            )
        }
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
    weights: &[crate::problem::weights::EdgeWeight],
) -> Entity {
    let residuals: Vec<f64> = graph
        .edges
        .iter()
        .zip(weights)
        .map(|(e, w)| crate::problem::matrix::edge_cost(e, *w, &graph.poses))
        .collect();
    let (strips, from, to) = edge_strips(graph, |_| true);
    colored_strips(path, strips, residuals, [("from", from), ("to", to)])
}

/// The strip of each edge between its poses' positions, with the ids of its ends.
fn edge_strips(
    graph: &PoseGraph,
    keep: impl Fn(usize) -> bool,
) -> (Vec<[[f32; 2]; 2]>, Vec<f64>, Vec<f64>) {
    let mut strips = Vec::new();
    let (mut from, mut to) = (Vec::new(), Vec::new());
    for (_, e) in graph.edges.iter().enumerate().filter(|(k, _)| keep(*k)) {
        let (a, b) = (graph.poses[e.i], graph.poses[e.j]);
        strips.push([point(a.x, a.y), point(b.x, b.y)]);
        from.push(f64::from(graph.ids[e.i]));
        to.push(f64::from(graph.ids[e.j]));
    }
    (strips, from, to)
}

/// What `pgo-solve --robust` found, drawn on the estimate `graph`: `optimized/rejected`, the
/// edges GNC rejected in [`REJECTED_COLOR`] with their `residual` r_e² at the estimate; and per
/// GNC iteration k (timeline `gnc_iteration`), `robust/weights`: every edge colored by its
/// weight w_e, from [`REJECTED_COLOR`] at 0 to [`ODOMETRY_COLOR`] at 1, the weights as
/// `weight`.
pub fn robust_entities(
    graph: &PoseGraph,
    rejected: &[bool],
    residuals: &[f64],
    weights_by_iteration: &[&[f64]],
) -> Vec<Entity> {
    let (strips, from, to) = edge_strips(graph, |k| rejected[k]);
    let rejected_residuals = residuals
        .iter()
        .zip(rejected)
        .filter(|(_, r)| **r)
        .map(|(v, _)| *v)
        .collect();
    let mut v = vec![
        Entity::fixed(
            "optimized/rejected",
            Item::Strips {
                colors: vec![REJECTED_COLOR],
                strips,
                radius: RESIDUAL_LINE_RADIUS,
            },
        )
        .with("from", from)
        .with("to", to)
        .with("residual", rejected_residuals),
    ];
    let (strips, from, to) = edge_strips(graph, |_| true);
    for (k, weights) in weights_by_iteration.iter().enumerate() {
        let blend = |w: f64| {
            let w = w.clamp(0.0, 1.0);
            let c = |a: u8, b: u8| (f64::from(a) + w * (f64::from(b) - f64::from(a))).round() as u8;
            [
                c(REJECTED_COLOR[0], ODOMETRY_COLOR[0]),
                c(REJECTED_COLOR[1], ODOMETRY_COLOR[1]),
                c(REJECTED_COLOR[2], ODOMETRY_COLOR[2]),
            ]
        };
        let mut e = Entity::fixed(
            "robust/weights",
            Item::Strips {
                strips: strips.clone(),
                colors: weights.iter().map(|&w| blend(w)).collect(),
                radius: LINE_RADIUS,
            },
        )
        .with("from", from.clone())
        .with("to", to.clone())
        .with("weight", weights.to_vec());
        e.when = When::GncIteration(k as u64 + 1);
        v.push(e);
    }
    v
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
