//! Trajectory error of an estimate against a reference (ground truth, or another solver's
//! estimate), as evo (Grupp, 2017) computes it for planar poses: poses matched by vertex id,
//! the estimate aligned to the reference by the SE(2) transform that minimizes the squared
//! position error ([`align`]), then the absolute pose error per pose ([`ape`]) and the relative
//! pose error over a fixed id step ([`rpe`]), each summarized by [`Statistics`]; the same for 3D
//! graphs with an SE(3) alignment ([`spatial`]).
//!
//! May use: pgo-io (the graph model). Nothing of the solver: any two files of poses compare.

pub mod align;
pub mod ape;
pub mod rpe;
pub mod spatial;

use crate::graph::{Pose2, PoseGraph};
use serde::Serialize;

/// The poses of the estimate and of the reference with the same vertex id, in ascending id
/// order (planar poses, or rigid motions of 3D graphs: [`spatial`]).
#[derive(Debug, Clone)]
pub struct Matched<P = Pose2> {
    pub ids: Vec<u32>,
    pub estimate: Vec<P>,
    pub reference: Vec<P>,
}

/// Pairs the poses of `estimate` and `reference` by vertex id (ids in only one are left out).
pub fn match_by_id(estimate: &PoseGraph, reference: &PoseGraph) -> Matched {
    match_ids(
        &estimate.ids,
        &estimate.poses,
        &reference.ids,
        &reference.poses,
    )
}

/// [`match_by_id`] of any poses, given with their ids.
pub fn match_ids<P: Copy>(
    estimate_ids: &[u32],
    estimate: &[P],
    reference_ids: &[u32],
    reference: &[P],
) -> Matched<P> {
    let mut by_id: Vec<(u32, P)> = reference_ids
        .iter()
        .zip(reference)
        .map(|(&id, &p)| (id, p))
        .collect();
    by_id.sort_by_key(|&(id, _)| id);
    let mut pairs: Vec<(u32, P, P)> = estimate_ids
        .iter()
        .zip(estimate)
        .filter_map(|(&id, &p)| {
            by_id
                .binary_search_by_key(&id, |&(i, _)| i)
                .ok()
                .map(|k| (id, p, by_id[k].1))
        })
        .collect();
    pairs.sort_by_key(|&(id, _, _)| id);
    Matched {
        ids: pairs.iter().map(|p| p.0).collect(),
        estimate: pairs.iter().map(|p| p.1).collect(),
        reference: pairs.iter().map(|p| p.2).collect(),
    }
}

/// Summary of a list of errors, evo's fields: root mean square, mean, median (the mean of the
/// two middle values for an even count), population standard deviation, minimum, maximum.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Statistics {
    pub count: usize,
    pub rmse: f64,
    pub mean: f64,
    pub median: f64,
    pub std: f64,
    pub min: f64,
    pub max: f64,
}

impl Statistics {
    /// `None` for an empty list.
    pub fn of(errors: &[f64]) -> Option<Statistics> {
        if errors.is_empty() {
            return None;
        }
        let n = errors.len() as f64;
        let mean = errors.iter().sum::<f64>() / n;
        let rmse = (errors.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
        let std = (errors.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / n).sqrt();
        let mut sorted = errors.to_vec();
        sorted.sort_by(f64::total_cmp);
        let k = sorted.len() / 2;
        let median = if sorted.len() % 2 == 1 {
            sorted[k]
        } else {
            0.5 * (sorted[k - 1] + sorted[k])
        };
        Some(Statistics {
            count: errors.len(),
            rmse,
            mean,
            median,
            std,
            min: sorted[0],
            max: sorted[sorted.len() - 1],
        })
    }
}

/// The angle of a rotation in (−π, π].
pub(crate) fn wrap(angle: f64) -> f64 {
    let a = angle.rem_euclid(std::f64::consts::TAU);
    if a > std::f64::consts::PI {
        a - std::f64::consts::TAU
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statistics_by_hand() {
        // 3, 4, 0, 5: mean 3, rms sqrt(50/4), median (3 + 4)/2, variance (0 + 1 + 9 + 4)/4.
        let s = Statistics::of(&[3.0, 4.0, 0.0, 5.0]).unwrap();
        assert_eq!(s.count, 4);
        assert_eq!(s.mean, 3.0);
        assert_eq!(s.rmse, (12.5f64).sqrt());
        assert_eq!(s.median, 3.5);
        assert_eq!(s.std, (3.5f64).sqrt());
        assert_eq!((s.min, s.max), (0.0, 5.0));
        assert_eq!(Statistics::of(&[2.0, 9.0, 1.0]).unwrap().median, 2.0);
        assert!(Statistics::of(&[]).is_none());
    }

    #[test]
    fn wrap_is_in_the_half_open_interval() {
        use std::f64::consts::PI;
        assert_eq!(wrap(PI), PI);
        assert_eq!(wrap(-PI), PI);
        assert!((wrap(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-15);
        assert_eq!(wrap(0.25), 0.25);
    }
}
