//! `pgo-solve` as a user runs it: the gauge of FIX lines, the estimate the report speaks of, g2o's
//! chi2 beside the cost, what ran, exit statuses, written angles, and flags and outputs refused
//! before the work. Figures are held against independent ones: the input file's own values, a
//! chi2 computed here from the written file, a hand value, rigid-motion invariants, and what
//! pgo-certify says about the file pgo-solve wrote.

mod common;

use common::{Dir, Naive, datasets_dir, naive_read, run_with_stdin, s, text};
use serde_json::Value;
use std::f64::consts::PI;
use std::path::Path;
use std::process::Output;

fn solve(args: &[&str]) -> Output {
    run_with_stdin("pgo-solve", args, None)
}

fn json(out: &Output) -> Value {
    assert!(common::exited_normally(out), "{}", text(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}: {}", text(&out.stdout)))
}

fn dataset(name: &str) -> String {
    datasets_dir().join(name).to_str().unwrap().to_string()
}

fn read(path: &Path) -> Naive {
    naive_read(&std::fs::read(path).unwrap())
}

fn vertex(g: &Naive, id: u32) -> [f64; 3] {
    g.vertices.iter().find(|v| v.0 == id).unwrap().1
}

fn bits(p: [f64; 3]) -> [u64; 3] {
    p.map(f64::to_bits)
}

/// g2o's chi2 of the poses of `estimate` for the edges of `graph` (information in g2o order),
/// written out here from g2o's EdgeSE2: e = [R_z^T (R_i^T (t_j - t_i) - t_z); wrap(θ_j - θ_i - θ_z)].
fn naive_chi2(graph: &Naive, estimate: &Naive) -> f64 {
    let wrap = |a: f64| {
        let w = a.rem_euclid(2.0 * PI);
        if w > PI { w - 2.0 * PI } else { w }
    };
    graph
        .edges
        .iter()
        .map(|(i, j, z, o)| {
            let (a, b) = (vertex(estimate, *i), vertex(estimate, *j));
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let (u, v) = (
                a[2].cos() * dx + a[2].sin() * dy - z[0],
                -a[2].sin() * dx + a[2].cos() * dy - z[1],
            );
            let e = [
                z[2].cos() * u + z[2].sin() * v,
                -z[2].sin() * u + z[2].cos() * v,
                wrap(b[2] - a[2] - z[2]),
            ];
            let m = [[o[0], o[1], o[2]], [o[1], o[3], o[4]], [o[2], o[4], o[5]]];
            (0..3)
                .flat_map(|r| (0..3).map(move |c| (r, c)))
                .map(|(r, c)| e[r] * m[r][c] * e[c])
                .sum::<f64>()
        })
        .sum()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1.0)
}

/// MIT.g2o with `FIX` lines appended.
fn mit_with(dir: &Dir, fix: &str) -> String {
    let mut bytes = std::fs::read(dataset("MIT.g2o")).unwrap();
    bytes.extend_from_slice(format!("{fix}\n").as_bytes());
    s(&dir.file("mit-fix.g2o", &bytes)).to_string()
}

