//! Initializations for the scalable solver (docs/method.md §3.2).
//!
//! - Chordal relaxation of the rotations: drop |r_i| = 1 and minimize the rotation part of the
//!   cost, Σ κ |r_j − R r_i|² = r* Q_κ r with r_0 = 1 (a sparse linear least-squares problem whose
//!   normal equations are the anchored connection Laplacian), then normalize each r_i. On a tree
//!   or a balanced graph this is exact (Appendix 8.1: the measurements compose consistently).
//! - Positions optimal for given rotations: ρ̃ = −L⁻¹ S̃ r̃ (eq. (24)), by a sparse Cholesky of the
//!   anchored Laplacian L.

use crate::linalg::factor::{Assembly, Layout, Permuted, Scalar, SparseFactor};
use crate::problem::matrix::for_each_entry;
use crate::problem::rank_p::{Point, Problem};
use faer::c64;
use faer::sparse::SparseColMatRef;

/// Chordal rotations (unit modulus), r_0 = 1. `None` if the graph is not connected.
pub fn chordal_rotations(problem: &Problem) -> Option<Vec<c64>> {
    let n = problem.n;
    let one = c64::new(1.0, 0.0);
    if n == 1 {
        return Some(vec![one]);
    }
    // Unknowns r_1..r_{n−1} at 0..n−2; r_0 = 1 moves to the right-hand side.
    let mut entries = Vec::with_capacity(3 * problem.terms.len());
    let mut values = Vec::with_capacity(3 * problem.terms.len());
    let mut rhs = vec![c64::new(0.0, 0.0); n - 1];
    let mut push = |a: usize, b: usize, v: c64, entries: &mut Vec<(usize, usize)>| {
        // Upper triangle: (a, b) with a ≤ b holds v; below it its conjugate is implied.
        if a <= b {
            entries.push((a, b));
            values.push(v);
        } else {
            entries.push((b, a));
            values.push(v.conj());
        }
    };
    // Landmark observations have no rotation part (κ = 0): they add nothing here.
    for t in problem.terms.iter().filter(|t| !t.landmark) {
        let k = c64::new(t.kappa, 0.0);
        // κ|r_j − R r_i|²: κ at (i,i) and (j,j), −κR at (j,i), −κR̄ at (i,j).
        match (t.i.checked_sub(1), t.j.checked_sub(1)) {
            (Some(i), Some(j)) => {
                push(i, i, k, &mut entries);
                push(j, j, k, &mut entries);
                if i != j {
                    push(i, j, -k * t.rot.conj(), &mut entries);
                }
            }
            (None, Some(j)) => {
                // r_i = 1: κ|r_j − R|² → κ at (j,j), right-hand side κR.
                push(j, j, k, &mut entries);
                rhs[j] += k * t.rot;
            }
            (Some(i), None) => {
                // r_j = 1: κ|1 − R r_i|² → κ at (i,i), right-hand side κR̄.
                push(i, i, k, &mut entries);
                rhs[i] += k * t.rot.conj();
            }
            (None, None) => {}
        }
    }
    let mut factor = anchored_llt(n - 1, &problem.rotation_order(), &entries, &values)?;
    factor.solve_in_place(&mut rhs);
    Some(
        std::iter::once(one)
            .chain(rhs.into_iter().map(|z| {
                let m = z.norm();
                if m > 0.0 && m.is_finite() { z / m } else { one }
            }))
            .collect(),
    )
}

