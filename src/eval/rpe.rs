//! Relative pose error (evo's RPE): over pairs of matched poses (i, j) a fixed number `delta` of
//! matched poses apart (in ascending id order, as evo counts frames), the error of the estimate's
//! relative motion against the reference's, E = (Q_i⁻¹ Q_j)⁻¹ (P_i⁻¹ P_j): its translation norm
//! (metres) and rotation angle (degrees). Alignment does not change it. Pairs are consecutive
//! and disjoint (0, δ), (δ, 2δ), … as evo's default, or every (i, i + δ) with `all_pairs`.

use super::{Matched, Statistics, wrap};
use crate::graph::Pose2;
use serde::Serialize;

#[derive(Debug, Clone, Copy, Serialize)]
pub struct RelativeError {
    pub delta: usize,
    pub all_pairs: bool,
    pub translation: Statistics,
    pub rotation_deg: Statistics,
}

/// P_i⁻¹ P_j.
fn between(a: Pose2, b: Pose2) -> Pose2 {
    let (s, c) = a.theta.sin_cos();
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    Pose2::new(c * dx + s * dy, -s * dx + c * dy, wrap(b.theta - a.theta))
}

/// The RPE; `None` when `delta` is 0 or no pair is `delta` apart.
pub fn relative_error(matched: &Matched, delta: usize, all_pairs: bool) -> Option<RelativeError> {
    if delta == 0 {
        return None;
    }
    let n = matched.ids.len();
    let step = if all_pairs { 1 } else { delta };
    let (mut translation, mut rotation) = (Vec::new(), Vec::new());
    for i in (0..n.saturating_sub(delta)).step_by(step) {
        let j = i + delta;
        let q = between(matched.reference[i], matched.reference[j]);
        let p = between(matched.estimate[i], matched.estimate[j]);
        let e = between(q, p);
        translation.push(e.x.hypot(e.y));
        rotation.push(e.theta.abs().to_degrees());
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

    #[test]
    fn a_rigidly_moved_trajectory_has_no_relative_error() {
        let reference: Vec<Pose2> = (0..9)
            .map(|k| Pose2::new(k as f64, (k as f64).cos(), 0.3 * k as f64))
            .collect();
        let estimate = reference
            .iter()
            .map(|p| {
                super::super::align::Alignment {
                    angle: 1.0,
                    x: 4.0,
                    y: -2.0,
                }
                .apply(*p)
            })
            .collect();
        let matched = Matched {
            ids: (0..9).collect(),
            estimate,
            reference,
        };
        for (delta, all, count) in [(1, false, 8), (3, false, 2), (3, true, 6)] {
            let r = relative_error(&matched, delta, all).unwrap();
            assert_eq!(r.translation.count, count);
            assert!(
                r.translation.max < 1e-12 && r.rotation_deg.max < 1e-12,
                "{r:?}"
            );
        }
        assert!(relative_error(&matched, 0, false).is_none());
        assert!(relative_error(&matched, 9, false).is_none());
    }

    #[test]
    fn one_bad_step_by_hand() {
        // Reference: one unit step along x, Q = (1, 0, 0°). Estimate: P = (0, 2, 90°). Then
        // E = Q⁻¹P = (−1, 2, 90°): translation error √5, rotation error 90°.
        let reference = vec![Pose2::new(0.0, 0.0, 0.0), Pose2::new(1.0, 0.0, 0.0)];
        let estimate = vec![
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(0.0, 2.0, std::f64::consts::FRAC_PI_2),
        ];
        let matched = Matched {
            ids: vec![0, 1],
            estimate,
            reference,
        };
        let r = relative_error(&matched, 1, false).unwrap();
        assert!((r.translation.max - 5f64.sqrt()).abs() < 1e-15, "{r:?}");
        assert!((r.rotation_deg.max - 90.0).abs() < 1e-12);
    }
}
