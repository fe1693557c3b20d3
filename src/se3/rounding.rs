//! From the relaxation back to SE(3), and into it: SE-Sync's rounding (its Algorithm 2,
//! "Rounding procedure": the rank-3 truncated SVD of Y, the sign that makes most determinants
//! positive, each block projected onto SO(3)), the chordal initialization (SE-Sync §5.1: the
//! rotation-only problem without the orthogonality constraints, a sparse linear least-squares
//! problem, each block then projected onto SO(3)), and the maps between poses and points.

use super::problem::{Point3, Problem3};
use super::stiefel::nearest_rotation;
use crate::linalg::factor::{SparseFactor, column_buckets};

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
    // The matrix, pose pair by pose pair: a 3x3 block for each pair u < v of the graph (Problem3's
    // pairs, sorted) and the upper triangle of each pose's own block, summed term by term in the
    // terms' order; its CSC built from them directly. (Listed entry by entry and sorted by an
    // assembly, with 10 MB of arrays, it took 7 of the relaxation's 25 ms on torus3D; built from
    // the blocks, the relaxation takes 3 ms less.) The same pattern, entry for entry, and the
    // same sums in the same order as that assembly: the same bits.
    let others = &problem.pairs[n..];
    let mut off = vec![[[0.0f64; 3]; 3]; others.len()];
    let mut own = vec![[[0.0f64; 3]; 3]; n];
    // Whether a pose's block has entries off its diagonal: those of its edges' tails (and
    // self-loops), whatever their values.
    let mut full = vec![false; n];
    let mut rhs = vec![0.0; m * 3];
    // Adds v at the symmetric entry (pose r.0, row r.1) × (pose c.0, row c.1) of the rotation
    // Laplacian (once per unordered pair; the diagonal once); `pair` indexes the block of the
    // term's poses in `others` when they differ. The anchor's are the right-hand side.
    let mut add = |r: (usize, usize), c: (usize, usize), v: f64, pair: usize| {
        match (unknown(r.0, r.1), unknown(c.0, c.1)) {
            (Some(_), Some(_)) => {
                use std::cmp::Ordering::*;
                match r.0.cmp(&c.0) {
                    Equal => own[r.0][r.1.min(c.1)][r.1.max(c.1)] += v,
                    Less => off[pair][r.1][c.1] += v,
                    Greater => off[pair][c.1][r.1] += v,
                }
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
        let pair = if t.i == t.j {
            usize::MAX
        } else {
            others
                .binary_search(&(t.i.min(t.j), t.i.max(t.j)))
                .expect("a term's pair of poses is one of the problem's pairs")
        };
        full[t.i] = true;
        for b in 0..3 {
            add((t.j, b), (t.j, b), t.kappa, pair);
        }
        for a in 0..3 {
            for a2 in 0..3 {
                if a2 < a {
                    continue;
                }
                let rr: f64 = (0..3).map(|b| t.r[a][b] * t.r[a2][b]).sum();
                add((t.i, a), (t.i, a2), t.kappa * rr, pair);
            }
            for b in 0..3 {
                add((t.i, a), (t.j, b), -t.kappa * t.r[a][b], pair);
            }
        }
    }
    // The pairs by their second pose, first poses ascending within each (the pairs are sorted).
    let (by_second, second) = column_buckets(n, others.iter().map(|&(_, v)| v));
    let mut col_ptr = Vec::with_capacity(m + 1);
    let mut row_idx = Vec::new();
    let mut vals = Vec::new();
    col_ptr.push(0);
    for v in (0..n).filter(|&v| v != anchor) {
        for b in 0..3 {
            for &k in &second[by_second[v]..by_second[v + 1]] {
                let u = others[k].0;
                if let Some(first) = unknown(u, 0) {
                    for a in 0..3 {
                        row_idx.push(first + a);
                        vals.push(off[k][a][b]);
                    }
                }
            }
            let first = unknown(v, 0).expect("not the anchor");
            for a in if full[v] { 0..b + 1 } else { b..b + 1 } {
                row_idx.push(first + a);
                vals.push(own[v][a][b]);
            }
            col_ptr.push(row_idx.len());
        }
    }
    let matrix = faer::sparse::SparseColMat::new(
        faer::sparse::SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx),
        vals,
    );
    let mut factor = SparseFactor::<f64>::analyze(matrix.symbolic());
    if factor.llt(matrix.as_ref()).is_err() {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::se3::problem::weights3;
    use crate::simulate::space::{SpaceConfig, World3, simulate3};
    use crate::simulate::{RotationNoise, TranslationNoise};

    /// The chordal relaxation solved densely, straight from its definition: the unknowns Y_i
    /// (3x3, the anchor's fixed at I) minimizing Σ κ‖Y_j − Y_i R̃‖_F², whose normal equations
    /// row by row are A y = b with A the sum over the terms of κ (e_j − e_i ⊗ R̃ᵀ)ᵀ(…) on the
    /// 3(n−1) coordinates of one row of every Y_i; each block then its nearest rotation.
    fn dense_chordal(problem: &Problem3) -> Vec<[f64; 9]> {
        let n = problem.n;
        let m = 3 * (n - 1);
        let at = |i: usize, a: usize| -> Option<usize> {
            (i != problem.anchor).then(|| 3 * (i - usize::from(i > problem.anchor)) + a)
        };
        // One residual per term and row c of the Y's and column b: Y_j[c][b] − Σ_a Y_i[c][a]
        // R̃[a][b], the same linear form in (Y_i[c][·], Y_j[c][·]) for every row c.
        let mut a_mat = nalgebra::DMatrix::<f64>::zeros(m, m);
        let mut rhs = nalgebra::DMatrix::<f64>::zeros(m, 3);
        for t in &problem.terms {
            for b in 0..3 {
                // The residual's coefficients on the unknowns (pose, a) and its constant part
                // (the anchor's fixed Y = I, row c: e_c), as a function of c.
                let mut coef: Vec<((usize, usize), f64)> = vec![((t.j, b), 1.0)];
                for a in 0..3 {
                    coef.push(((t.i, a), -t.r[a][b]));
                }
                for &((p, a), va) in &coef {
                    let Some(ra) = at(p, a) else { continue };
                    for &((q, a2), vb) in &coef {
                        match at(q, a2) {
                            Some(rb) => a_mat[(ra, rb)] += t.kappa * va * vb,
                            // The anchor's Y_q[c][a2] = δ(c, a2): column c of the right-hand
                            // side.
                            None => rhs[(ra, a2)] -= t.kappa * va * vb,
                        }
                    }
                }
            }
        }
        let y = a_mat.cholesky().expect("connected").solve(&rhs);
        (0..n)
            .map(|i| match at(i, 0) {
                None => [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
                Some(k) => {
                    let mut block = [0.0; 9];
                    for a in 0..3 {
                        for c in 0..3 {
                            block[a * 3 + c] = y[(k + a, c)];
                        }
                    }
                    nearest_rotation(&block)
                }
            })
            .collect()
    }

    #[test]
    fn the_chordal_estimate_is_the_dense_least_squares_solution_rounded() {
        for (world, n, seed, anchor) in [
            (World3::Grid, 27, 3, 0),
            (World3::Sphere, 40, 5, 7),
            (World3::Torus, 36, 9, 35),
        ] {
            let graph = simulate3(&SpaceConfig {
                world,
                n,
                side: 6.0,
                loop_probability: 0.3,
                rotation_noise: RotationNoise::Gaussian { sigma: 0.1 },
                translation_noise: TranslationNoise::Gaussian { sigma: 0.05 },
                seed,
            })
            .graph;
            let weights = weights3(&graph, false).unwrap();
            let problem = Problem3::new(&graph, &weights, anchor);
            let x = chordal(&problem);
            let expected = dense_chordal(&problem);
            for (i, want) in expected.iter().enumerate() {
                let mut got = [0.0; 9];
                for a in 0..3 {
                    let r0 = problem.rotation_row(i, a);
                    got[a * 3..a * 3 + 3].copy_from_slice(&x.x[r0 * 3..r0 * 3 + 3]);
                }
                let diff = got
                    .iter()
                    .zip(want)
                    .map(|(g, w)| (g - w).abs())
                    .fold(0.0, f64::max);
                assert!(diff < 1e-9, "{world:?} pose {i}: {got:?} against {want:?}");
            }
        }
    }
}
