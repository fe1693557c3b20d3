//! Vertigo's robust file types (`EDGE_SE2_SWITCHABLE` with `VERTEX_SWITCH` and
//! `EDGE_SWITCH_PRIOR`, `EDGE_SE2_MAXMIX`): read as loop closures, written back line for line by
//! `pgo-convert` and `pgo-solve -o`, refused where they cannot be kept, never dropped silently.

mod common;

use std::path::Path;
use std::process::{Command, Output, Stdio};

fn run(tool: &str, args: &[&str]) -> Output {
    let exe = match tool {
        "pgo-solve" => env!("CARGO_BIN_EXE_pgo-solve"),
        "pgo-convert" => env!("CARGO_BIN_EXE_pgo-convert"),
        _ => unreachable!(),
    };
    Command::new(exe)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

/// A square of 6 poses with odometry, two switchable loop closures (one of them false), one
/// max-mixture loop closure, their switches and priors, as Vertigo's generator lays them out.
const FILE: &str = "\
VERTEX_SE2 0 0 0 0
VERTEX_SE2 1 1 0 1.5707963267948966
VERTEX_SE2 2 1 1 3.141592653589793
VERTEX_SE2 3 0 1 -1.5707963267948966
VERTEX_SE2 4 0 0 0
VERTEX_SE2 5 1 0 1.5707963267948966
EDGE_SE2 0 1 1 0 1.5707963267948966 100 0 0 100 0 1000
EDGE_SE2 1 2 1 0 1.5707963267948966 100 0 0 100 0 1000
EDGE_SE2 2 3 1 0 1.5707963267948966 100 0 0 100 0 1000
EDGE_SE2 3 4 1 0 1.5707963267948966 100 0 0 100 0 1000
EDGE_SE2 4 5 1 0 1.5707963267948966 100 0 0 100 0 1000
VERTEX_SWITCH 6 1
EDGE_SWITCH_PRIOR 6 1 1
EDGE_SE2_SWITCHABLE 0 4 6 0 0 0 100 0 0 100 0 1000
VERTEX_SWITCH 7 1
EDGE_SWITCH_PRIOR 7 1 1
EDGE_SE2_SWITCHABLE 1 3 7 0.25 -0.1 0.3 100 0 0 100 0 1000
EDGE_SE2_MAXMIX 1 5 1e-07 0 0 0 100 0 0 100 0 1000
";

/// The lines of a g2o text as sorted lists of (tag, numbers), independent of the library.
fn lines(text: &str) -> Vec<(String, Vec<f64>)> {
    let mut v: Vec<(String, Vec<f64>)> = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let mut f = l.split_whitespace();
            let tag = f.next().unwrap().to_string();
            (tag, f.map(|x| x.parse().unwrap()).collect())
        })
        .collect();
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

#[test]
fn convert_keeps_every_line() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "in.g2o", FILE);
    let once = dir.path().join("once.g2o");
    let twice = dir.path().join("twice.g2o");
    let out = run("pgo-convert", &[&input, "-o", once.to_str().unwrap()]);
    assert!(out.status.success(), "{}", common::text(&out.stderr));
    // Said, not silent: the warning names the counts.
    let stderr = common::text(&out.stderr);
    assert!(
        stderr.contains("2 EDGE_SE2_SWITCHABLE and 1 EDGE_SE2_MAXMIX"),
        "{stderr}"
    );
    let written = std::fs::read_to_string(&once).unwrap();
    assert_eq!(lines(&written), lines(FILE));
    let out = run(
        "pgo-convert",
        &[once.to_str().unwrap(), "-o", twice.to_str().unwrap()],
    );
    assert!(out.status.success());
    assert_eq!(
        std::fs::read(&once).unwrap(),
        std::fs::read(&twice).unwrap()
    );
}

#[test]
fn robust_solve_rejects_the_false_switchable_edge_and_writes_every_line() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "in.g2o", FILE);
    let all = dir.path().join("all.g2o");
    let inliers = dir.path().join("inliers.g2o");
    let out = run(
        "pgo-solve",
        &[
            &input,
            "--robust",
            "tls",
            "--json",
            "-o",
            all.to_str().unwrap(),
        ],
    );
    assert!(out.status.success(), "{}", common::text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rejected = &json["robust"]["rejected_edges"];
    assert_eq!(rejected.as_array().unwrap().len(), 1, "{json}");
    assert_eq!(rejected[0]["line"], 17);
    assert_eq!(
        (rejected[0]["i"].clone(), rejected[0]["j"].clone()),
        (1.into(), 3.into())
    );
    assert_eq!(json["certified"], true);
    // Every line back, with the estimate's poses.
    let tags = |text: &str| {
        let mut t: Vec<String> = lines(text)
            .into_iter()
            .map(|(t, f)| format!("{t} {}", f.len()))
            .collect();
        t.sort();
        t
    };
    let written = std::fs::read_to_string(&all).unwrap();
    assert_eq!(tags(&written), tags(FILE));
    let out = run(
        "pgo-solve",
        &[
            &input,
            "--robust",
            "tls",
            "--drop-outliers",
            "-o",
            inliers.to_str().unwrap(),
        ],
    );
    assert!(out.status.success());
    let written = std::fs::read_to_string(&inliers).unwrap();
    assert_eq!(written.matches("EDGE_SE2_SWITCHABLE").count(), 1);
    assert_eq!(written.matches("EDGE_SE2_MAXMIX").count(), 1);
    assert!(!written.contains("EDGE_SE2_SWITCHABLE 1 3 "));
}

