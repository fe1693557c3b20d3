//! Trajectory files for evo and other trajectory-evaluation tools: the poses only, sorted by id.
//!
//! - TUM (the TUM RGB-D benchmark's format, evo's `tum`): one line `t x y z qx qy qz qw` per
//!   pose, t the vertex id (or a time stamp given for it), z = 0 and the heading θ as the unit
//!   quaternion of the rotation about z, (0, 0, sin θ/2, cos θ/2).
//! - KITTI (the KITTI odometry benchmark's poses, evo's `kitti`): one line per pose, the 3×4
//!   matrix [R | t] row by row, R the rotation about z by θ and t = (x, y, 0). KITTI files have no
//!   time stamps: line k is the k-th pose in ascending id order.
//!
//! 3D graphs ([`write_trajectory3`]) write their translations and rotations as they are (a TUM
//! line's z and quaternion, KITTI's full [R | t]).
//!
//! Numbers are written as the graph writers write them (shortest round-trip decimals), so x, y
//! and the quaternion's or matrix's entries read back bit for bit; θ itself is recovered only up
//! to rounding (atan2 of the entries).

use super::writer::format_f64;
use crate::Error;
use crate::graph::PoseGraph;
use crate::graph3::Graph3;
use std::io::Write;

/// A trajectory format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrajectoryFormat {
    Tum,
    Kitti,
}

impl TrajectoryFormat {
    pub fn name(self) -> &'static str {
        match self {
            TrajectoryFormat::Tum => "tum",
            TrajectoryFormat::Kitti => "kitti",
        }
    }
}

