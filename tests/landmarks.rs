//! Planar pose-landmark graphs (issue 13): g2o's `VERTEX_XY`/`EDGE_SE2_XY` and CPL-SLAM's
//! `LANDMARK2` files, read, written, converted between the two forms and counted. Each check
//! holds the library against something independent of it: a naive split-on-whitespace reading of
//! the same file, the manifest of the data sets, or a round trip.

mod common;

use common::{Dir, bits, datasets_dir, run_with_stdin, s, text};
use pgo::graph::{LandmarkForm, PoseGraph};
use pgo::io::{self, Format, ReadOptions, WriteOptions};
use std::collections::{BTreeMap, BTreeSet};

fn read(path: &std::path::Path) -> PoseGraph {
    io::read_path(s(path), &ReadOptions::default()).unwrap().0
}

fn read_bytes(bytes: &[u8]) -> PoseGraph {
    io::read(bytes, "in.g2o", &ReadOptions::default())
        .unwrap()
        .0
}

fn write(g: &PoseGraph) -> Vec<u8> {
    let mut out = Vec::new();
    let options = WriteOptions {
        format: Format::G2o,
        dialect: io::Dialect::G2o,
    };
    io::write(g, options, &mut out).unwrap();
    out
}

/// The landmark lines of a file, read naively: (tag, pose id, landmark id, dx dy I11 I12 I22).
fn naive_observations(path: &std::path::Path) -> Vec<(String, u32, u32, [f64; 5])> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .filter_map(|l| {
            let t: Vec<&str> = l.split_whitespace().collect();
            matches!(t.first(), Some(&"LANDMARK2" | &"EDGE_SE2_XY")).then(|| {
                let mut v = [0.0; 5];
                for k in 0..5 {
                    v[k] = t[3 + k].parse().unwrap();
                }
                (
                    t[0].to_string(),
                    t[1].parse().unwrap(),
                    t[2].parse().unwrap(),
                    v,
                )
            })
        })
        .collect()
}

/// Both CPL-SLAM files load as intended: landmark ids in their own id space (cityTrees10000's
/// landmarks 0..99 are not poses 0..99), every observation with its values bit for bit, counts
/// as the manifest and a naive reading of the file give them.
#[test]
fn cpl_slam_files_load_with_landmarks_in_their_own_id_space() {
    for (name, poses, landmarks) in [
        ("victoriaPark.g2o", 6969, 151),
        ("cityTrees10000.g2o", 10000, 100),
    ] {
        let path = datasets_dir().join(name);
        let g = read(&path);
        let naive = naive_observations(&path);
        assert_eq!(g.num_poses(), poses, "{name}");
        assert_eq!(g.landmarks.len(), landmarks, "{name}");
        assert_eq!(g.landmarks.form, LandmarkForm::Landmark2, "{name}");
        assert_eq!(g.landmarks.observations.len(), naive.len(), "{name}");
        let ids: BTreeSet<u32> = naive.iter().map(|o| o.2).collect();
        assert_eq!(
            g.landmarks.ids,
            ids.iter().copied().collect::<Vec<_>>(),
            "{name}"
        );
        for (o, (tag, pose, mark, v)) in g.landmarks.observations.iter().zip(&naive) {
            assert_eq!(tag, "LANDMARK2");
            assert_eq!(g.ids[o.pose], *pose);
            assert_eq!(g.landmarks.ids[o.landmark], *mark);
            assert_eq!(
                bits(&[
                    o.d[0],
                    o.d[1],
                    o.information.0[0],
                    o.information.0[1],
                    o.information.0[2]
                ]),
                bits(v)
            );
        }
        // Landmarks seen once, counted from the naive reading.
        let mut count: BTreeMap<u32, usize> = BTreeMap::new();
        for o in &naive {
            *count.entry(o.2).or_default() += 1;
        }
        let once = count.values().filter(|&&c| c == 1).count();
        let seen = g.landmarks.observation_counts();
        assert_eq!(seen.iter().filter(|&&c| c == 1).count(), once, "{name}");
        // Connected: the odometry chain joins every pose.
        assert_eq!(g.connected_components().1, 1, "{name}");
    }
    // cityTrees10000: landmark ids collide with pose ids, and both are there.
    let g = read(&datasets_dir().join("cityTrees10000.g2o"));
    assert_eq!(g.landmarks.ids, (0..100).collect::<Vec<u32>>());
    assert_eq!(&g.ids[..100], &(0..100).collect::<Vec<u32>>()[..]);
    // victoriaPark: landmark ids interleave with the pose ids (one numbering, disjoint).
    let g = read(&datasets_dir().join("victoriaPark.g2o"));
    assert!(g.landmarks.ids.iter().all(|&id| g.index_of(id).is_none()));
    assert_eq!(g.ids.len() + g.landmarks.len(), 7120);
    assert_eq!(*g.ids.last().unwrap(), 7119);
}

