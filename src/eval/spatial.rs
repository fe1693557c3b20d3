//! The trajectory error of 3D graphs, as evo computes it: poses (rigid motions, the g2o
//! quaternions normalized) matched by vertex id, the estimate aligned to the reference by the
//! rotation and translation that minimize the squared position error (Umeyama, IEEE TPAMI 1991,
//! without scale: evo's `align(correct_scale=False)`), then the absolute and relative pose errors
//! with the definitions of the planar modules ([`super::ape`], [`super::rpe`]) in SE(3): the
//! distance between positions and the angle of the rotation error Q⁻¹P (the norm of its
//! logarithm, evo's `rotation_angle_deg`).

use super::ape::AbsoluteError;
use super::rpe::RelativeError;
use super::{Matched, Statistics, match_ids};
use crate::graph3::Graph3;
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::Serialize;

/// A pose of a 3D graph as the rigid motion it stands for.
pub type Pose = Isometry3<f64>;

/// Pairs the poses of two 3D graphs by vertex id.
pub fn match_by_id3(estimate: &Graph3, reference: &Graph3) -> Matched<Pose> {
    let poses = |g: &Graph3| -> Vec<Pose> { g.poses.iter().map(|p| p.to_isometry()).collect() };
    match_ids(
        &estimate.ids,
        &poses(estimate),
        &reference.ids,
        &poses(reference),
    )
}

/// The rigid motion x ↦ R x + t applied to the estimate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Alignment3 {
    /// R, row by row.
    pub rotation: [[f64; 3]; 3],
    pub translation: [f64; 3],
}

impl Alignment3 {
    pub const IDENTITY: Alignment3 = Alignment3 {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0; 3],
    };

    /// Umeyama's least-squares rotation and translation of the estimate's positions a_k onto
    /// the reference's b_k: with the centroids ā, b̄ and the SVD U D Vᵀ of
    /// Σ_k (b_k − b̄)(a_k − ā)ᵀ, R = U S Vᵀ where S = diag(1, 1, det(U)·det(V)) keeps R a
    /// rotation, and t = b̄ − R ā. `None` when nothing is matched.
    pub fn least_squares(matched: &Matched<Pose>) -> Option<Alignment3> {
        let n = matched.ids.len();
        if n == 0 {
            return None;
        }
        let centroid = |poses: &[Pose]| {
            poses
                .iter()
                .fold(Vector3::zeros(), |s, p| s + p.translation.vector)
                / n as f64
        };
        let (a, b) = (centroid(&matched.estimate), centroid(&matched.reference));
        let mut sigma = Matrix3::zeros();
        for (e, r) in matched.estimate.iter().zip(&matched.reference) {
            sigma += (r.translation.vector - b) * (e.translation.vector - a).transpose();
        }
        let svd = sigma.svd(true, true);
        let (u, v_t) = (svd.u?, svd.v_t?);
        let mut s = Matrix3::identity();
        if u.determinant() * v_t.determinant() < 0.0 {
            s[(2, 2)] = -1.0;
        }
        let r = u * s * v_t;
        let t = b - r * a;
        Some(Alignment3 {
            rotation: std::array::from_fn(|i| std::array::from_fn(|j| r[(i, j)])),
            translation: [t.x, t.y, t.z],
        })
    }

    /// The motion as an isometry.
    pub fn isometry(&self) -> Pose {
        let r = Matrix3::from_fn(|i, j| self.rotation[i][j]);
        Isometry3::from_parts(
            Translation3::from(Vector3::from(self.translation)),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
        )
    }
}

/// The angle of a rotation error in degrees: the norm of its logarithm, in [0, 180].
fn angle_deg(e: &Pose) -> f64 {
    e.rotation.angle().to_degrees()
}

/// APE of aligned 3D poses: ‖P′_k − Q_k‖ of the positions and the angle of Q_k⁻¹P′_k, P′ the
/// estimate moved by `alignment`.
pub fn absolute_error3(matched: &Matched<Pose>, alignment: &Alignment3) -> Option<AbsoluteError> {
    let t = alignment.isometry();
    let (mut translation, mut rotation) = (Vec::new(), Vec::new());
    for (e, r) in matched.estimate.iter().zip(&matched.reference) {
        let p = t * e;
        translation.push((p.translation.vector - r.translation.vector).norm());
        rotation.push(angle_deg(&(r.inverse() * p)));
    }
    Some(AbsoluteError {
        translation: Statistics::of(&translation)?,
        rotation_deg: Statistics::of(&rotation)?,
    })
}

