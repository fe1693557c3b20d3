//! Absolute pose error (evo's APE): per matched pose, after alignment, the position error
//! |t_est − t_ref| (metres) and the heading error |wrap(θ_est − θ_ref)| (degrees), the
//! translation part and the rotation angle of E_i = Q_i⁻¹ P_i for the reference pose Q_i and the
//! aligned estimate P_i.

use super::align::Alignment;
use super::{Matched, Statistics, wrap};
use serde::Serialize;

#[derive(Debug, Clone, Copy, Serialize)]
pub struct AbsoluteError {
    pub translation: Statistics,
    pub rotation_deg: Statistics,
}

/// The APE of `matched.estimate` moved by `alignment`; `None` when nothing is matched.
pub fn absolute_error(matched: &Matched, alignment: &Alignment) -> Option<AbsoluteError> {
    let (mut translation, mut rotation) = (Vec::new(), Vec::new());
    for (e, r) in matched.estimate.iter().zip(&matched.reference) {
        let p = alignment.apply(*e);
        translation.push((p.x - r.x).hypot(p.y - r.y));
        rotation.push(wrap(p.theta - r.theta).abs().to_degrees());
    }
    Some(AbsoluteError {
        translation: Statistics::of(&translation)?,
        rotation_deg: Statistics::of(&rotation)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::Pose2;

    #[test]
    fn errors_by_hand() {
        // Estimate 3-4-5 off in position at one pose and 10 degrees off in heading at the other.
        let matched = Matched {
            ids: vec![0, 1],
            estimate: vec![
                Pose2::new(3.0, 4.0, 0.0),
                Pose2::new(1.0, 0.0, 10f64.to_radians()),
            ],
            reference: vec![Pose2::new(0.0, 0.0, 0.0), Pose2::new(1.0, 0.0, 0.0)],
        };
        let a = absolute_error(&matched, &Alignment::IDENTITY).unwrap();
        assert_eq!(a.translation.max, 5.0);
        assert_eq!(a.translation.mean, 2.5);
        assert!((a.rotation_deg.max - 10.0).abs() < 1e-12);
        assert_eq!(a.rotation_deg.min, 0.0);
    }
}
