//! The 3D pose graph as read from a file (issue 15, first landing: the file layer only): poses
//! in SE(3), relative-pose measurements with 6x6 information matrices, FIX ids, every value kept
//! with its bits, beside the planar [`crate::PoseGraph`] rather than inside it.
//!
//! Two file forms (docs/formats.md §2.6, §3.4, §10):
//! - g2o: `VERTEX_SE3:QUAT id x y z qx qy qz qw`, `EDGE_SE3:QUAT i j x y z qx qy qz qw` + 21
//!   information values, the upper triangle row by row of a 6x6 over (x, y, z, qx, qy, qz);
//! - TORO: `VERTEX3 id x y z roll pitch yaw`, `EDGE3 i j x y z roll pitch yaw` + 21 information
//!   values, the upper triangle row by row of a 6x6 over (x, y, z, roll, pitch, yaw).
//!
//! The two forms parametrize rotations, and hence the rotation block of the information, in
//! different coordinates (a quaternion's vector part, about half the rotation angle, against
//! Euler angles); a graph keeps the form it was read in ([`Rotation3`]) and is written back in
//! it bit for bit. Converting between them is not lossless (neither the angles nor the
//! information carry over exactly) and is refused by the writer.
//!
//! Conventions: an edge `(i, j, z)` measures the pose of `j` in the frame of `i`,
//! z ≈ x_i⁻¹ · x_j, as in 2D. Quaternions are Hamilton, written `qx qy qz qw` (w last); the
//! rotation a quaternion stands for is q / |q| (g2o normalizes the measurement quaternion when
//! it reads an edge, docs/formats.md §2.6), so q and −q are the same rotation; both are kept as
//! written. TORO's Euler angles compose as R = Rz(yaw) · Ry(pitch) · Rx(roll) (TORO's
//! `transformation3.hxx`, docs/formats.md §10).

use crate::graph::{SymMat3, VertexId};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

/// The rotation of a 3D pose, as written in the file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rotation3 {
    /// g2o: a quaternion `[qx, qy, qz, qw]` (Hamilton, w last), not necessarily of unit norm
    /// (never zero: the reader refuses a zero quaternion).
    Quaternion([f64; 4]),
    /// TORO: Euler angles `[roll, pitch, yaw]` in radians, R = Rz(yaw) · Ry(pitch) · Rx(roll),
    /// not normalized.
    Euler([f64; 3]),
}

impl Rotation3 {
    pub const IDENTITY_QUATERNION: Rotation3 = Rotation3::Quaternion([0.0, 0.0, 0.0, 1.0]);

    /// The rotation (a quaternion normalized, as g2o does).
    pub fn unit_quaternion(self) -> UnitQuaternion<f64> {
        match self {
            Rotation3::Quaternion([x, y, z, w]) => {
                UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z))
            }
            Rotation3::Euler([roll, pitch, yaw]) => {
                UnitQuaternion::from_euler_angles(roll, pitch, yaw)
            }
        }
    }

    /// The values as written: 4 for a quaternion, 3 for Euler angles.
    pub fn values(&self) -> &[f64] {
        match self {
            Rotation3::Quaternion(q) => q,
            Rotation3::Euler(e) => e,
        }
    }
}

/// A 3D pose (translation and rotation) exactly as read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose3 {
    /// `[x, y, z]`.
    pub translation: [f64; 3],
    pub rotation: Rotation3,
}

impl Pose3 {
    pub const IDENTITY: Pose3 = Pose3 {
        translation: [0.0; 3],
        rotation: Rotation3::IDENTITY_QUATERNION,
    };

    /// The rigid motion this pose stands for.
    pub fn to_isometry(self) -> Isometry3<f64> {
        let [x, y, z] = self.translation;
        Isometry3::from_parts(Translation3::new(x, y, z), self.rotation.unit_quaternion())
    }

    /// Every value in file order: x y z, then qx qy qz qw or roll pitch yaw.
    pub fn values(&self) -> impl Iterator<Item = f64> + '_ {
        self.translation
            .iter()
            .chain(self.rotation.values())
            .copied()
    }
}