/// Writes the poses of `graph` in ascending id order. `stamps`, for TUM only, maps a vertex id
/// to its time stamp (every pose must have one); without it the id is the time stamp.
pub fn write_trajectory(
    graph: &PoseGraph,
    format: TrajectoryFormat,
    stamps: Option<&std::collections::HashMap<u32, f64>>,
    out: &mut dyn Write,
    name: &str,
) -> crate::Result<()> {
    let mut order: Vec<usize> = (0..graph.num_poses()).collect();
    order.sort_by_key(|&k| graph.ids[k]);
    let poses = order.into_iter().map(|k| {
        let p = graph.poses[k];
        let (s, c) = p.theta.sin_cos();
        let (sh, ch) = (0.5 * p.theta).sin_cos();
        (
            graph.ids[k],
            [p.x, p.y, 0.0],
            [0.0, 0.0, sh, ch],
            // −sin θ + 0: no "-0" where θ = 0.
            [[c, -s + 0.0, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
        )
    });
    write_poses(poses, format, stamps, out, name)
}

/// [`write_trajectory`] for a 3D graph: the translations as read, the rotations as unit
/// quaternions (a g2o quaternion normalized, as g2o and pgo read it; TORO's Euler angles
/// R = Rz(yaw)·Ry(pitch)·Rx(roll) turned into one) and, for KITTI, their rotation matrices.
pub fn write_trajectory3(
    graph: &Graph3,
    format: TrajectoryFormat,
    stamps: Option<&std::collections::HashMap<u32, f64>>,
    out: &mut dyn Write,
    name: &str,
) -> crate::Result<()> {
    // A Graph3's ids are ascending already.
    let poses = graph.ids.iter().zip(&graph.poses).map(|(&id, p)| {
        let q = p.rotation.unit_quaternion();
        let r = q.to_rotation_matrix();
        let c = q.coords;
        (
            id,
            p.translation,
            [c.x, c.y, c.z, c.w],
            // + 0: no "-0" in the matrix.
            std::array::from_fn(|a| std::array::from_fn(|b| r[(a, b)] + 0.0)),
        )
    });
    write_poses(poses, format, stamps, out, name)
}

/// The lines of a trajectory: per pose in the order given, its id, translation, unit quaternion
/// [qx, qy, qz, qw] (TUM) and rotation matrix (KITTI).
fn write_poses(
    poses: impl Iterator<Item = (u32, [f64; 3], [f64; 4], [[f64; 3]; 3])> + Clone,
    format: TrajectoryFormat,
    stamps: Option<&std::collections::HashMap<u32, f64>>,
    out: &mut dyn Write,
    name: &str,
) -> crate::Result<()> {
    // Every stamp is there before the first line is written.
    if let (Some(map), TrajectoryFormat::Tum) = (stamps, format)
        && let Some((id, ..)) = poses.clone().find(|(id, ..)| !map.contains_key(id))
    {
        return Err(Error::Invalid(format!(
            "no time stamp for vertex {id} (every pose needs one)"
        )));
    }
    let mut line = Vec::with_capacity(256);
    let io = |e| Error::io(name, e);
    for (id, t, q, r) in poses {
        line.clear();
        let put = |v: f64, line: &mut Vec<u8>| {
            if !line.is_empty() {
                line.push(b' ');
            }
            format_f64(v, line);
        };
        match format {
            TrajectoryFormat::Tum => {
                match stamps {
                    Some(map) => put(map[&id], &mut line),
                    None => line.extend_from_slice(id.to_string().as_bytes()),
                }
                for v in t.into_iter().chain(q) {
                    put(v, &mut line);
                }
            }
            TrajectoryFormat::Kitti => {
                for a in 0..3 {
                    for v in r[a].into_iter().chain([t[a]]) {
                        put(v, &mut line);
                    }
                }
            }
        }
        line.push(b'\n');
        out.write_all(&line).map_err(io)?;
    }
    out.flush().map_err(io)
}

/// Reads a time-stamp file for [`write_trajectory`]: one `id stamp` pair per line (blank lines
/// and `#` comments skipped). Errors name `PATH:LINE`.
pub fn read_stamps(path: &str) -> crate::Result<std::collections::HashMap<u32, f64>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut map = std::collections::HashMap::new();
    for (k, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let bad = |what: &str| Error::Invalid(format!("{path}:{}: {what}", k + 1));
        let mut fields = line.split_whitespace();
        let (Some(id), Some(t), None) = (fields.next(), fields.next(), fields.next()) else {
            return Err(bad("expected two fields, `id stamp`"));
        };
        let id: u32 = id
            .parse()
            .map_err(|_| bad(&format!("'{id}' is not a vertex id")))?;
        let t: f64 = t
            .parse()
            .ok()
            .filter(|t: &f64| t.is_finite())
            .ok_or_else(|| bad(&format!("'{t}' is not a finite time stamp")))?;
        if map.insert(id, t).is_some() {
            return Err(bad(&format!("vertex {id} has a second time stamp")));
        }
    }
    Ok(map)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Pose2, PoseGraph};

    fn graph() -> PoseGraph {
        let mut g = PoseGraph::with_edges(
            vec![
                Pose2::new(1.5, -2.0, std::f64::consts::FRAC_PI_2),
                Pose2::new(0.0, 0.0, 0.0),
            ],
            Vec::new(),
        );
        g.ids = vec![7, 3];
        g
    }

    fn text(
        format: TrajectoryFormat,
        stamps: Option<&std::collections::HashMap<u32, f64>>,
    ) -> String {
        let mut out = Vec::new();
        write_trajectory(&graph(), format, stamps, &mut out, "test").unwrap();
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn tum_lines_by_hand() {
        // Sorted by id: vertex 3 first. A quarter turn is the quaternion (0, 0, √½, √½).
        let t = text(TrajectoryFormat::Tum, None);
        let lines: Vec<Vec<f64>> = t
            .lines()
            .map(|l| l.split(' ').map(|v| v.parse().unwrap()).collect())
            .collect();
        assert_eq!(lines[0], [3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let expected = [7.0, 1.5, -2.0, 0.0, 0.0, 0.0, h, h];
        for (a, b) in lines[1].iter().zip(expected) {
            assert!((a - b).abs() <= 1.2e-16, "{t}");
        }
        assert!(
            t.starts_with("3 ") && t.contains("\n7 1.5 -2 0 0 0 "),
            "{t}"
        );
        let stamps = std::collections::HashMap::from([(3, 0.5), (7, 12.25)]);
        let t = text(TrajectoryFormat::Tum, Some(&stamps));
        assert!(
            t.starts_with("0.5 0 0 ") && t.contains("\n12.25 1.5 -2 "),
            "{t}"
        );
    }

    #[test]
    fn kitti_lines_by_hand() {
        // R(90°) = [[0, -1], [1, 0]] up to cos(π/2) = 6.1e-17.
        let t = text(TrajectoryFormat::Kitti, None);
        let lines: Vec<Vec<f64>> = t
            .lines()
            .map(|l| l.split(' ').map(|v| v.parse().unwrap()).collect())
            .collect();
        assert_eq!(
            lines[0],
            [1.0, -0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        );
        let expected = [0.0, -1.0, 0.0, 1.5, 1.0, 0.0, 0.0, -2.0, 0.0, 0.0, 1.0, 0.0];
        for (a, b) in lines[1].iter().zip(expected) {
            assert!((a - b).abs() < 1e-16, "{:?}", lines[1]);
        }
    }

    #[test]
    fn a_missing_stamp_is_an_error() {
        let stamps = std::collections::HashMap::from([(3, 0.5)]);
        let mut out = Vec::new();
        let e = write_trajectory(
            &graph(),
            TrajectoryFormat::Tum,
            Some(&stamps),
            &mut out,
            "x",
        );
        assert!(
            e.unwrap_err()
                .to_string()
                .contains("no time stamp for vertex 7")
        );
    }
}
