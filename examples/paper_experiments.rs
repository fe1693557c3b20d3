//! The paper's experiments (Sec. 6), reproduced: prints each table and draws its figure as SVG.
//!
//! ```text
//! cargo run --release --example paper_experiments -- fig5 [--runs 100] [--svg fig5.svg]
//! cargo run --release --example paper_experiments -- fig7 [--instances 30] [--svg fig7.svg]
//! cargo run --release --example paper_experiments -- fig8
//! cargo run --release --example paper_experiments -- fig9 [--svg fig9.svg]
//! ```
//!
//! Unit weights throughout (the paper's cost (5)); graphs from `pgo::simulate` (eq. (47)), seeds
//! 0, 1, 2, ... per point, so every run prints the same numbers.

use pgo::dual::algorithm1::{ComponentSolution, comparison_estimate, solve_connected};
use pgo::dual::rounding::Rounding;
use pgo::dual::solver::SdpSolver;
use pgo::graph::PoseGraph;
use pgo::problem::matrix::cost;
use pgo::problem::weights::{Weights, edge_weights};
use pgo::refine::gauss_newton::refine;
use pgo::simulate::{RotationNoise, SimulationConfig, TranslationNoise, simulate};
use std::fmt::Write as _;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|k| args.get(k + 1))
            .cloned()
    };
    let count =
        |name: &str, default: usize| flag(name).map_or(default, |v| v.parse().expect("a count"));
    let svg = flag("--svg");
    match args.first().map(String::as_str) {
        Some("fig5") => fig5(count("--runs", 100), svg),
        Some("fig7") => fig7(count("--instances", 30), svg),
        Some("fig8") => fig8(),
        Some("fig9") => fig9(svg),
        _ => {
            eprintln!(
                "usage: paper_experiments fig5|fig7|fig8|fig9 [--runs N] [--instances N] [--svg FILE]"
            );
            std::process::exit(2);
        }
    }
}

fn solve(graph: &PoseGraph) -> ComponentSolution {
    let w = edge_weights(graph, Weights::Unit).expect("unit weights");
    solve_connected(graph, &w, SdpSolver::Ipm).expect("the dual SDP solves")
}

/// Share of `runs` random graphs whose W̃(λ*) has the SZEP.
fn szep_share(config: SimulationConfig, runs: usize) -> f64 {
    let ok = (0..runs)
        .filter(|&seed| {
            let g = simulate(&SimulationConfig {
                seed: seed as u64,
                ..config
            })
            .graph;
            solve(&g).szep
        })
        .count();
    100.0 * ok as f64 / runs as f64
}

fn gauss(sigma: f64) -> RotationNoise {
    RotationNoise::Gaussian { sigma }
}

fn tgauss(sigma: f64) -> TranslationNoise {
    TranslationNoise::Gaussian { sigma }
}

struct Panel {
    title: String,
    x_label: String,
    points: Vec<(String, f64)>,
}

fn fig5(runs: usize, svg: Option<String>) {
    let t = Instant::now();
    let base = SimulationConfig::default();
    let mut panels = Vec::new();

    let mut points = Vec::new();
    for s in [0.01, 0.05, 0.1, 0.2, 0.5, 1.0] {
        let c = SimulationConfig {
            rotation_noise: gauss(s),
            ..base
        };
        points.push((format!("{s}"), szep_share(c, runs)));
    }
    let c = SimulationConfig {
        rotation_noise: RotationNoise::Uniform,
        ..base
    };
    points.push(("unif".into(), szep_share(c, runs)));
    panels.push(Panel {
        title: "(a) sigma_Delta = 0.1".into(),
        x_label: "sigma_R (rad)".into(),
        points,
    });

    let mut points = Vec::new();
    for s in [0.01, 0.05, 0.1, 0.2, 0.5, 1.0] {
        let c = SimulationConfig {
            translation_noise: tgauss(s),
            ..base
        };
        points.push((format!("{s}"), szep_share(c, runs)));
    }
    let c = SimulationConfig {
        translation_noise: TranslationNoise::Uniform { half_width: 5.0 },
        ..base
    };
    points.push(("unif".into(), szep_share(c, runs)));
    panels.push(Panel {
        title: "(b) sigma_R = 0.1".into(),
        x_label: "sigma_Delta (m)".into(),
        points,
    });

    let hard = SimulationConfig {
        rotation_noise: gauss(1.0),
        translation_noise: tgauss(1.0),
        ..base
    };
    let mut points = Vec::new();
    for p in [0.0, 0.2, 0.4, 0.6, 0.8, 1.0] {
        let c = SimulationConfig {
            loop_probability: p,
            ..hard
        };
        points.push((format!("{p}"), szep_share(c, runs)));
    }
    panels.push(Panel {
        title: "(c) sigma_R = sigma_Delta = 1".into(),
        x_label: "P_c".into(),
        points,
    });

    let mut points = Vec::new();
    for n in [10, 20, 30, 40, 50] {
        let c = SimulationConfig { n, ..hard };
        points.push((format!("{n}"), szep_share(c, runs)));
    }
    panels.push(Panel {
        title: "(d) sigma_R = sigma_Delta = 1".into(),
        x_label: "n".into(),
        points,
    });

    println!("Fig. 5: share of runs (%) whose W(lambda*) has the SZEP, {runs} runs per point");
    for p in &panels {
        println!("\n{}", p.title);
        println!("| {} | SZEP % |\n|---|---:|", p.x_label);
        for (x, y) in &p.points {
            println!("| {x} | {y:.0} |");
        }
    }
    println!(
        "\n({} SDPs in {:.1} s)",
        runs * 26,
        t.elapsed().as_secs_f64()
    );
    if let Some(path) = svg {
        std::fs::write(&path, panels_svg(&panels, 0.0, 100.0, "SZEP %")).expect("writable");
        println!("plot: {path}");
    }
}

