//! 3D pose graphs in the file layer (issue 15, first landing): g2o `VERTEX_SE3:QUAT` /
//! `EDGE_SE3:QUAT` and TORO `VERTEX3` / `EDGE3` read, written back bit for bit, described by
//! `pgo-convert --stats`, and refused by the solving tools with a specific message.
//!
//! Held against: a naive reader written here (split on whitespace, `str::parse`), values and
//! positions worked out by hand, the data sets' MANIFEST counts, and round trips.

mod common;

use common::{Dir, bin, datasets_dir, input_tools, manifest, run_tool, s, text};
use pgo::graph3::{Form3, Graph3, Rotation3};
use pgo::io::{self, AnyGraph, Format, ReadOptions};
use std::process::Command;

const FILES: [&str; 7] = [
    "sphere2500.g2o",
    "torus3D.g2o",
    "parking-garage.g2o",
    "cubicle.g2o",
    "sphere_bignoise_vertex3.g2o",
    "smallGrid3D.g2o",
    "tinyGrid3D.g2o",
];

/// Every number of every vertex and edge line, in file order, by a reader that knows nothing
/// but the line layouts: (tag, ids, values).
fn naive3(bytes: &[u8]) -> Vec<(String, Vec<u32>, Vec<u64>)> {
    let text = String::from_utf8(bytes.to_vec()).unwrap();
    let mut out = Vec::new();
    for line in text.lines() {
        let t: Vec<&str> = line.split_whitespace().collect();
        let ids = match t.first().copied() {
            Some("VERTEX_SE3:QUAT" | "VERTEX3") => 1,
            Some("EDGE_SE3:QUAT" | "EDGE3") => 2,
            _ => continue,
        };
        out.push((
            t[0].to_string(),
            t[1..=ids].iter().map(|v| v.parse().unwrap()).collect(),
            t[ids + 1..]
                .iter()
                .map(|v| v.parse::<f64>().unwrap().to_bits())
                .collect(),
        ));
    }
    out
}

fn read3_path(path: &str) -> Graph3 {
    match io::read_any_path(path, &ReadOptions::default()).unwrap().0 {
        AnyGraph::Spatial(g) => g,
        AnyGraph::Planar(_) => panic!("{path}: read as planar"),
    }
}

fn written(g: &Graph3, format: Format) -> Vec<u8> {
    let mut out = Vec::new();
    io::write3(g, format, &mut out).unwrap();
    out
}

#[test]
fn every_public_3d_file_round_trips_bit_for_bit() {
    let counts = manifest();
    for name in FILES {
        let path = datasets_dir().join(name);
        let original = std::fs::read(&path).unwrap();
        let g = read3_path(s(&path));
        let entry = counts.iter().find(|e| e.file == name).unwrap();
        assert_eq!(
            (g.num_poses(), g.edges.len()),
            (entry.poses, entry.edges),
            "{name}: MANIFEST counts"
        );
        assert_eq!(g.form, Form3::G2o);
        // The naive reader's values of the original file are the graph's, bit for bit (the
        // files list vertices in id order).
        let lines = naive3(&original);
        let mut vertices = lines.iter().filter(|l| l.0 == "VERTEX_SE3:QUAT");
        for (id, pose) in g.ids.iter().zip(&g.poses) {
            let (_, ids, values) = vertices.next().unwrap();
            assert_eq!(ids, &[*id], "{name}");
            let mine: Vec<u64> = pose.values().map(f64::to_bits).collect();
            assert_eq!(&mine, values, "{name}: vertex {id}");
        }
        let mut edges = lines.iter().filter(|l| l.0 == "EDGE_SE3:QUAT");
        for e in &g.edges {
            let (_, ids, values) = edges.next().unwrap();
            assert_eq!(ids, &[g.ids[e.i], g.ids[e.j]], "{name}");
            let mine: Vec<u64> = e
                .measurement
                .values()
                .chain(e.information.0)
                .map(f64::to_bits)
                .collect();
            assert_eq!(&mine, values, "{name}: edge {ids:?}");
        }
        // Written and read back by the naive reader: the same tags, ids and bits.
        let bytes = written(&g, Format::G2o);
        assert_eq!(naive3(&bytes), lines, "{name}: written file");
        // Read back by pgo: the same graph, and the same bytes again.
        let (back, _) = io::read_any(&bytes, name, &ReadOptions::default()).unwrap();
        assert_eq!(back, AnyGraph::Spatial(g.clone()), "{name}: read back");
        let AnyGraph::Spatial(back) = back else {
            panic!("{name}: read back as planar")
        };
        assert_eq!(written(&back, Format::G2o), bytes, "{name}: second write");
    }
}