/// A symmetric 6x6 information matrix, stored as its upper triangle row by row
/// (`m00 m01 .. m05 m11 .. m55`, 21 values), the order of both `EDGE_SE3:QUAT` and `EDGE3`
/// lines. Its coordinates are the file form's: (x, y, z, qx, qy, qz) for g2o, (x, y, z, roll,
/// pitch, yaw) for TORO (docs/formats.md §2.6, §3.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymMat6(pub [f64; 21]);

impl SymMat6 {
    /// The 6x6 identity (ones at the upper triangle's diagonal positions 0, 6, 11, 15, 18, 20).
    pub const IDENTITY: SymMat6 = SymMat6([
        1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0,
        1.0, 0.0, 1.0,
    ]);

    /// Entry (r, c) of the symmetric matrix.
    pub fn get(&self, r: usize, c: usize) -> f64 {
        let (r, c) = if r <= c { (r, c) } else { (c, r) };
        self.0[upper_index(r, c)]
    }

    /// The 3x3 diagonal block starting at row `at` (0: translation, 3: rotation), as a
    /// [`SymMat3`] (upper triangle, g2o order).
    pub fn block(&self, at: usize) -> SymMat3 {
        let g = |r: usize, c: usize| self.get(at + r, at + c);
        SymMat3([g(0, 0), g(0, 1), g(0, 2), g(1, 1), g(1, 2), g(2, 2)])
    }

    /// Positive definiteness by Cholesky factorization M = L Lᵀ; `Err(k)` names the first
    /// (0-based) pivot that is not positive (or not finite).
    pub fn check_positive_definite(&self) -> Result<(), usize> {
        let mut l = [[0.0f64; 6]; 6];
        for j in 0..6 {
            let d = self.get(j, j) - dot(&l[j][..j], &l[j][..j]);
            if d.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || !d.is_finite() {
                return Err(j);
            }
            let djj = d.sqrt();
            l[j][j] = djj;
            for i in j + 1..6 {
                l[i][j] = (self.get(i, j) - dot(&l[i][..j], &l[j][..j])) / djj;
            }
        }
        Ok(())
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Position of entry (r, c), r <= c < 6, in an upper triangle stored row by row: rows before r
/// hold 6 + 5 + ... + (6 − r + 1) values.
fn upper_index(r: usize, c: usize) -> usize {
    debug_assert!(r <= c && c < 6);
    6 * r - r * r.saturating_sub(1) / 2 + (c - r)
}

/// A relative-pose measurement between two 3D poses (dense indices into [`Graph3::ids`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge3 {
    pub i: usize,
    pub j: usize,
    /// z: the pose of `j` in the frame of `i`, in the graph's rotation form.
    pub measurement: Pose3,
    /// Information matrix over the measurement's coordinates (see [`SymMat6`]).
    pub information: SymMat6,
}

/// Which 3D file form a graph was read in, and so which it is written in (its rotations and
/// the coordinates of its information matrices).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Form3 {
    /// `VERTEX_SE3:QUAT`, `EDGE_SE3:QUAT`: quaternions.
    G2o,
    /// `VERTEX3`, `EDGE3`: Euler angles.
    Toro,
}

/// A 3D pose graph. Poses are indexed densely `0..n` in ascending id order (`ids[k]` is the
/// file's id of pose `k`); edges keep the input order, duplicates and direction. Every edge
/// joins declared vertices (3D files carry their vertex lines; like GTSAM's `load3D`, pgo does
/// not invent missing ones, docs/formats.md §5.9).
#[derive(Debug, Clone, PartialEq)]
pub struct Graph3 {
    /// File ids, strictly ascending.
    pub ids: Vec<VertexId>,
    /// The vertex lines as read (rotations in the graph's form).
    pub poses: Vec<Pose3>,
    pub edges: Vec<Edge3>,
    /// Dense indices of fixed poses, in the order of the FIX lines, without repeats.
    pub fixed: Vec<usize>,
    pub form: Form3,
}

impl Graph3 {
    pub fn num_poses(&self) -> usize {
        self.ids.len()
    }

    /// Dense index of a file id.
    pub fn index_of(&self, id: VertexId) -> Option<usize> {
        self.ids.binary_search(&id).ok()
    }

    /// Renumbers the ids densely as `0..n` in ascending order of the old ids.
    pub fn reindex(&mut self) {
        for (k, id) in self.ids.iter_mut().enumerate() {
            *id = k as VertexId;
        }
    }

