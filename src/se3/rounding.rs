//! From the relaxation back to SE(3), and into it: SE-Sync's rounding (its Algorithm 2,
//! "Rounding procedure": the rank-3 truncated SVD of Y, the sign that makes most determinants
//! positive, each block projected onto SO(3)), the chordal initialization (SE-Sync §5.1: the
//! rotation-only problem without the orthogonality constraints, a sparse linear least-squares
//! problem, each block then projected onto SO(3)), and the maps between poses and points.

use super::problem::{Point3, Problem3};
use super::stiefel::nearest_rotation;
use crate::linalg::factor::{Assembly, SparseFactor};

/// A pose as a rotation matrix (row-major) and a translation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rt {
    pub r: [f64; 9],
    pub t: [f64; 3],
}

/// Rounds a rank-p point to rank 3 on SO(3)^n: X ← X U₃ with U₃ the three leading right
/// singular vectors of the rotation rows, X ← X diag(−1, 1, 1) if fewer than half of the blocks
/// have a positive determinant, every block replaced by its nearest rotation (translations as
/// projected; the local solver makes them optimal).
pub fn round_to_rank3(problem: &Problem3, x: &Point3) -> Point3 {
    let p = x.p;
    let dim = problem.dim();
    let mut u3 = nalgebra::DMatrix::<f64>::zeros(p, 3);
    if p == 3 {
        u3 = nalgebra::DMatrix::identity(3, 3);
    } else {
        let mut g = nalgebra::DMatrix::<f64>::zeros(p, p);
        for i in 0..problem.n {
            for a in 0..3 {
                let row = x.row(problem.rotation_row(i, a));
                for c in 0..p {
                    for d in 0..p {
                        g[(c, d)] += row[c] * row[d];
                    }
                }
            }
        }
        let eig = g.symmetric_eigen();
        let mut idx: Vec<usize> = (0..p).collect();
        idx.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        for (k, &j) in idx.iter().take(3).enumerate() {
            u3.set_column(k, &eig.eigenvectors.column(j));
        }
    }
    let mut out = Point3 {
        p: 3,
        x: vec![0.0; dim * 3],
    };
    for r in 0..dim {
        let row = x.row(r);
        for k in 0..3 {
            out.x[r * 3 + k] = (0..p).map(|c| row[c] * u3[(c, k)]).sum();
        }
    }
    let block = |pt: &Point3, i: usize| -> [f64; 9] {
        let r0 = problem.rotation_row(i, 0);
        let mut m = [0.0; 9];
        m.copy_from_slice(&pt.x[r0 * 3..(r0 + 3) * 3]);
        m
    };
    let positive = (0..problem.n)
        .filter(|&i| nalgebra::Matrix3::from_row_slice(&block(&out, i)).determinant() > 0.0)
        .count();
    if 2 * positive < problem.n {
        for r in 0..dim {
            out.x[r * 3] = -out.x[r * 3];
        }
    }
    for i in 0..problem.n {
        let r = nearest_rotation(&block(&out, i));
        let r0 = problem.rotation_row(i, 0);
        out.x[r0 * 3..(r0 + 3) * 3].copy_from_slice(&r);
    }
    out
}