/// Fig. 7: on instances where the SZEP fails, the cost of the null-space method (NS), the
/// eigenvector method (Eig), SDP rank-1 rounding (SDP) and Gauss-Newton from the ground truth
/// (GN), raw and after Gauss-Newton refinement.
fn fig7(instances: usize, svg: Option<String>) {
    let base = SimulationConfig::default();
    let setups = [
        ("sigma_R=1, sigma_D=0.1", gauss(1.0), tgauss(0.1)),
        ("sigma_R=1, sigma_D=1", gauss(1.0), tgauss(1.0)),
        (
            "sigma_R=unif, sigma_D=0.1",
            RotationNoise::Uniform,
            tgauss(0.1),
        ),
        (
            "sigma_R=0.1, sigma_D=unif(5)",
            gauss(0.1),
            TranslationNoise::Uniform { half_width: 5.0 },
        ),
    ];
    let methods = ["NS", "Eig", "SDP", "GN(truth)"];
    println!(
        "Fig. 7: instances without the SZEP ({instances} per setup): mean [median] cost of each estimate; d* is the dual bound"
    );
    let mut panels = Vec::new();
    for (name, rot, tra) in setups {
        let mut raw = vec![Vec::new(); 4];
        let mut refined = vec![Vec::new(); 4];
        let mut bound = Vec::new();
        let mut best = [0usize; 4];
        let mut seed = 0u64;
        while bound.len() < instances && seed < 200 * instances as u64 {
            let sim = simulate(&SimulationConfig {
                rotation_noise: rot,
                translation_noise: tra,
                seed,
                ..base
            });
            seed += 1;
            let g = &sim.graph;
            let s = solve(g);
            if s.szep {
                continue;
            }
            let w = edge_weights(g, Weights::Unit).unwrap();
            let anchor = g.poses[0];
            let estimates = [
                s.poses.clone(),
                comparison_estimate(&s, Rounding::Eigenvector, anchor),
                comparison_estimate(&s, Rounding::SdpRank1, anchor),
                refine(g, &w, &sim.truth, 100).poses,
            ];
            let mut refined_costs = [0.0; 4];
            for (k, e) in estimates.iter().enumerate() {
                raw[k].push(cost(g, &w, e));
                let r = refine(g, &w, e, 100).cost;
                refined[k].push(r);
                refined_costs[k] = r;
            }
            let min = refined_costs.iter().copied().fold(f64::INFINITY, f64::min);
            for k in 0..4 {
                if refined_costs[k] <= min * (1.0 + 1e-9) {
                    best[k] += 1;
                }
            }
            bound.push(s.lower_bound);
        }
        println!("\n{name}: {} instances", bound.len());
        println!("| method | cost | after GN | best after GN |\n|---|---:|---:|---:|");
        for k in 0..4 {
            println!(
                "| {} | {:.3} [{:.3}] | {:.3} [{:.3}] | {} |",
                methods[k],
                mean(&raw[k]),
                median(&raw[k]),
                mean(&refined[k]),
                median(&refined[k]),
                best[k]
            );
        }
        println!(
            "| d* (bound) | {:.3} [{:.3}] | | |",
            mean(&bound),
            median(&bound)
        );
        panels.push(Panel {
            title: name.into(),
            x_label: "method".into(),
            points: (0..4)
                .map(|k| (methods[k].to_string(), median(&raw[k])))
                .collect(),
        });
    }
    if let Some(path) = svg {
        let top = panels
            .iter()
            .flat_map(|p| p.points.iter().map(|q| q.1))
            .fold(0.0, f64::max);
        std::fs::write(&path, panels_svg(&panels, 0.0, top * 1.1, "median cost"))
            .expect("writable");
        println!("plot: {path}");
    }
}

fn toy() -> PoseGraph {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/paper_toy.g2o");
    pgo::io::read_path(path, &Default::default())
        .expect("the toy graph reads")
        .0
}