/// One line of each type, every field checked by hand.
#[test]
fn one_line_of_each_type_parses_as_worked_out_by_hand() {
    // Information values 1..21: row 0 holds (0,0)..(0,5) = 1..6, row 1 (1,1)..(1,5) = 7..11,
    // row 2 (2,2)..(2,5) = 12..15, row 3 16..18, row 4 19..20, row 5 (5,5) = 21.
    let info: String = (1..=21).map(|k| format!(" {k}")).collect();
    let g2o = format!(
        "VERTEX_SE3:QUAT 4 1.5 -2 3e-1 0 0 1 1\nVERTEX_SE3:QUAT 9 0 0 0 0 0 0 -1\nEDGE_SE3:QUAT 9 4 1 2 3 0 0 0 2{info}\nFIX 9\n"
    );
    // 1..21 is no positive definite matrix: read as is.
    let any = ReadOptions {
        allow_indefinite: true,
        ..Default::default()
    };
    let (g, report) = io::read_any(g2o.as_bytes(), "hand.g2o", &any).unwrap();
    let AnyGraph::Spatial(g) = g else { panic!() };
    assert_eq!((report.format, report.lines), (Format::G2o, 4));
    assert_eq!(g.ids, [4, 9]);
    assert_eq!(g.poses[0].translation, [1.5, -2.0, 0.3]);
    assert_eq!(
        g.poses[0].rotation,
        Rotation3::Quaternion([0.0, 0.0, 1.0, 1.0])
    );
    // qw = -1: kept as written, the identity rotation.
    assert_eq!(
        g.poses[1].rotation,
        Rotation3::Quaternion([0.0, 0.0, 0.0, -1.0])
    );
    let e = &g.edges[0];
    assert_eq!((e.i, e.j), (1, 0)); // 9 -> 4, dense indices
    assert_eq!(e.measurement.translation, [1.0, 2.0, 3.0]);
    // qw = 2: the identity once normalized, kept as 2.
    assert_eq!(
        e.measurement.rotation,
        Rotation3::Quaternion([0.0, 0.0, 0.0, 2.0])
    );
    let m = &e.information;
    for (r, c, v) in [
        (0, 0, 1.0),
        (0, 5, 6.0),
        (5, 0, 6.0),
        (1, 1, 7.0),
        (1, 5, 11.0),
        (2, 3, 13.0),
        (3, 2, 13.0),
        (3, 3, 16.0),
        (4, 5, 20.0),
        (5, 5, 21.0),
    ] {
        assert_eq!(m.get(r, c), v, "({r}, {c})");
    }
    assert_eq!(g.fixed, [1]);
    // (0, 0, 1, 1) normalized: a quarter turn about z, x goes to y.
    let x = g.poses[0].rotation.unit_quaternion() * nalgebra::Vector3::new(1.0, 0.0, 0.0);
    assert!((x - nalgebra::Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-15);

    // TORO: VERTEX3 id x y z roll pitch yaw; EDGE3 i j x y z roll pitch yaw + 21.
    let toro = format!(
        "VERTEX3 0 1 2 3 0.1 -0.2 4\nVERTEX3 1 0 0 0 0 0 0\nEDGE3 0 1 1 0 0 0.5 0 -0.5{info}\n"
    );
    let (g, report) = io::read_any(toro.as_bytes(), "hand.graph", &any).unwrap();
    let AnyGraph::Spatial(g) = g else { panic!() };
    assert_eq!((g.form, report.format), (Form3::Toro, Format::Toro));
    assert_eq!(g.poses[0].translation, [1.0, 2.0, 3.0]);
    // Angles as written (4 rad is not wrapped).
    assert_eq!(g.poses[0].rotation, Rotation3::Euler([0.1, -0.2, 4.0]));
    assert_eq!(
        g.edges[0].measurement.rotation,
        Rotation3::Euler([0.5, 0.0, -0.5])
    );
    assert_eq!(g.edges[0].information.get(2, 3), 13.0);
    // Written back: the same text, numbers in shortest form.
    assert_eq!(String::from_utf8(written(&g, Format::Toro)).unwrap(), toro);
}

#[test]
fn g2o_and_toro_3d_are_not_converted_into_each_other() {
    let g = read3_path(s(&datasets_dir().join("tinyGrid3D.g2o")));
    let e = io::write3(&g, Format::Toro, Vec::new())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cannot be written as TORO") && e.contains("without loss"),
        "{e}"
    );
    let toro = "VERTEX3 0 0 0 0 0 0 0\n";
    let (g, _) = io::read_any(toro.as_bytes(), "t.graph", &ReadOptions::default()).unwrap();
    let AnyGraph::Spatial(g) = g else { panic!() };
    let e = io::write3(&g, Format::G2o, Vec::new())
        .unwrap_err()
        .to_string();
    assert!(e.contains("cannot be written as g2o"), "{e}");
}