/// Landmark positions of a file without vertex lines: the pose that reaches a landmark first in
/// the spanning tree places it, l = p + R(θ) d (here by hand: pose 1 at (1, 0) facing +y sees
/// (2, 0) ahead, at (1, 2); pose 0 at the origin sees (5, 5) at (5, 5)).
#[test]
fn landmark_positions_from_the_first_observation() {
    let g = read_bytes(
        b"EDGE_SE2 0 1 1 0 1.5707963267948966 1 0 0 1 0 1\n\
          LANDMARK2 1 0 2 0 1 0 1\n\
          LANDMARK2 0 1 5 5 1 0 1\n",
    );
    let [x, y] = g.landmarks.positions[0];
    assert!(
        (x - 1.0).abs() < 1e-15 && (y - 2.0).abs() < 1e-15,
        "{x} {y}"
    );
    assert_eq!(g.landmarks.positions[1], [5.0, 5.0]);
    assert!(!g.landmarks.declared);
}

/// A graph connected only through a landmark: two poses without an edge between them, both
/// observing landmark 7, are one component; a landmark declared but never observed is in none.
#[test]
fn components_are_counted_through_landmarks() {
    let g = read_bytes(
        b"VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 3 0 0\nVERTEX_SE2 2 9 9 0\n\
          VERTEX_XY 7 1 1\nVERTEX_XY 8 5 5\n\
          EDGE_SE2_XY 0 7 1 1 1 0 1\nEDGE_SE2_XY 1 7 -2 1 1 0 1\n",
    );
    let (label, count) = g.connected_components();
    assert_eq!((label, count), (vec![0, 0, 1], 2));
    assert_eq!(g.landmark_components(), vec![Some(0), None]);
    let parts = g.components();
    assert_eq!(parts[0].0.landmarks.ids, vec![7]);
    assert_eq!(parts[0].0.landmarks.observations.len(), 2);
    assert!(parts[1].0.landmarks.is_empty());
}

/// g2o's form round-trips bit for bit (read, write, read: the same graph), and so does
/// CPL-SLAM's (positions on POINT2 lines).
#[test]
fn both_forms_round_trip_losslessly() {
    let g2o = b"VERTEX_SE2 0 0 0 0\nVERTEX_SE2 2 1.25 -0.5 0.3\nVERTEX_XY 1 0.1 1e-7\n\
        EDGE_SE2 0 2 1.25 -0.5 0.3 1 0 0 1 0 1\nEDGE_SE2_XY 0 1 0.1 1e-7 3 0.5 2\n\
        EDGE_SE2_XY 2 1 -1.15 0.5000001 1 0 1\n";
    let g = read_bytes(g2o);
    assert_eq!(g.landmarks.form, LandmarkForm::G2o);
    assert!(g.landmarks.declared);
    let out = write(&g);
    assert_eq!(read_bytes(&out), g);
    assert_eq!(write(&read_bytes(&out)), out);
    for name in ["victoriaPark.g2o", "cityTrees10000.g2o"] {
        let g = read(&datasets_dir().join(name));
        let out = write(&g);
        let text = String::from_utf8_lossy(&out);
        assert!(text.contains("\nPOINT2 ") && text.contains("\nLANDMARK2 "));
        let back = read_bytes(&out);
        assert_eq!(back.poses, g.poses, "{name}");
        assert_eq!(back.edges, g.edges, "{name}");
        assert_eq!(back.landmarks.ids, g.landmarks.ids, "{name}");
        assert_eq!(back.landmarks.positions, g.landmarks.positions, "{name}");
        assert_eq!(
            back.landmarks.observations, g.landmarks.observations,
            "{name}"
        );
        assert_eq!(write(&back), out, "{name}");
    }
}