#[test]
fn a_fix_vertex_is_the_gauge_with_and_without_refine() {
    let dir = Dir::new();
    let input = mit_with(&dir, "FIX 100");
    let original = read(Path::new(&input));
    let free_out = dir.path("free.g2o");
    let free = json(&solve(&[
        &dataset("MIT.g2o"),
        "--json",
        "--no-timings",
        "-o",
        s(&free_out),
    ]));
    for refine in [false, true] {
        let out_path = dir.path("fixed.g2o");
        let mut args = vec![&input[..], "--json", "--no-timings", "-o", s(&out_path)];
        if refine {
            args.push("--refine");
        }
        let r = json(&solve(&args));
        let written = read(&out_path);
        // Vertex 100 exactly as read, bit for bit; the FIX line is kept.
        assert_eq!(
            bits(vertex(&written, 100)),
            bits(vertex(&original, 100)),
            "refine {refine}"
        );
        assert_eq!(written.fixed, vec![100]);
        if refine {
            // The refined estimate is another estimate (LM held vertex 100): its chi2 is the
            // chi2 of the refined free estimate (the same minimum, moved), to LM's tolerance.
            let fixed_chi2 = r["refined_chi2"].as_f64().unwrap();
            let free_refined = json(&solve(&[
                &dataset("MIT.g2o"),
                "--json",
                "--no-timings",
                "--refine",
                "-o",
                "/dev/null",
            ]));
            let free_chi2 = free_refined["refined_chi2"].as_f64().unwrap();
            assert!(
                close(fixed_chi2, free_chi2, 1e-6),
                "{fixed_chi2} {free_chi2}"
            );
            continue;
        }
        // The same estimate up to a rigid motion: the cost of the written file (computed by
        // pgo-certify from the file) equals the cost without FIX, and distances between poses
        // and differences of headings are those of the free estimate.
        let certify = run_with_stdin(
            "pgo-certify",
            &[&dataset("MIT.g2o"), "--estimate", s(&out_path), "--json"],
            None,
        );
        assert_eq!(certify.status.code(), Some(0), "{}", text(&certify.stderr));
        let c = json(&certify);
        let (cost, free_cost) = (c["cost"].as_f64().unwrap(), free["cost"].as_f64().unwrap());
        assert!(close(cost, free_cost, 1e-9), "{cost} vs {free_cost}");
        assert_eq!(r["cost"], free["cost"]);
        assert_eq!(r["lower_bound"], free["lower_bound"]);
        let free_written = read(&free_out);
        for (i, j) in [(0, 100), (100, 807), (3, 500)] {
            let dist = |g: &Naive| {
                let (a, b) = (vertex(g, i), vertex(g, j));
                ((b[0] - a[0]).hypot(b[1] - a[1]), (b[2] - a[2]).sin())
            };
            let (d, t) = dist(&written);
            let (d0, t0) = dist(&free_written);
            assert!(close(d, d0, 1e-9) && (t - t0).abs() < 1e-9, "{i}-{j}");
        }
        // Without FIX, pose 0 stays where the input has it.
        assert_eq!(bits(vertex(&free_written, 0)), bits(vertex(&original, 0)));
    }
}

#[test]
fn several_fix_vertices_in_one_component_are_refused() {
    let dir = Dir::new();
    let input = mit_with(&dir, "FIX 100\nFIX 5 100");
    for refine in [false, true] {
        let out_path = dir.path("out.g2o");
        let mut args = vec![&input[..], "-o", s(&out_path)];
        if refine {
            args.push("--refine");
        }
        let out = solve(&args);
        assert_eq!(out.status.code(), Some(2));
        let err = text(&out.stderr);
        assert!(
            err.starts_with("pgo-solve: error: FIX lines name vertices 5, 100, which are in one connected component"),
            "{err}"
        );
        assert!(err.contains("known poses"), "{err}");
        assert!(!out_path.exists());
    }
}