fn fig8() {
    let g = toy();
    println!(
        "Fig. 8: four smallest eigenvalues of W(lambda*) for the toy graph (Appendix 8.8) and with one node removed"
    );
    println!("| graph | d* | mu1 | mu2 | mu3 | mu4 | zero eigenvalues | SZEP |");
    println!("|---|---:|---:|---:|---:|---:|---:|---|");
    let row = |name: String, g: &PoseGraph| {
        let s = solve(g);
        let mu: Vec<String> = s
            .eigenvalues
            .iter()
            .take(4)
            .map(|v| format!("{v:.3e}"))
            .collect();
        println!(
            "| {name} | {:.6} | {} | {} | {} |",
            s.dual_objective,
            mu.join(" | "),
            s.near_zero,
            if s.szep { "yes" } else { "no" }
        );
    };
    row("(a) toy".into(), &g);
    for k in 0..5 {
        let label = (b'b' + k as u8) as char;
        row(
            format!("({label}) without node {}", k + 1),
            &g.eliminate_pose(k).expect("pose k lies on the cycle"),
        );
    }
}

fn fig9(svg: Option<String>) {
    let g = toy();
    println!("Fig. 9: second eigenvalue of W(lambda*) with every translation scaled");
    println!("| scale | mu2 | zero eigenvalues | SZEP |\n|---:|---:|---:|---|");
    let mut points = Vec::new();
    for k in 1..=10 {
        let scale = k as f64 / 10.0;
        let mut h = g.clone();
        for e in &mut h.edges {
            e.measurement.x *= scale;
            e.measurement.y *= scale;
        }
        let s = solve(&h);
        println!(
            "| {scale:.1} | {:.4e} | {} | {} |",
            s.eigenvalues[1],
            s.near_zero,
            if s.szep { "yes" } else { "no" }
        );
        points.push((format!("{scale:.1}"), s.eigenvalues[1]));
    }
    if let Some(path) = svg {
        let top = points.iter().map(|p| p.1).fold(0.0, f64::max);
        let panel = Panel {
            title: "toy graph, translations scaled".into(),
            x_label: "scale".into(),
            points,
        };
        std::fs::write(&path, panels_svg(&[panel], 0.0, top * 1.1, "mu2")).expect("writable");
        println!("plot: {path}");
    }
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}

/// Line charts, one panel per series, side by side: a plain SVG, no dependency.
fn panels_svg(panels: &[Panel], lo: f64, hi: f64, y_label: &str) -> String {
    let (w, h, m) = (300.0, 220.0, 40.0);
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{}" height="{}" font-family="sans-serif" font-size="11">"#,
        w * panels.len() as f64,
        h + 20.0
    );
    for (p, panel) in panels.iter().enumerate() {
        let x0 = p as f64 * w;
        let n = panel.points.len().max(2) as f64;
        let px = |k: usize| x0 + m + (w - 2.0 * m) * k as f64 / (n - 1.0);
        let py =
            |v: f64| h - m - (h - 2.0 * m) * ((v - lo) / (hi - lo).max(1e-300)).clamp(0.0, 1.0);
        let _ = write!(
            s,
            r#"<text x="{}" y="14">{}</text><line x1="{}" y1="{}" x2="{}" y2="{}" stroke="black"/><line x1="{}" y1="{}" x2="{}" y2="{}" stroke="black"/>"#,
            x0 + m,
            panel.title,
            x0 + m,
            h - m,
            x0 + w - m,
            h - m,
            x0 + m,
            m,
            x0 + m,
            h - m
        );
        let _ = write!(
            s,
            r#"<text x="{}" y="{}">{}</text><text x="{}" y="{}">{:.3}</text><text x="{}" y="{}">{:.3}</text><text x="{}" y="{}">{}</text>"#,
            x0 + w / 2.0 - 20.0,
            h - 5.0,
            panel.x_label,
            x0 + 2.0,
            m + 4.0,
            hi,
            x0 + 2.0,
            h - m,
            lo,
            x0 + 2.0,
            m - 8.0,
            y_label
        );
        let pts: Vec<String> = panel
            .points
            .iter()
            .enumerate()
            .map(|(k, (_, v))| format!("{:.1},{:.1}", px(k), py(*v)))
            .collect();
        let _ = write!(
            s,
            r#"<polyline fill="none" stroke="steelblue" stroke-width="2" points="{}"/>"#,
            pts.join(" ")
        );
        for (k, (label, v)) in panel.points.iter().enumerate() {
            let _ = write!(
                s,
                r#"<circle cx="{:.1}" cy="{:.1}" r="3" fill="steelblue"/><text x="{:.1}" y="{}" text-anchor="middle">{}</text>"#,
                px(k),
                py(*v),
                px(k),
                h - m + 14.0,
                label
            );
        }
    }
    s.push_str("</svg>\n");
    s
}
