//! The readers and writers against every public data set in `../shared/datasets`: counts from
//! MANIFEST.tsv, values against a naive independent parse, lossless round trips, and the
//! parser oddities the data set README lists.

mod common;

use common::*;
use pgo::io::{self, Dialect, Format, ReadOptions, WriteOptions};
use pgo::stats::GraphStats;
use pgo::{PoseGraph, VertexId};

/// The 2D pose-graph files (3D files and GTSAM's bearing-range landmark file are rejected, tested
/// below; the LANDMARK2 files are read in tests/landmarks.rs).
fn planar_files() -> Vec<ManifestEntry> {
    manifest()
        .into_iter()
        .filter(|e| {
            matches!(
                e.format.as_str(),
                "g2o-2d" | "toro-2d" | "toro-2d-g2o-info-order"
            )
        })
        .collect()
}

/// Reads a public file as `pgo-convert --stats` does: w100.graph's EQUIV lines are skipped (its
/// statistics describe the file; every tool that solves refuses them unless told to skip them).
fn read(name: &str) -> (PoseGraph, io::ReadReport) {
    let path = datasets_dir().join(name);
    let options = ReadOptions {
        ignore_equiv: true,
        ..Default::default()
    };
    io::read_path(path.to_str().unwrap(), &options).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn to_bytes(g: &PoseGraph, format: Format, dialect: Dialect) -> Vec<u8> {
    let mut out = Vec::new();
    io::write(g, WriteOptions { format, dialect }, &mut out).unwrap();
    out
}

fn from_bytes(bytes: &[u8], name: &str) -> PoseGraph {
    io::read(bytes, name, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .0
}

/// Every value of two graphs, bit for bit (so -0 and 0 differ).
fn assert_same_bits(a: &PoseGraph, b: &PoseGraph, what: &str) {
    assert_eq!(a.ids, b.ids, "{what}: ids");
    assert_eq!(a.fixed, b.fixed, "{what}: fixed");
    assert_eq!(a.noise, b.noise, "{what}: noise kind");
    for (k, (p, q)) in a.poses.iter().zip(&b.poses).enumerate() {
        assert_eq!(bits(&p.values()), bits(&q.values()), "{what}: pose {k}");
    }
    assert_eq!(a.edges.len(), b.edges.len(), "{what}: edge count");
    for (k, (e, f)) in a.edges.iter().zip(&b.edges).enumerate() {
        assert_eq!((e.i, e.j), (f.i, f.j), "{what}: edge {k}");
        assert_eq!(
            bits(&e.measurement.values()),
            bits(&f.measurement.values()),
            "{what}: edge {k} measurement"
        );
        assert_eq!(bits(&e.noise.0), bits(&f.noise.0), "{what}: edge {k} noise");
    }
}

#[test]
fn manifest_lists_the_planar_files() {
    let files = planar_files();
    assert!(files.len() >= 35, "only {} planar files", files.len());
    for e in &files {
        let meta = std::fs::metadata(datasets_dir().join(&e.file)).unwrap();
        assert_eq!(
            meta.len(),
            e.bytes,
            "{}: size differs from MANIFEST.tsv",
            e.file
        );
    }
}

#[test]
fn every_planar_file_parses_with_the_manifest_counts_and_exact_values() {
    for e in planar_files() {
        let (g, report) = read(&e.file);
        let raw = std::fs::read(datasets_dir().join(&e.file)).unwrap();
        let naive = naive_read(&raw);
        assert_eq!(g.edges.len(), e.edges, "{}: edges", e.file);
        assert_eq!(naive.edges.len(), e.edges, "{}: naive edges", e.file);
        let expected_dialect = match e.format.as_str() {
            "g2o-2d" | "toro-2d-g2o-info-order" => Dialect::G2o,
            _ => Dialect::ToroInfo,
        };
        assert_eq!(report.dialect, expected_dialect, "{}: dialect", e.file);

        if e.poses > 0 {
            assert!(g.vertices_declared, "{}", e.file);
            assert_eq!(g.num_poses(), e.poses, "{}: poses", e.file);
            // Every vertex exactly as written.
            let mut v = naive.vertices.clone();
            v.sort_by_key(|x| x.0);
            for ((id, p), (gid, gp)) in v.iter().zip(g.ids.iter().zip(&g.poses)) {
                assert_eq!(id, gid, "{}", e.file);
                assert_eq!(bits(p), bits(&gp.values()), "{}: vertex {id}", e.file);
            }
        } else {
            // No vertex lines: the poses are the ids the edges mention.
            assert!(!g.vertices_declared, "{}", e.file);
            let mut ids: Vec<u32> = naive.edges.iter().flat_map(|x| [x.0, x.1]).collect();
            ids.sort_unstable();
            ids.dedup();
            assert_eq!(g.ids, ids, "{}: ids", e.file);
        }

        // Every edge exactly as written, in input order, information mapped per docs/formats.md §3.1.
        for (k, ((i, j, z, n), ge)) in naive.edges.iter().zip(&g.edges).enumerate() {
            assert_eq!((g.ids[ge.i], g.ids[ge.j]), (*i, *j), "{}: edge {k}", e.file);
            assert_eq!(
                bits(z),
                bits(&ge.measurement.values()),
                "{}: edge {k}",
                e.file
            );
            let expect = if expected_dialect == Dialect::ToroInfo {
                toro_to_g2o(*n)
            } else {
                *n
            };
            assert_eq!(
                bits(&expect),
                bits(&ge.noise.0),
                "{}: edge {k} noise",
                e.file
            );
        }
        let fixed: Vec<VertexId> = g.fixed.iter().map(|&k| g.ids[k]).collect();
        assert_eq!(fixed, naive.fixed, "{}: FIX", e.file);
    }
}

#[test]
fn g2o_toro_g2o_and_toro_g2o_toro_are_lossless() {
    for e in planar_files() {
        let (g, report) = read(&e.file);
        let (first, second) = match report.format {
            Format::G2o => (Format::Toro, Format::G2o),
            Format::Toro => (Format::G2o, Format::Toro),
        };
        let a = to_bytes(&g, first, first.default_dialect());
        let ga = from_bytes(&a, &format!("{}.{}", e.file, first.name()));
        assert_same_bits(&g, &ga, &format!("{} -> {}", e.file, first));
        let b = to_bytes(&ga, second, second.default_dialect());
        let gb = from_bytes(&b, &format!("{}.back", e.file));
        assert_same_bits(&g, &gb, &format!("{} -> {} -> {}", e.file, first, second));
        // And the written text is stable: writing the re-read graph gives the same bytes.
        assert_eq!(
            b,
            to_bytes(&gb, second, second.default_dialect()),
            "{}",
            e.file
        );
    }
}

#[test]
fn files_without_vertices_get_spanning_tree_poses_consistent_with_tree_edges() {
    for name in [
        "CSAIL.g2o",
        "manhattan.g2o",
        "kitti_00.g2o",
        "kitti_08.g2o",
        "w20000.txt",
    ] {
        let (g, _) = read(name);
        assert!(!g.vertices_declared);
        // The smallest id sits at the origin.
        assert_eq!(g.poses[0].values(), [0.0; 3], "{name}");
        // kitti_08 is an odometry chain: the tree is the chain, so every edge is matched
        // exactly (up to rounding) by the composed poses.
        if name == "kitti_08.g2o" {
            for e in &g.edges {
                let rel = g.poses[e.i]
                    .to_isometry()
                    .inv_mul(&g.poses[e.j].to_isometry());
                let z = e.measurement.to_isometry();
                let d = z.inv_mul(&rel);
                assert!(d.translation.vector.norm() < 1e-6, "{name}");
                assert!(d.rotation.angle().abs() < 1e-9, "{name}");
            }
        }
    }
}

#[test]
fn statistics_match_the_dataset_readme() {
    // (file, duplicate pairs, identical duplicates, backward edges) from README.md/MANIFEST.tsv.
    type Case = (&'static str, Option<usize>, Option<usize>, Option<usize>);
    let cases: &[Case] = &[
        ("CSAIL.g2o", Some(1), Some(1), None),
        ("kitti_00.g2o", Some(1), Some(1), Some(137)),
        ("kitti_02.g2o", None, None, Some(43)),
        ("kitti_06.g2o", Some(1), Some(1), Some(50)),
        ("kitti_07.g2o", None, None, Some(6)),
        ("kitti_09.g2o", None, None, Some(2)),
        ("INTEL_P_toro.graph", None, Some(22), None),
        ("intel_openslam_g2o.g2o", None, Some(2), None),
        ("manhattanOlson3500.g2o", Some(145), None, None),
        ("MIT.g2o", None, None, Some(20)),
        ("ring.g2o", None, None, Some(26)),
        ("w100.graph", None, None, Some(300)),
        ("noisyToyGraph.txt", None, None, Some(1)),
    ];
    for &(name, pairs, identical, backward) in cases {
        let (g, report) = read(name);
        let s = GraphStats::new(&g, &report);
        if let Some(p) = pairs {
            assert_eq!(s.duplicate_edges, p, "{name}: duplicate pairs");
        }
        if let Some(x) = identical {
            assert_eq!(s.exact_duplicate_edges, x, "{name}: identical duplicates");
        }
        if let Some(b) = backward {
            assert_eq!(s.backward_edges, b, "{name}: backward edges");
        }
    }
    // "Every graph is connected", and every id range starts at 0 without gaps.
    for e in planar_files() {
        let (g, report) = read(&e.file);
        let s = GraphStats::new(&g, &report);
        assert_eq!(s.components, 1, "{}", e.file);
        assert_eq!((s.id_min, s.id_gaps), (Some(0), 0), "{}", e.file);
        assert_eq!(s.odometry_edges + s.loop_closures, s.edges, "{}", e.file);
    }
    // kitti_08 is only the odometry chain.
    let (g, report) = read("kitti_08.g2o");
    let s = GraphStats::new(&g, &report);
    assert_eq!((s.odometry_edges, s.loop_closures), (4070, 0));
    // ais2klinik's odometry chain has one gap, 7289 -> 7290 (MANIFEST.tsv).
    let (g, report) = read("ais2klinik.g2o");
    let s = GraphStats::new(&g, &report);
    assert!(
        !g.edges
            .iter()
            .any(|e| g.ids[e.i] == 7289 && g.ids[e.j] == 7290)
    );
    assert_eq!(s.poses, 15115);
    // The FIX line of the dpgo copy.
    let (g, _) = read("ais2klinik_dpgo_fix.g2o");
    assert_eq!(g.fixed, vec![0]);
}

#[test]
fn frh_g2o_and_toro_versions_carry_the_same_information() {
    // README.md: "FRH.g2o does match FRH_P_toro.graph" (I13 is the subnormal 6.95335e-310 in the
    // g2o file, 0 in the TORO file). This holds the TORO order mapping against real data.
    let (g, _) = read("FRH.g2o");
    let (t, _) = read("FRH_P_toro.graph");
    assert_eq!(g.edges.len(), t.edges.len());
    for (a, b) in g.edges.iter().zip(&t.edges) {
        assert_eq!((a.i, a.j), (b.i, b.j));
        assert_eq!(a.noise.0[2], 6.95335e-310);
        assert_eq!(b.noise.0[2], 0.0);
        for k in [0, 1, 3, 4, 5] {
            let (x, y) = (a.noise.0[k], b.noise.0[k]);
            // The g2o copy was written with 6 significant digits: half a unit in the 6th digit
            // is at most 5e-6 relative.
            assert!((x - y).abs() <= 5e-6 * y.abs() + 1e-12, "{x} vs {y}");
        }
    }
}

#[test]
fn three_d_and_landmark_files_get_specific_errors() {
    for (name, needle, line) in [
        (
            "tinyGrid3D.g2o",
            "this tool handles planar SE(2) graphs only",
            1,
        ),
        (
            "smallGrid3D.g2o",
            "this tool handles planar SE(2) graphs only",
            1,
        ),
        (
            "example.graph",
            "this landmark type is not supported (tag BR)",
            190,
        ),
    ] {
        let path = datasets_dir().join(name);
        let err = io::read_path(path.to_str().unwrap(), &ReadOptions::default()).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains(needle), "{name}: {msg}");
        let expect = format!("{}:{line}:1: ", path.display());
        assert!(msg.starts_with(&expect), "{name}: {msg}");
    }
}

#[test]
fn w20000_in_toro_order_is_refused_with_a_hint() {
    let path = datasets_dir().join("w20000.txt");
    let options = ReadOptions {
        dialect: Some(Dialect::ToroInfo),
        ..Default::default()
    };
    let msg = io::read_path(path.to_str().unwrap(), &options)
        .unwrap_err()
        .to_string();
    assert!(msg.contains(":1:"), "{msg}");
    assert!(msg.contains("not positive definite"), "{msg}");
    assert!(msg.contains("try --dialect g2o"), "{msg}");
}