#[test]
fn pgo_convert_round_trips_and_describes_3d_files() {
    let dir = Dir::new();
    let input = datasets_dir().join("tinyGrid3D.g2o");
    let out = dir.path("out.g2o");
    let run = Command::new(bin("pgo-convert"))
        .args([s(&input), "-o", s(&out), "--quiet"])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", text(&run.stderr));
    let again = dir.path("again.g2o");
    let run = Command::new(bin("pgo-convert"))
        .args([s(&out), "-o", s(&again), "--quiet", "--reindex"])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", text(&run.stderr));
    let (a, b) = (std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());
    // Ids are 0..8 already: --reindex changes nothing.
    assert_eq!(a, b);
    assert_eq!(naive3(&a), naive3(&std::fs::read(&input).unwrap()));

    // To TORO: refused, exit 2, nothing written.
    let toro = dir.path("out.graph");
    let run = Command::new(bin("pgo-convert"))
        .args([s(&input), "-o", s(&toro)])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(
        text(&run.stderr).contains("without loss"),
        "{}",
        text(&run.stderr)
    );
    assert!(!toro.exists());

    // --stats: the edges of tinyGrid3D.g2o are 0-1 1-2 2-3 3-4 4-5 5-6 6-7 7-8 1-8 3-6 7-2
    // (listed with awk): 8 with j = i + 1, 3 loop closures, one written backwards (7-2).
    let run = Command::new(bin("pgo-convert"))
        .args(["--stats", "--json", s(&input)])
        .output()
        .unwrap();
    assert!(run.status.success());
    let json = text(&run.stdout);
    for field in [
        "\"dimension\":3",
        "\"poses\":9",
        "\"edges\":11",
        "\"odometry_edges\":8",
        "\"loop_closures\":3",
        "\"backward_edges\":1",
        "\"duplicate_edges\":0",
        "\"components\":1",
        "\"id_min\":0",
        "\"id_max\":8",
        "\"id_gaps\":0",
    ] {
        assert!(json.contains(field), "{field} in {json}");
    }
    // Every public 3D file: its MANIFEST counts, one component.
    for entry in manifest().iter().filter(|e| e.format == "g2o-3d") {
        let run = Command::new(bin("pgo-convert"))
            .args(["--stats", "--json", s(&datasets_dir().join(&entry.file))])
            .output()
            .unwrap();
        let json = text(&run.stdout);
        assert!(
            json.contains(&format!("\"poses\":{},", entry.poses))
                && json.contains(&format!("\"edges\":{},", entry.edges)),
            "{}: {json}",
            entry.file
        );
    }
}