/// pgo-convert between the forms: LANDMARK2 -> g2o shifts landmark ids past the poses when they
/// collide (cityTrees10000: by 10000) and keeps them when they do not (victoriaPark: by 0), says
/// so, and the reported offset converts back to the same file bit for bit.
#[test]
fn convert_between_forms_and_back() {
    for (name, offset) in [("cityTrees10000.g2o", 10000), ("victoriaPark.g2o", 0)] {
        let dir = Dir::new();
        let input = datasets_dir().join(name);
        let original = dir.path("original.g2o");
        let g2o = dir.path("g2o.g2o");
        let back = dir.path("back.g2o");
        let run = |args: &[&str]| {
            let out = run_with_stdin("pgo-convert", args, None);
            assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
            text(&out.stderr)
        };
        run(&[s(&input), "-o", s(&original), "-q"]);
        let said = run(&[s(&input), "--landmarks", "g2o", "-o", s(&g2o)]);
        assert!(
            said.contains(&format!("landmark ids shifted by +{offset}")),
            "{said}"
        );
        let g = read(&g2o);
        let first = read(&input);
        assert_eq!(g.landmarks.form, LandmarkForm::G2o);
        let shifted: Vec<u32> = first.landmarks.ids.iter().map(|k| k + offset).collect();
        assert_eq!(g.landmarks.ids, shifted);
        assert!(g.landmarks.ids.iter().all(|&id| g.index_of(id).is_none()));
        let naive = naive_observations(&g2o);
        assert!(naive.iter().all(|o| o.0 == "EDGE_SE2_XY"));
        let off = offset.to_string();
        run(&[
            s(&g2o),
            "--landmarks",
            "landmark2",
            "--landmark-offset",
            &off,
            "-o",
            s(&back),
            "-q",
        ]);
        assert_eq!(
            std::fs::read(&back).unwrap(),
            std::fs::read(&original).unwrap(),
            "{name}"
        );
    }
}

/// TORO has no landmark type: writing one is a clear error, exit status 2, nothing written.
#[test]
fn toro_output_of_a_landmark_graph_is_an_error() {
    let dir = Dir::new();
    let out_path = dir.path("out.graph");
    let input = datasets_dir().join("cityTrees10000.g2o");
    let out = run_with_stdin("pgo-convert", &[s(&input), "-o", s(&out_path)], None);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("TORO has no landmark type"),
        "{}",
        text(&out.stderr)
    );
    assert!(!out_path.exists());
}

/// `--stats` counts landmarks, observations, landmarks seen once and by no pose (here by hand).
#[test]
fn stats_count_landmarks() {
    let graph = b"VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_XY 5 1 1\nVERTEX_XY 6 2 2\n\
        VERTEX_XY 9 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2_XY 0 5 1 1 1 0 1\n\
        EDGE_SE2_XY 1 5 0 1 1 0 1\nEDGE_SE2_XY 1 6 1 2 1 0 1\n";
    let out = run_with_stdin("pgo-convert", &["-", "--stats", "--json"], Some(graph));
    let json = text(&out.stdout);
    for field in [
        "\"landmarks\":3",
        "\"landmark_form\":\"g2o\"",
        "\"observations\":3",
        "\"landmarks_seen_once\":1",
        "\"landmarks_unseen\":1",
    ] {
        assert!(json.contains(field), "{field} in {json}");
    }
}