/// The chordal relaxation of the whole problem, for graphs with landmarks: minimize
/// x̃* W̃ x̃ (eq. (24)) over the positions of poses and landmarks and the rotations with
/// |r_i| = 1 dropped and r_0 = 1, a sparse linear least-squares problem whose normal equations
/// are W̃ without the row and column of r_0; then each r_i normalized. Unlike
/// [`chordal_rotations`] it sees the landmark observations, the only loop closures of a
/// landmark graph such as Victoria Park's (the rotations alone see only the odometry).
/// `None` if that matrix is not numerically positive definite.
pub fn chordal_full(problem: &Problem) -> Option<Vec<c64>> {
    let r0 = problem.rotation_row(0);
    let dim = problem.rows() - 1;
    let at = |k: usize| if k < r0 { k } else { k - 1 };
    // W̃ y = −W̃[:, r0] · 1: the row and column of r0 move to the right-hand side.
    let upper = &problem.matrix.upper;
    let mut rhs = vec![c64::new(0.0, 0.0); dim];
    for_each_entry(upper, |a, b, v| match (a == r0, b == r0) {
        (false, true) => rhs[at(a)] -= v,
        (true, false) => rhs[at(b)] -= v.conj(),
        _ => {}
    });
    // The rest of W̃, without the row and column of r0, straight in the factor's order and
    // triangle ([`Permuted`]: the matrices faer's permutation would copy, without the copy).
    let order: Vec<usize> = problem
        .row_order()
        .into_iter()
        .filter(|&k| k != r0)
        .map(at)
        .collect();
    let (mut factor, permuted) = Permuted::analyzed(upper, &order, Some(r0), Layout::Auto);
    let values = permuted.values_of(upper);
    factor
        .llt(SparseColMatRef::new(permuted.pattern.as_ref(), &values))
        .ok()?;
    let rhs = factor.solve_gathered(&order, |k| rhs[k]);
    let one = c64::new(1.0, 0.0);
    Some(
        std::iter::once(one)
            .chain((1..problem.n).map(|k| {
                let z = rhs[at(problem.rotation_row(k))];
                let m = z.norm();
                if m > 0.0 && m.is_finite() { z / m } else { one }
            }))
            .collect(),
    )
}

/// The LLᴴ of a `dim` x `dim` Hermitian matrix (upper-triangle entries, duplicates summed), in
/// the given fill-reducing order. `None` if it is not numerically positive definite.
fn anchored_llt<T: Scalar>(
    dim: usize,
    order: &[usize],
    entries: &[(usize, usize)],
    values: &[T],
) -> Option<SparseFactor<T>> {
    let mut assembly = Assembly::<T>::new(dim, entries);
    assembly.fill(values);
    let mut factor = SparseFactor::analyze_ordered(assembly.matrix.symbolic(), order, Layout::Auto);
    if dim > 0 {
        factor.llt(assembly.matrix.as_ref()).ok()?;
    }
    Some(factor)
}

/// The rank-1 point [ρ̃; r̃] with the given rotations and the positions optimal for them.
/// `None` if the graph is not connected.
pub fn with_optimal_positions(problem: &Problem, r: &[c64]) -> Option<Point> {
    let mut x = Point {
        p: 1,
        x: vec![c64::new(0.0, 0.0); problem.positions()]
            .into_iter()
            .chain(r.iter().copied())
            .collect(),
    };
    OptimalPositions::new(problem)?.apply(problem, &mut x);
    Some(x)
}

/// The positions optimal for given rotations, ρ̃ = −L⁻¹ S̃ r̃ (eq. (24)), column by column of a
/// rank-p point, with one Cholesky factorization of the anchored Laplacian L for every call (L
/// depends on the graph and τ only).
pub struct OptimalPositions {
    /// L's LLᵀ, real (a complex one of the same real matrix took twice the memory: 111 MiB at
    /// 10⁶ poses).
    factor: SparseFactor<f64>,
}

impl OptimalPositions {
    /// Factors L, summed edge by edge (Σ τ over the edges at each pose on the diagonal, −τ
    /// between the poses of an edge). `None` if the graph is not connected (L singular).
    pub fn new(problem: &Problem) -> Option<Self> {
        let mut entries = Vec::with_capacity(3 * problem.terms.len());
        let mut values = Vec::with_capacity(3 * problem.terms.len());
        for t in &problem.terms {
            let tau = t.tau;
            let (i, j) = (problem.position_row(t.i), problem.head_position_row(t));
            for a in [i, j].into_iter().flatten() {
                entries.push((a, a));
                values.push(tau);
            }
            if let (Some(i), Some(j)) = (i, j)
                && i != j
            {
                entries.push((i.min(j), i.max(j)));
                values.push(-tau);
            }
        }
        // Every pose's diagonal, so that a pose without edges makes L singular, not malformed.
        for a in 0..problem.positions() {
            entries.push((a, a));
            values.push(0.0);
        }
        let mut factor = anchored_llt(
            problem.positions(),
            &problem.anchored_order(),
            &entries,
            &values,
        )?;
        // Kept to the end of the solve for solves alone.
        factor.keep_solves_only();
        Some(OptimalPositions { factor })
    }