#[test]
fn where_they_cannot_be_kept_or_are_malformed_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "in.g2o", FILE);
    let short = write(
        dir.path(),
        "short.g2o",
        &FILE.replace(
            "EDGE_SE2_SWITCHABLE 0 4 6 0 0 0",
            "EDGE_SE2_SWITCHABLE 0 4 0 0 0",
        ),
    );
    let bad_weight = write(dir.path(), "weight.g2o", &FILE.replace("1e-07", "heavy"));
    let bad_switch = write(
        dir.path(),
        "switch.g2o",
        &FILE.replace("VERTEX_SWITCH 7 1", "VERTEX_SWITCH 7"),
    );
    let out_graph = dir.path().join("x.graph");
    let cases: Vec<(&str, Vec<&str>, &str)> = vec![
        (
            "pgo-convert",
            vec![&input, "--to", "toro", "-o", out_graph.to_str().unwrap()],
            "write g2o",
        ),
        (
            "pgo-convert",
            vec![&input, "--reindex", "-o", "-"],
            "switch variables",
        ),
        ("pgo-convert", vec![&short, "-o", "-"], "short.g2o:14:"),
        (
            "pgo-convert",
            vec![&bad_weight, "-o", "-"],
            "weight.g2o:18:",
        ),
        (
            "pgo-solve",
            vec![&bad_switch, "--robust", "tls"],
            "switch.g2o:15:",
        ),
    ];
    for (tool, args, expect) in cases {
        let out = run(tool, &args);
        let stderr = common::text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{tool} {args:?}: {stderr}");
        assert!(stderr.contains(expect), "{tool} {args:?}: {stderr}");
        assert!(!stderr.contains("panicked"));
    }
    assert!(!out_graph.exists());
}

/// The edge lines of a g2o text in their order, as (tag, numbers).
fn edge_lines(text: &str) -> Vec<(String, Vec<f64>)> {
    text.lines()
        .filter(|l| l.starts_with("EDGE_SE2"))
        .map(|l| {
            let mut f = l.split_whitespace();
            let tag = f.next().unwrap().to_string();
            (tag, f.map(|x| x.parse().unwrap()).collect())
        })
        .collect()
}

/// A file of 12000 edges of all three kinds is written with its edges in input order, every
/// number kept: the writer formats the last edges on a second thread from 8192 edges on, and
/// the two halves must join in order.
#[test]
fn convert_keeps_every_edge_in_order_in_large_files() {
    let n = 6000;
    let mut text = String::new();
    for i in 0..n {
        text += &format!(
            "VERTEX_SE2 {i} {} {} {}\n",
            i as f64 * 0.5,
            (i % 7) as f64,
            0.001 * i as f64
        );
    }
    let mut switch = n;
    for i in 0..n - 1 {
        text += &format!("EDGE_SE2 {i} {} 0.5 0.25 0.001 100 0 0 100 0 1000\n", i + 1);
        let j = (i * 37 + 11) % n;
        if j == i {
            continue;
        }
        if i % 2 == 0 {
            text += &format!("VERTEX_SWITCH {switch} 1\nEDGE_SWITCH_PRIOR {switch} 1 1\n");
            text += &format!(
                "EDGE_SE2_SWITCHABLE {i} {j} {switch} {} -0.125 0.3 100 0 0 100 0 1000\n",
                i as f64 / 8.0
            );
            switch += 1;
        } else {
            text += &format!(
                "EDGE_SE2_MAXMIX {i} {j} 1e-7 {} 0 0.5 100 0 0 100 0 1000\n",
                j as f64 / 4.0
            );
        }
    }
    let input_edges = edge_lines(&text);
    assert!(input_edges.len() > 10000, "{}", input_edges.len());
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "large.g2o", &text);
    let once = dir.path().join("once.g2o");
    let out = run("pgo-convert", &[&input, "-o", once.to_str().unwrap()]);
    assert!(out.status.success(), "{}", common::text(&out.stderr));
    let written = std::fs::read_to_string(&once).unwrap();
    assert_eq!(edge_lines(&written), input_edges);
    assert_eq!(lines(&written), lines(&text));
}
