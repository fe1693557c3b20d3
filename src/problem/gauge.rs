//! The gauge: f is invariant to a rigid motion of the whole estimate (Sec. 3, pose 0 anchored,
//! eq. (15)), so an estimate is reported in the input's frame: the fixed pose (a g2o `FIX` line)
//! where the input has it, else pose 0 where the input has it.

use crate::graph::Pose2;
use crate::problem::matrix::rotation;
use faer::c64;

/// The estimate moved rigidly (f is invariant to that) so that pose 0 is exactly `anchor`.
pub fn move_to_anchor(poses: &[Pose2], anchor: Pose2) -> Vec<Pose2> {
    move_pose_to(poses, 0, anchor)
}

/// The estimate moved rigidly (f is invariant to that) so that pose `k` is exactly `anchor`: the
/// gauge of a component whose pose `k` is fixed (a g2o `FIX` line).
pub fn move_pose_to(poses: &[Pose2], k: usize, anchor: Pose2) -> Vec<Pose2> {
    // Rotate by φ so that θ_k becomes the anchor's, then translate p_k to the anchor's. φ is
    // taken from the anchor's angle reduced to [-π, π] (if outside, by the rotation e^{iθ}, whose
    // argument reduction is exact): an anchor angle of 1e30 added to every θ would erase the
    // differences between them.
    let anchor_angle = if anchor.theta.abs() <= std::f64::consts::PI {
        anchor.theta
    } else {
        rotation(anchor.theta).arg()
    };
    let phi = anchor_angle - poses[k].theta;
    let turn = rotation(phi);
    let pk = c64::new(poses[k].x, poses[k].y);
    let place = |at: Pose2| -> Vec<Pose2> {
        let mut moved: Vec<Pose2> = poses
            .iter()
            .map(|p| {
                let q = turn * (c64::new(p.x, p.y) - pk);
                Pose2::new(at.x + q.re, at.y + q.im, p.theta + phi)
            })
            .collect();
        // Exactly, not up to the rounding of θ_k + φ.
        moved[k] = at;
        moved
    };
    place_or_origin(anchor, place)
}

/// `place(anchor)`, or, where positions would overflow next to the anchor's (near 1.8e308),
/// `place` with the anchored pose at the origin and the anchor's heading (f does not depend on where the
/// estimate is).
pub fn place_or_origin(anchor: Pose2, place: impl Fn(Pose2) -> Vec<Pose2>) -> Vec<Pose2> {
    let moved = place(anchor);
    if moved.iter().all(|p| p.x.is_finite() && p.y.is_finite()) {
        return moved;
    }
    place(Pose2::new(0.0, 0.0, anchor.theta))
}