#[test]
fn the_planar_only_tools_refuse_3d_files_with_a_specific_message() {
    let input = datasets_dir().join("tinyGrid3D.g2o");
    for tool in input_tools()
        .iter()
        .filter(|t| !READS_3D.contains(&t.name.as_str()))
    {
        let dir = Dir::new();
        let output = dir.path("out.g2o");
        let out = run_tool(tool, &input, Some(&output), &[]);
        assert_eq!(out.status.code(), Some(2), "{}", tool.name);
        assert_eq!(
            text(&out.stderr),
            format!(
                "{}:1:1: error: 3D pose graph (tag VERTEX_SE3:QUAT): this tool handles planar SE(2) graphs only (pgo-solve and pgo-certify solve and certify 3D files, pgo-spectrum prints their spectra, pgo-eval compares them; pgo-convert reads, writes and describes them)\n",
                s(&input)
            ),
            "{}",
            tool.name
        );
        assert!(!output.exists());
    }
}

/// The tools that read 3D files (issue 15).
const READS_3D: [&str; 5] = [
    "pgo-convert",
    "pgo-solve",
    "pgo-certify",
    "pgo-spectrum",
    "pgo-eval",
];

#[test]
fn pgo_convert_round_trips_toro_3d_and_reads_3d_on_stdin() {
    let dir = Dir::new();
    // Written as pgo writes: shortest numbers, single spaces, vertices by id.
    let toro = "VERTEX3 0 0 0 0 0 0 0\nVERTEX3 1 1 0 0 0.1 -0.2 4\nEDGE3 0 1 1 0 0 0.1 -0.2 4 100 0 0 0 0 0 100 0 0 0 0 100 0 0 0 25 0 0 25 0 25\nFIX 0\n";
    let input = dir.file("in.graph", toro.as_bytes());
    let out = dir.path("out.graph");
    let run = Command::new(bin("pgo-convert"))
        .args([s(&input), "-o", s(&out), "--quiet"])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", text(&run.stderr));
    assert_eq!(std::fs::read_to_string(&out).unwrap(), toro);
    // To g2o: refused, nothing written.
    let g2o = dir.path("out.g2o");
    let run = Command::new(bin("pgo-convert"))
        .args([s(&input), "-o", s(&g2o)])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(!g2o.exists());
    // A covariance dialect does not apply to 3D files.
    let run = Command::new(bin("pgo-convert"))
        .args([s(&input), "--dialect", "toro-cov", "-o", s(&out)])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(text(&run.stderr).contains("does not apply to a 3D file"));
    // On stdin, the tags decide: the same bytes as from the file.
    let run = common::run_with_stdin("pgo-convert", &["-", "--quiet"], Some(toro.as_bytes()));
    assert!(run.status.success(), "{}", text(&run.stderr));
    assert_eq!(text(&run.stdout), toro);
}

/// A path that can be read only once (a FIFO, as a shell's `<(zcat graph.g2o.gz)` gives; here
/// /dev/stdin on a pipe): a 3D file is read from it as from the file itself. (The planar reader
/// used to drain it and the 3D reader then found it empty.)
#[test]
fn a_3d_file_is_read_from_a_path_that_can_be_read_once() {
    for name in ["tinyGrid3D.g2o", "smallGrid3D.g2o"] {
        let path = datasets_dir().join(name);
        let from_file = Command::new(bin("pgo-solve"))
            .args([s(&path), "--json", "--no-timings"])
            .output()
            .unwrap();
        assert!(from_file.status.success(), "{}", text(&from_file.stderr));
        let bytes = std::fs::read(&path).unwrap();
        let from_pipe = common::run_with_stdin(
            "pgo-solve",
            &["/dev/stdin", "--json", "--no-timings"],
            Some(&bytes),
        );
        assert!(
            from_pipe.status.success(),
            "{name}: {}",
            text(&from_pipe.stderr)
        );
        assert_eq!(text(&from_pipe.stdout), text(&from_file.stdout), "{name}");
        // pgo-convert describes it as the 3D graph it is.
        let convert =
            common::run_with_stdin("pgo-convert", &["/dev/stdin", "--stats"], Some(&bytes));
        assert!(
            convert.status.success(),
            "{name}: {}",
            text(&convert.stderr)
        );
        assert!(text(&convert.stdout).contains("(SE(3) poses)"), "{name}");
    }
}