/// The chordal initialization at rank 3: min Σ κ‖Y_j − Y_i R̃‖_F² over unconstrained 3x3
/// blocks with the anchor's fixed at I, each block then projected onto SO(3); translations 0
/// (the local solver projects them).
pub fn chordal(problem: &Problem3) -> Point3 {
    let n = problem.n;
    let dim = problem.dim();
    let mut x = Point3 {
        p: 3,
        x: vec![0.0; dim * 3],
    };
    let anchor = problem.anchor;
    for a in 0..3 {
        x.x[problem.rotation_row(anchor, a) * 3 + a] = 1.0;
    }
    if n == 1 {
        return x;
    }
    // Unknown index of (pose, a): poses other than the anchor, 3 each.
    let unknown = |i: usize, a: usize| -> Option<usize> {
        use std::cmp::Ordering::*;
        match i.cmp(&anchor) {
            Less => Some(3 * i + a),
            Equal => None,
            Greater => Some(3 * (i - 1) + a),
        }
    };
    let m = 3 * (n - 1);
    let mut entries: Vec<(usize, usize)> = (0..m).map(|k| (k, k)).collect();
    let mut values: Vec<f64> = vec![0.0; m];
    let mut rhs = vec![0.0; m * 3];
    let mut add = |r: (usize, usize),
                   c: (usize, usize),
                   v: f64,
                   entries: &mut Vec<(usize, usize)>,
                   values: &mut Vec<f64>| {
        // Symmetric entry (r, c) of the rotation Laplacian with value v (added once per
        // unordered pair; the diagonal once).
        match (unknown(r.0, r.1), unknown(c.0, c.1)) {
            (Some(a), Some(b)) => {
                entries.push((a.min(b), a.max(b)));
                values.push(v);
            }
            (Some(a), None) => {
                // Moves to the right-hand side: −v · X_anchor's row c.1 = −v e_{c.1}.
                rhs[c.1 * m + a] -= v;
            }
            (None, Some(b)) => {
                rhs[r.1 * m + b] -= v;
            }
            (None, None) => {}
        }
    };
    for t in &problem.terms {
        for b in 0..3 {
            add((t.j, b), (t.j, b), t.kappa, &mut entries, &mut values);
        }
        for a in 0..3 {
            for a2 in 0..3 {
                if a2 < a {
                    continue;
                }
                let rr: f64 = (0..3).map(|b| t.r[a][b] * t.r[a2][b]).sum();
                add((t.i, a), (t.i, a2), t.kappa * rr, &mut entries, &mut values);
            }
            for b in 0..3 {
                add(
                    (t.i, a),
                    (t.j, b),
                    -t.kappa * t.r[a][b],
                    &mut entries,
                    &mut values,
                );
            }
        }
    }
    let mut assembly = Assembly::<f64>::new(m, &entries);
    assembly.fill(&values);
    let mut factor = SparseFactor::<f64>::analyze(assembly.matrix.symbolic());
    if factor.llt(assembly.matrix.as_ref()).is_err() {
        // Not connected enough for the relaxation: start from the identity.
        for i in 0..n {
            for a in 0..3 {
                x.x[problem.rotation_row(i, a) * 3 + a] = 1.0;
            }
        }
        return x;
    }
    factor.solve_block_in_place(faer::MatMut::from_column_major_slice_mut(&mut rhs, m, 3));
    for i in (0..n).filter(|&i| i != anchor) {
        let mut block = [0.0; 9];
        for a in 0..3 {
            for c in 0..3 {
                block[a * 3 + c] = rhs[c * m + unknown(i, a).unwrap()];
            }
        }
        let r = nearest_rotation(&block);
        let r0 = problem.rotation_row(i, 0);
        x.x[r0 * 3..(r0 + 3) * 3].copy_from_slice(&r);
    }
    x
}

/// The poses of a rank-3 point: R_i = X_iᵀ (X_i the block's rows), t_i its translation row
/// (0 for the anchor).
pub fn poses_of(problem: &Problem3, x: &Point3) -> Vec<Rt> {
    assert_eq!(x.p, 3);
    (0..problem.n)
        .map(|i| {
            let mut r = [0.0; 9];
            for a in 0..3 {
                for c in 0..3 {
                    // R[c][a] = X_i[a][c].
                    r[c * 3 + a] = x.x[problem.rotation_row(i, a) * 3 + c];
                }
            }
            let t = problem
                .position_row(i)
                .map_or([0.0; 3], |k| [x.x[k * 3], x.x[k * 3 + 1], x.x[k * 3 + 2]]);
            Rt { r, t }
        })
        .collect()
}

/// The rank-3 point of poses (translations relative to the anchor's; rotations as they are).
pub fn point_of(problem: &Problem3, poses: &[Rt]) -> Point3 {
    let mut x = Point3 {
        p: 3,
        x: vec![0.0; problem.dim() * 3],
    };
    let origin = poses[problem.anchor].t;
    for (i, pose) in poses.iter().enumerate() {
        for a in 0..3 {
            for c in 0..3 {
                x.x[problem.rotation_row(i, a) * 3 + c] = pose.r[c * 3 + a];
            }
        }
        if let Some(k) = problem.position_row(i) {
            for c in 0..3 {
                x.x[k * 3 + c] = pose.t[c] - origin[c];
            }
        }
    }
    x
}