    /// Replaces the positions of `x` with the ones optimal for its rotations.
    pub fn apply(&mut self, problem: &Problem, x: &mut Point) {
        let (positions, p) = (problem.positions(), x.p);
        if positions == 0 {
            return;
        }
        // At ρ̃ = 0 the position rows of W̃x̃ are S̃r̃; then ρ̃ = −L⁻¹S̃r̃, solved in place in
        // −S̃r̃'s own memory. L is real: the real and imaginary parts of each column c (in the
        // row-major positions x p layout, as pairs of f64) are a positions x 2 real matrix of
        // row stride 2p, both solved in one pass over L's factor.
        x.x[..positions * p].fill(c64::new(0.0, 0.0));
        let mut g = problem.position_half_gradient(x);
        g.iter_mut().for_each(|v| *v = -*v);
        let parts: &mut [f64] = bytemuck::cast_slice_mut(&mut g);
        let stride = isize::try_from(2 * p).expect("a rank that fits memory");
        for c in 0..p {
            // SAFETY: entry (k, j) of column c's matrix is parts[2c + 2p·k + j], k < positions,
            // j < 2: at most 2c + 2p(positions − 1) + 1 < 2p·positions = parts.len() (c < p);
            // the entries are distinct, and `parts` is borrowed mutably for the view's life.
            let rhs = unsafe {
                faer::MatMut::from_raw_parts_mut(
                    parts.as_mut_ptr().add(2 * c),
                    positions,
                    2,
                    stride,
                    1,
                )
            };
            self.factor.solve_block_in_place(rhs);
        }
        x.x[..positions * p].copy_from_slice(&g);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::weights::{Weights, edge_weights};
    use crate::simulate::{SimulationConfig, simulate};

    /// ∂f/∂ρ̃ = 2(W̃x̃)_ρ = 0 at the positions optimal for the rotations (f is convex quadratic in
    /// ρ̃ with Hessian 2L ≻ 0), for a rank-1 and a rank-2 point with arbitrary rotations; and no
    /// other positions do better.
    #[test]
    fn optimal_positions_zero_the_position_gradient_at_every_rank() {
        let sim = simulate(&SimulationConfig {
            n: 40,
            seed: 3,
            loop_probability: 0.3,
            ..Default::default()
        });
        let w = edge_weights(&sim.graph, Weights::Isotropic).unwrap();
        let problem = Problem::new(&sim.graph, &w);
        let n = problem.n;
        let mut positions = OptimalPositions::new(&problem).unwrap();
        for p in [1, 2] {
            // Rows of unit norm for the rotations (any phases), arbitrary positions.
            let x: Vec<c64> = (0..(2 * n - 1) * p)
                .map(|k| {
                    let a = 0.7 * k as f64 + 0.3 * (k * k % 11) as f64;
                    let row = k / p;
                    let scale = if row < n - 1 {
                        5.0
                    } else {
                        1.0 / (p as f64).sqrt()
                    };
                    c64::new(a.cos(), a.sin()) * scale
                })
                .collect();
            let mut point = Point { p, x };
            positions.apply(&problem, &mut point);
            let g = problem.half_gradient(&point);
            let scale: f64 = g.iter().map(|z| z.norm()).fold(0.0, f64::max);
            let position_rows = g[..(n - 1) * p]
                .iter()
                .map(|z| z.norm())
                .fold(0.0, f64::max);
            assert!(
                position_rows <= 1e-10 * scale,
                "p = {p}: {position_rows} vs {scale}"
            );
            let best = problem.cost(&point);
            for k in 0..(n - 1) * p {
                let mut moved = point.clone();
                moved.x[k] += c64::new(1e-3, -1e-3);
                assert!(problem.cost(&moved) > best, "p = {p}, entry {k}");
            }
        }
    }
}