    /// Connected components: a label per pose (in order of first pose) and their count.
    pub fn connected_components(&self) -> (Vec<usize>, usize) {
        let n = self.num_poses();
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(parent: &mut [usize], mut u: usize) -> usize {
            while parent[u] != u {
                parent[u] = parent[parent[u]];
                u = parent[u];
            }
            u
        }
        for e in &self.edges {
            let (a, b) = (find(&mut parent, e.i), find(&mut parent, e.j));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
        let mut label = vec![usize::MAX; n];
        let mut count = 0;
        for u in 0..n {
            let r = find(&mut parent, u);
            if label[r] == usize::MAX {
                label[r] = count;
                count += 1;
            }
            label[u] = label[r];
        }
        (label, count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upper_triangle_positions_row_by_row() {
        // Row 0: 0..=5, row 1: 6..=10, row 2: 11..=14, row 3: 15..=17, row 4: 18..=19, row 5: 20.
        let mut k = 0;
        for r in 0..6 {
            for c in r..6 {
                assert_eq!(upper_index(r, c), k, "({r}, {c})");
                k += 1;
            }
        }
        assert_eq!(k, 21);
    }

    #[test]
    fn the_identity_is_one_on_the_diagonal_only() {
        for r in 0..6 {
            for c in 0..6 {
                assert_eq!(
                    SymMat6::IDENTITY.get(r, c),
                    f64::from(u8::from(r == c)),
                    "({r}, {c})"
                );
            }
        }
    }

    #[test]
    fn positive_definiteness_of_6x6() {
        let mut diag = [0.0; 21];
        for (r, v) in [100.0, 100.0, 100.0, 25.0, 25.0, 25.0]
            .into_iter()
            .enumerate()
        {
            diag[upper_index(r, r)] = v;
        }
        assert_eq!(SymMat6(diag).check_positive_definite(), Ok(()));
        let mut zero_last = diag;
        zero_last[20] = 0.0;
        assert_eq!(SymMat6(zero_last).check_positive_definite(), Err(5));
        // [[1, 2], [2, 1]] in the (x, y) block: det < 0, the second pivot is 1 − 4 < 0.
        let mut indefinite = diag;
        indefinite[0] = 1.0;
        indefinite[6] = 1.0;
        indefinite[1] = 2.0;
        assert_eq!(SymMat6(indefinite).check_positive_definite(), Err(1));
    }

    #[test]
    fn euler_angles_compose_as_toro_does() {
        // roll = π/2 alone turns y into z: Rx(π/2) (0, 1, 0) = (0, 0, 1).
        let half = std::f64::consts::FRAC_PI_2;
        let r = Rotation3::Euler([half, 0.0, 0.0]).unit_quaternion();
        let v = r * nalgebra::Vector3::new(0.0, 1.0, 0.0);
        assert!((v - nalgebra::Vector3::new(0.0, 0.0, 1.0)).norm() < 1e-15);
        // Rz(yaw) · Ry(pitch): pitch π/2 takes x to −z, then yaw π/2 leaves −z alone; x after
        // yaw alone goes to y. So (1, 0, 0) -> Ry: (0, 0, −1) -> Rz: (0, 0, −1).
        let r = Rotation3::Euler([0.0, half, half]).unit_quaternion();
        let v = r * nalgebra::Vector3::new(1.0, 0.0, 0.0);
        assert!((v - nalgebra::Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-15);
        // (0, 0, 1) -> Ry(π/2): (1, 0, 0) -> Rz(π/2): (0, 1, 0).
        let v = r * nalgebra::Vector3::new(0.0, 0.0, 1.0);
        assert!((v - nalgebra::Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-15);
    }

    #[test]
    fn quaternions_are_normalized_on_use_and_sign_free() {
        // (0, 0, 2, 0) and (0, 0, −1, 0): both a half turn about z.
        let a = Rotation3::Quaternion([0.0, 0.0, 2.0, 0.0]).unit_quaternion();
        let b = Rotation3::Quaternion([0.0, 0.0, -1.0, 0.0]).unit_quaternion();
        let x = nalgebra::Vector3::new(1.0, 0.0, 0.0);
        assert!((a * x - nalgebra::Vector3::new(-1.0, 0.0, 0.0)).norm() < 1e-15);
        assert!((b * x - a * x).norm() < 1e-15);
    }
}