/// RPE of 3D poses over pairs `delta` apart (as [`super::rpe::relative_error`]): the
/// translation norm and angle of E = (Q_i⁻¹Q_j)⁻¹ (P_i⁻¹P_j).
pub fn relative_error3(
    matched: &Matched<Pose>,
    delta: usize,
    all_pairs: bool,
) -> Option<RelativeError> {
    if delta == 0 {
        return None;
    }
    let n = matched.ids.len();
    let step = if all_pairs { 1 } else { delta };
    let (mut translation, mut rotation) = (Vec::new(), Vec::new());
    for i in (0..n.saturating_sub(delta)).step_by(step) {
        let j = i + delta;
        let q = matched.reference[i].inverse() * matched.reference[j];
        let p = matched.estimate[i].inverse() * matched.estimate[j];
        let e = q.inverse() * p;
        translation.push(e.translation.vector.norm());
        rotation.push(angle_deg(&e));
    }
    Some(RelativeError {
        delta,
        all_pairs,
        translation: Statistics::of(&translation)?,
        rotation_deg: Statistics::of(&rotation)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trajectory() -> Vec<Pose> {
        (0..8)
            .map(|k| {
                let k = k as f64;
                Isometry3::new(
                    Vector3::new(k.sin() * 4.0, 0.7 * k, (0.5 * k).cos()),
                    Vector3::new(0.1 * k, -0.2 * k, 0.3),
                )
            })
            .collect()
    }

    #[test]
    fn a_moved_copy_is_aligned_back_exactly() {
        let reference = trajectory();
        let moved = Isometry3::new(Vector3::new(3.0, -8.0, 2.0), Vector3::new(0.4, -1.1, 2.0));
        let estimate: Vec<Pose> = reference.iter().map(|p| moved.inverse() * p).collect();
        let matched = Matched {
            ids: (0..8).collect(),
            estimate,
            reference,
        };
        let a = Alignment3::least_squares(&matched).unwrap();
        let back = a.isometry();
        let expect = moved.to_homogeneous();
        assert!(
            (back.to_homogeneous() - expect).abs().max() < 1e-12,
            "{a:?}"
        );
        let ape = absolute_error3(&matched, &a).unwrap();
        assert!(
            ape.translation.max < 1e-12 && ape.rotation_deg.max < 1e-9,
            "{ape:?}"
        );
        // Relative motions do not see the rigid motion.
        let rpe = relative_error3(&matched, 2, true).unwrap();
        assert!(rpe.translation.max < 1e-12 && rpe.rotation_deg.max < 1e-9);
        assert_eq!(rpe.translation.count, 6);
    }

    #[test]
    fn errors_by_hand() {
        // Positions 3-4-5 apart and a rotation error of 10 degrees about an oblique axis.
        let axis = Vector3::new(1.0, 2.0, 2.0) / 3.0;
        let reference = vec![Pose::identity(), Pose::translation(1.0, 0.0, 0.0)];
        let estimate = vec![
            Pose::translation(0.0, 3.0, 4.0),
            Isometry3::new(Vector3::new(1.0, 0.0, 0.0), axis * 10f64.to_radians()),
        ];
        let matched = Matched {
            ids: vec![0, 1],
            estimate,
            reference,
        };
        let ape = absolute_error3(&matched, &Alignment3::IDENTITY).unwrap();
        assert_eq!(ape.translation.max, 5.0);
        assert_eq!(ape.translation.mean, 2.5);
        assert!((ape.rotation_deg.max - 10.0).abs() < 1e-12);
        assert_eq!(ape.rotation_deg.min, 0.0);
        // One pair: Q = (1, 0, 0); P = (1, -3, -4) in the first pose's frame, turned by 10°.
        let rpe = relative_error3(&matched, 1, false).unwrap();
        assert!((rpe.translation.max - 5.0).abs() < 1e-15);
        assert!((rpe.rotation_deg.max - 10.0).abs() < 1e-12);
        // Nothing matched: no alignment.
        let none: Matched<Pose> = Matched {
            ids: vec![],
            estimate: vec![],
            reference: vec![],
        };
        assert!(Alignment3::least_squares(&none).is_none());
    }
}
