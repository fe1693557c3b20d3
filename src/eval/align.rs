//! The SE(2) transform that best aligns the estimate's positions to the reference's: the planar
//! case of Umeyama's least-squares alignment without scale (IEEE TPAMI 13(4), 1991, eqs. (34)-
//! (42)), which evo's `--align` computes in 3D. With centred positions a_i (estimate) and b_i
//! (reference), Σ |R(φ) a_i − b_i|² is least at φ = atan2(Σ a_i × b_i, Σ a_i · b_i); the
//! translation then maps the estimate's centroid onto the reference's.

use super::Matched;
use crate::graph::Pose2;
use serde::Serialize;

/// x ↦ R(angle) x + (x, y), a heading θ ↦ θ + angle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Alignment {
    pub angle: f64,
    pub x: f64,
    pub y: f64,
}

impl Alignment {
    pub const IDENTITY: Alignment = Alignment {
        angle: 0.0,
        x: 0.0,
        y: 0.0,
    };

    /// The least-squares alignment of `matched.estimate` onto `matched.reference` (positions
    /// only, as evo's); `None` when nothing is matched. With one pose every rotation about it
    /// is a minimum: the one of angle 0 is taken.
    pub fn least_squares(matched: &Matched) -> Option<Alignment> {
        let n = matched.ids.len();
        if n == 0 {
            return None;
        }
        let centroid = |poses: &[Pose2]| {
            let (sx, sy) = poses
                .iter()
                .fold((0.0, 0.0), |(sx, sy), p| (sx + p.x, sy + p.y));
            (sx / n as f64, sy / n as f64)
        };
        let (ax, ay) = centroid(&matched.estimate);
        let (bx, by) = centroid(&matched.reference);
        let (mut dot, mut cross) = (0.0, 0.0);
        for (a, b) in matched.estimate.iter().zip(&matched.reference) {
            let (a0, a1) = (a.x - ax, a.y - ay);
            let (b0, b1) = (b.x - bx, b.y - by);
            dot += a0 * b0 + a1 * b1;
            cross += a0 * b1 - a1 * b0;
        }
        let angle = cross.atan2(dot);
        let (s, c) = angle.sin_cos();
        Some(Alignment {
            angle,
            x: bx - (c * ax - s * ay),
            y: by - (s * ax + c * ay),
        })
    }

    /// The pose moved by the alignment.
    pub fn apply(&self, p: Pose2) -> Pose2 {
        let (s, c) = self.angle.sin_cos();
        Pose2 {
            x: c * p.x - s * p.y + self.x,
            y: s * p.x + c * p.y + self.y,
            theta: super::wrap(p.theta + self.angle),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_moved_copy_is_aligned_back_exactly() {
        // The reference moved by a known rigid transform: the alignment is its inverse's
        // inverse, i.e. the transform itself, to rounding.
        let reference: Vec<Pose2> = (0..7)
            .map(|k| Pose2::new((k as f64).sin() * 5.0, k as f64 * 0.7, 0.1 * k as f64))
            .collect();
        let moved = Alignment {
            angle: -2.5,
            x: 3.0,
            y: -8.0,
        };
        // estimate = moved⁻¹(reference), so aligning the estimate must give `moved`.
        let (s, c) = (-moved.angle).sin_cos();
        let estimate: Vec<Pose2> = reference
            .iter()
            .map(|p| {
                let (dx, dy) = (p.x - moved.x, p.y - moved.y);
                Pose2::new(c * dx - s * dy, s * dx + c * dy, p.theta - moved.angle)
            })
            .collect();
        let matched = Matched {
            ids: (0..7).collect(),
            estimate,
            reference: reference.clone(),
        };
        let a = Alignment::least_squares(&matched).unwrap();
        assert!((a.angle - moved.angle).abs() < 1e-13, "{a:?}");
        assert!(
            (a.x - moved.x).abs() < 1e-12 && (a.y - moved.y).abs() < 1e-12,
            "{a:?}"
        );
        for (e, r) in matched.estimate.iter().zip(&reference) {
            let p = a.apply(*e);
            assert!((p.x - r.x).abs() < 1e-12 && (p.y - r.y).abs() < 1e-12);
            assert!(super::super::wrap(p.theta - r.theta).abs() < 1e-13);
        }
    }

    #[test]
    fn one_pose_is_moved_onto_its_reference_without_rotation() {
        let mut one = Matched {
            ids: vec![3],
            estimate: vec![Pose2::new(1.0, 2.0, 0.5)],
            reference: vec![Pose2::new(-4.0, 7.0, 1.5)],
        };
        let a = Alignment::least_squares(&one).unwrap();
        assert_eq!(
            a,
            Alignment {
                angle: 0.0,
                x: -5.0,
                y: 5.0
            }
        );
        one.ids.clear();
        one.estimate.clear();
        one.reference.clear();
        assert!(Alignment::least_squares(&one).is_none());
    }
}