#[test]
fn one_fix_vertex_per_component_fixes_each() {
    // Two triangles, inconsistent measurements (the estimate moves), one FIX in each.
    let info = "1 0 0 1 0 1";
    let mut g = String::new();
    for base in [0, 10] {
        for k in 0..3 {
            g += &format!(
                "VERTEX_SE2 {} {}.5 {}.25 {}.75\n",
                base + k,
                k + base,
                2 * k,
                k
            );
        }
        g += &format!("EDGE_SE2 {} {} 1 0.1 0.2 {info}\n", base, base + 1);
        g += &format!("EDGE_SE2 {} {} 1.2 -0.1 2 {info}\n", base + 1, base + 2);
        g += &format!("EDGE_SE2 {} {} -0.9 0.3 -2.1 {info}\n", base + 2, base);
    }
    g += "FIX 2 11\n";
    let dir = Dir::new();
    let input = dir.file("two.g2o", g.as_bytes());
    let out_path = dir.path("out.g2o");
    let out = solve(&[s(&input), "-o", s(&out_path), "--no-timings"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let (before, after) = (read(&input), read(&out_path));
    for id in [2, 11] {
        assert_eq!(bits(vertex(&after, id)), bits(vertex(&before, id)), "{id}");
    }
    for id in [0, 1, 10, 12] {
        assert_ne!(bits(vertex(&after, id)), bits(vertex(&before, id)), "{id}");
    }
}

#[test]
fn solved_angles_are_in_minus_pi_pi() {
    let dir = Dir::new();
    let mit = dataset("MIT.g2o");
    for refine in [false, true] {
        let out_path = dir.path("mit.g2o");
        let mut args = vec![&mit[..], "-o", s(&out_path)];
        if refine {
            args.push("--refine");
        }
        assert_eq!(solve(&args).status.code(), Some(0));
        let g = read(&out_path);
        assert_eq!(g.vertices.len(), 808);
        for (id, p) in &g.vertices {
            assert!(p[2] > -PI && p[2] <= PI, "vertex {id}: {}", p[2]);
        }
    }
}

#[test]
fn chi2_of_the_estimate_and_the_refined_file_named_apart() {
    let dir = Dir::new();
    let input = dataset("intel.g2o");
    let graph = read(Path::new(&input));
    let out_path = dir.path("intel-opt.g2o");
    let r = json(&solve(&[
        &input,
        "--json",
        "--no-timings",
        "-o",
        s(&out_path),
    ]));
    let chi2 = r["chi2"].as_f64().unwrap();
    assert!(
        close(chi2, naive_chi2(&graph, &read(&out_path)), 1e-9),
        "{chi2}"
    );
    assert_eq!(r["written_estimate"], "solved");
    assert_eq!(r["written_chi2"], r["chi2"]);
    assert_eq!(r["written_certified"], true);
    assert_eq!(r["certified"], true);

    let lm_path = dir.path("intel-lm.g2o");
    let out = solve(&[
        &input,
        "--json",
        "--no-timings",
        "--refine",
        "-o",
        s(&lm_path),
    ]);
    let r = json(&out);
    // The cost and bound stay the certified estimate's (as without --refine)...
    assert_eq!(r["certified"], true);
    assert_eq!(r["chi2"].as_f64().unwrap(), chi2);
    // ...and the file holds the refined one, named as such, with its own chi2.
    assert_eq!(r["written_estimate"], "refined");
    assert_eq!(r["written_certified"], false);
    let written_chi2 = r["written_chi2"].as_f64().unwrap();
    assert_eq!(r["refined_chi2"].as_f64().unwrap(), written_chi2);
    assert!(close(
        written_chi2,
        naive_chi2(&graph, &read(&lm_path)),
        1e-9
    ));
    assert!(written_chi2 < chi2);
    // What pgo-certify says of that file: not certified (an optimum of chi2, not of the cost),
    // with the same chi2.
    let certify = run_with_stdin(
        "pgo-certify",
        &[&input, "--estimate", s(&lm_path), "--json"],
        None,
    );
    assert_eq!(certify.status.code(), Some(1));
    let c = json(&certify);
    assert_eq!(c["certified"], false);
    assert!(close(c["chi2"].as_f64().unwrap(), written_chi2, 1e-9));
    assert!(c["cost"].as_f64().unwrap() > r["cost"].as_f64().unwrap());

    let out = solve(&[&input, "--no-timings", "--refine", "-o", "/dev/null"]);
    let report = text(&out.stderr);
    assert!(
        report.contains(&format!(
            "  written estimate     refined by LM (chi2 {written_chi2}), not the certified one; certify it with pgo-certify\n"
        )),
        "{report}"
    );
    assert!(
        report.contains(&format!("  chi2 (g2o)           {chi2}\n")),
        "{report}"
    );
}

#[test]
fn pgo_certify_prints_chi2_and_cost_by_hand() {
    // One edge, x0 = (0, 0, 0), x1 = (1, 2, 0.5), z = (1, 1, 0.3), Ω = diag(2, 3, 5).
    // g2o: e = R(0.3)ᵀ (0, 1) = (sin 0.3, cos 0.3), angle 0.2: chi2 = 2 sin² + 3 cos² + 5·0.04.
    // f: τ = 2 / (1/2 + 1/3) = 2.4 times |(1, 2) - (1, 1)|² = 1, κ = 10 times |e^{0.5i} - e^{0.3i}|².
    let g = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 2 0.5\nEDGE_SE2 0 1 1 1 0.3 2 0 0 3 0 5\n";
    let dir = Dir::new();
    let input = dir.file("one.g2o", g.as_bytes());
    let out = run_with_stdin("pgo-certify", &[s(&input), "--json"], None);
    assert_eq!(out.status.code(), Some(1));
    let c = json(&out);
    let (sn, cs) = 0.3f64.sin_cos();
    let chi2 = 2.0 * sn * sn + 3.0 * cs * cs + 5.0 * 0.04;
    let cost = 2.4 + 10.0 * (2.0 - 2.0 * 0.2f64.cos());
    assert!(
        close(c["chi2"].as_f64().unwrap(), chi2, 1e-14),
        "{}",
        c["chi2"]
    );
    assert!(
        close(c["cost"].as_f64().unwrap(), cost, 1e-14),
        "{}",
        c["cost"]
    );
}

#[test]
fn the_report_says_what_ran_and_warns_of_an_unused_solver() {
    let toy = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/paper_toy.g2o");
    let header = |out: &Output| text(&out.stderr).lines().next().unwrap_or("").to_string();
    // On the paper's toy graph (the relaxation is not exact) auto returns the lower of the SDP's
    // and the staircase's estimates, which agree to the last digits of f: the header names the
    // one the JSON report says won.
    let out = solve(&[toy, "--weights", "unit", "-o", "/dev/null"]);
    let report = json(&solve(&[
        toy,
        "--weights",
        "unit",
        "--json",
        "-o",
        "/dev/null",
    ]));
    let won = match report["components"][0]["method"].as_str() {
        Some("sdp") => "; method auto: sdp (ipm)",
        Some("staircase") => "; method auto: staircase",
        other => panic!("{other:?}"),
    };
    assert!(header(&out).ends_with(won), "{}", header(&out));
    let out = solve(&[
        toy,
        "--weights",
        "unit",
        "--method",
        "staircase",
        "-o",
        "/dev/null",
    ]);
    assert!(
        header(&out).ends_with("; method staircase"),
        "{}",
        header(&out)
    );

    // MIT (808 poses, staircase), a triangle (sdp) and a chain of three poses (a tree, composed)
    // in one file.
    let dir = Dir::new();
    let mut bytes = std::fs::read(dataset("MIT.g2o")).unwrap();
    let chain = b"VERTEX_SE2 6000 0 0 0\nVERTEX_SE2 6001 3 1 2\nVERTEX_SE2 6002 -1 0 0\n\
          EDGE_SE2 6000 6001 1 0 0.5 1 0 0 1 0 1\nEDGE_SE2 6002 6001 0 1 0 1 0 0 1 0 1\n";
    bytes.extend_from_slice(
        b"VERTEX_SE2 5000 0 0 0\nVERTEX_SE2 5001 1 0 0\nVERTEX_SE2 5002 1 1 0\n\
          EDGE_SE2 5000 5001 1 0 0 1 0 0 1 0 1\nEDGE_SE2 5001 5002 0 1 0 1 0 0 1 0 1\n\
          EDGE_SE2 5002 5000 -1 -1.1 0.1 1 0 0 1 0 1\n",
    );
    bytes.extend_from_slice(chain);
    let mixed = dir.file("mixed.g2o", &bytes);
    let out = solve(&[s(&mixed), "-o", "/dev/null"]);
    assert!(
        header(&out)
            .ends_with("; method auto: sdp (ipm) on 1 component, staircase on 1, tree on 1"),
        "{}",
        header(&out)
    );
    assert!(!text(&out.stderr).contains("warning"));
    // The chain alone: its lower bound 0 and why, no computation.
    let out = solve(&[s(&dir.file("chain.g2o", chain)), "-o", "/dev/null"]);
    assert!(
        header(&out).ends_with("; method auto: tree"),
        "{}",
        header(&out)
    );
    let report = text(&out.stderr);
    assert!(report.contains("\n  lower bound          0\n"), "{report}");
    assert!(
        report.contains("SZEP                 yes (a tree: lambda* = 0"),
        "{report}"
    );

    // --solver where no component runs the SDP: a warning, the same report.
    let mit = dataset("MIT.g2o");
    let plain = solve(&[&mit, "--json", "--no-timings", "-o", "/dev/null"]);
    let out = solve(&[
        &mit,
        "--json",
        "--no-timings",
        "-o",
        "/dev/null",
        "--solver",
        "clarabel",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let (mut with, without) = (json(&out), json(&plain));
    assert_eq!(with["solver"], "clarabel");
    with["solver"] = "ipm".into();
    assert_eq!(with, without);
    assert_eq!(
        text(&out.stderr),
        "pgo-solve: warning: --solver clarabel had no effect: no component was solved by the SDP (method auto: staircase)\n"
    );
}

#[test]
fn fail_uncertified_exits_1_and_still_writes() {
    // The toy graph under unit weights is not certified (Appendix 8.8); MIT is.
    let toy = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/paper_toy.g2o");
    let dir = Dir::new();
    let out_path = dir.path("toy.g2o");
    let out = solve(&[toy, "--weights", "unit", "-o", s(&out_path)]);
    assert_eq!(out.status.code(), Some(0));
    assert!(text(&out.stderr).contains("NOT certified"));
    std::fs::remove_file(&out_path).unwrap();
    let out = solve(&[
        toy,
        "--weights",
        "unit",
        "-o",
        s(&out_path),
        "--fail-uncertified",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert_eq!(read(&out_path).vertices.len(), 5);
    let out = solve(&[&dataset("MIT.g2o"), "-o", "/dev/null", "--fail-uncertified"]);
    assert_eq!(out.status.code(), Some(0));
}

#[test]
fn bad_tolerance_and_outputs_are_named_before_the_work() {
    let mit = dataset("MIT.g2o");
    for tool in ["pgo-solve", "pgo-certify"] {
        for tol in [&["--tol", "-1"][..], &["--tol=-1"][..]] {
            let mut args = vec![&mit[..]];
            args.extend_from_slice(tol);
            let out = run_with_stdin(tool, &args, None);
            assert_eq!(out.status.code(), Some(2), "{tool} {tol:?}");
            assert!(
                text(&out.stderr).contains("--tol must be a finite number >= 0, found -1"),
                "{tool} {tol:?}: {}",
                text(&out.stderr)
            );
        }
    }
    let dir = Dir::new();
    let out = solve(&[&mit, "-o", s(dir.0.path())]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        text(&out.stderr),
        format!(
            "pgo-solve: error: {}: is a directory, not a file to write\n",
            s(dir.0.path())
        )
    );
    let missing = dir.path("no/such/out.g2o");
    let out = solve(&[&mit, "-o", s(&missing)]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        text(&out.stderr),
        format!(
            "pgo-solve: error: {}: directory {} does not exist\n",
            s(&missing),
            s(&dir.path("no/such"))
        )
    );
    let out = run_with_stdin("pgo-convert", &[&mit, "-o", s(dir.0.path())], None);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        text(&out.stderr),
        format!(
            "pgo-convert: error: {}: is a directory, not a file to write\n",
            s(dir.0.path())
        )
    );
    assert!(dir.entries().is_empty());
}
