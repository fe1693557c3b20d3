//! Initializations for the scalable solver (docs/method.md §3.2).
//!
//! - Chordal relaxation of the rotations: drop |r_i| = 1 and minimize the rotation part of the
//!   cost, Σ κ |r_j − R r_i|² = r* Q_κ r with r_0 = 1 (a sparse linear least-squares problem whose
//!   normal equations are the anchored connection Laplacian), then normalize each r_i. On a tree
//!   or a balanced graph this is exact (Appendix 8.1: the measurements compose consistently).
//! - Gauss-Newton on the rotations' angles ([`refine_rotations`]), where the chordal rotations
//!   are visibly off the minimum of the rotation part of the cost (graphs with noisy rotations).
//! - Positions optimal for given rotations: ρ̃ = −L⁻¹ S̃ r̃ (eq. (24)), by a sparse Cholesky of the
//!   anchored Laplacian L.

use crate::linalg::factor::{Layout, Permuted, SparseFactor};
use crate::linalg::laplacian::{anchored_laplacian, anchored_llt};
use crate::problem::matrix::for_each_entry;
use crate::problem::rank_p::{EdgeTerm, Point, Problem};
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

/// Gauss-Newton on the angles of the rotation part of f, Σ κ |r_j − r_i R_e|² = Σ 2κ (1 − cos e)
/// with e = arg(r̄_j r_i R_e), from `r` (the chordal rotations, r_0 = 1 held), where the chordal
/// rotations are visibly off that part's own minimum: the chordal relaxation drops |r_i| = 1 and
/// normalizes afterwards, which on graphs with noisy rotations leaves them far from it, and Newton
/// on the whole problem then spends its steps there. Each step turns r_i by e^{iδ_i}, δ solving
/// G δ = −∇ for the Gauss-Newton matrix G = Σ 2κ (e_i − e_j)(e_i − e_j)ᵀ (the exact Hessian's
/// weights 2κ cos e taken at e = 0: the anchored κ-weighted Laplacian, positive definite on a
/// connected graph), the same at every step: one factorization in all. With z = r̄_j r_i R_e of
/// unit modulus, cos e = Re z and sin e = Im z: the cost 2κ(1 − Re z) and its gradient ±2κ Im z
/// need no trigonometry.
///
/// The refinement runs only where the Jacobi estimate of the first step's gain, ½ Σ ∇_k²/G_kk,
/// is at least [`ROTATION_GATE`] of the rotation cost (else the rotations are returned as they
/// are, for the price of one pass over the edges). A step is halved until the cost falls; the
/// refinement stops once a step gains less than [`ROTATION_GAIN`] of the cost, after
/// [`ROTATION_STEPS`] steps, or at once where G cannot be factored (poses joined only through
/// landmarks). Newton steps to the certified optimum from the chordal rotations against from
/// these: M3500c 12 to 7, M3500a 7 to 5, M3500b 9 to 8 (the same optima to 1e-14 relative);
/// whole process (20 interleaved pairs, twice) 0.76, 0.88 and 0.95-0.97 of the time.
pub fn refine_rotations(problem: &Problem, r: Vec<c64>) -> Vec<c64> {
    let n = problem.n;
    if n < 2 || r.len() != n {
        return r;
    }
    let edges: Vec<&EdgeTerm> = problem.terms.iter().filter(|t| !t.landmark).collect();
    // The cost and its gradient in the angles (every pose's; r_0's is not used).
    let evaluate = |r: &[c64]| {
        let mut cost = 0.0;
        let mut gradient = vec![0.0; n];
        for t in &edges {
            let z = r[t.j].conj() * r[t.i] * t.rot;
            cost += 2.0 * t.kappa * (1.0 - z.re);
            let g = 2.0 * t.kappa * z.im;
            gradient[t.i] += g;
            gradient[t.j] -= g;
        }
        (cost, gradient)
    };
    let (mut cost, mut gradient) = evaluate(&r);
    let mut diagonal = vec![0.0; n];
    for t in &edges {
        diagonal[t.i] += 2.0 * t.kappa;
        diagonal[t.j] += 2.0 * t.kappa;
    }
    let jacobi: f64 = (1..n)
        .filter(|&k| diagonal[k] > 0.0)
        .map(|k| 0.5 * gradient[k] * gradient[k] / diagonal[k])
        .sum();
    // Also false for a NaN cost or gradient.
    let worth_it = jacobi >= ROTATION_GATE * cost;
    if !worth_it {
        return r;
    }
    // G over r_1..r_{n−1} at 0..n−2 (r_0 held: its edges add to the diagonal only).
    let (entries, values) = anchored_laplacian(
        edges
            .iter()
            .map(|t| (t.i.checked_sub(1), t.j.checked_sub(1), 2.0 * t.kappa)),
    );
    let Some(mut factor) = anchored_llt(n - 1, &problem.rotation_order(), &entries, &values) else {
        return r;
    };
    let mut r = r;
    for _ in 0..ROTATION_STEPS {
        let mut delta: Vec<f64> = gradient[1..].iter().map(|g| -g).collect();
        factor.solve_in_place(&mut delta);
        let turned = |alpha: f64| -> Vec<c64> {
            std::iter::once(r[0])
                .chain(r[1..].iter().zip(&delta).map(|(z, d)| {
                    let (s, c) = (alpha * d).sin_cos();
                    z * c64::new(c, s)
                }))
                .collect()
        };
        let Some((trial, (trial_cost, trial_gradient))) = (0..ROTATION_HALVINGS)
            .map(|h| {
                let trial = turned(0.5f64.powi(h));
                let e = evaluate(&trial);
                (trial, e)
            })
            .find(|(_, (c, _))| *c < cost)
        else {
            break;
        };
        let gain = cost - trial_cost;
        (r, cost, gradient) = (trial, trial_cost, trial_gradient);
        if gain <= ROTATION_GAIN * cost {
            break;
        }
    }
    r
}

/// The Jacobi estimate of the first step's gain, relative to the rotation cost, from which
/// [`refine_rotations`] refines. On the public planar files: M3500c 3.2e-2, M3500b 1.5e-2,
/// M3500a 2.5e-3 (those whose Newton steps the refinement saves), every other one 1.6e-4 (MIT)
/// or less.
pub const ROTATION_GATE: f64 = 1e-3;

/// The relative gain below which [`refine_rotations`] stops (after 2 to 4 steps on the files it
/// refines: M3500c's gain 1.2e-1, 2.6e-4, 1.8e-6, 5.1e-8 of the cost).
pub const ROTATION_GAIN: f64 = 1e-6;

/// The most steps of [`refine_rotations`].
pub const ROTATION_STEPS: usize = 10;

/// The most halvings of a step of [`refine_rotations`] before it stops.
const ROTATION_HALVINGS: i32 = 8;

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
        let (mut entries, mut values) = anchored_laplacian(problem.terms.iter().map(|t| {
            (
                problem.position_row(t.i),
                problem.head_position_row(t),
                t.tau,
            )
        }));
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

    /// A cycle of m poses whose rotation measurements fail to close by E: the rotation part's
    /// minimum spreads E evenly, every edge's residual e = E/m (by hand: minimize Σ 2κ(1 − cos
    /// e_k) subject to Σ e_k = E, all κ equal). From the odometry's rotations (the whole E on the
    /// closing edge) the refinement ends there, r_0 held; rotations already at that minimum are
    /// returned unchanged (the gate), as are those of a cycle that closes.
    #[test]
    fn refined_rotations_spread_a_cycle_s_error_evenly() {
        use crate::graph::{Edge, Pose2, PoseGraph, SymMat3};
        let (m, closing_error) = (12, 0.6);
        let step = std::f64::consts::TAU / m as f64;
        let graph = |error: f64| {
            let edges = (0..m)
                .map(|k| Edge {
                    i: k,
                    j: (k + 1) % m,
                    measurement: Pose2::new(1.0, 0.0, step + if k == 3 { error } else { 0.0 }),
                    noise: SymMat3::IDENTITY,
                })
                .collect();
            PoseGraph::with_edges(vec![Pose2::IDENTITY; m], edges)
        };
        // The residual of each edge, e = arg(r̄_j r_i R_e), with the library's atan2.
        let residuals = |problem: &Problem, r: &[c64]| -> Vec<f64> {
            problem
                .terms
                .iter()
                .map(|t| {
                    let z = r[t.j].conj() * r[t.i] * t.rot;
                    z.im.atan2(z.re)
                })
                .collect()
        };
        let odometry = |problem: &Problem| -> Vec<c64> {
            // r_{k+1} = r_k R_k along the cycle from r_0 = 1: every residual 0 but the closing
            // edge's, which carries E.
            let mut r = vec![c64::new(1.0, 0.0); m];
            for k in 0..m - 1 {
                let t = problem
                    .terms
                    .iter()
                    .find(|t| t.i == k && t.j == k + 1)
                    .unwrap();
                r[k + 1] = r[k] * t.rot;
            }
            r
        };
        let g = graph(closing_error);
        let w = edge_weights(&g, Weights::Unit).unwrap();
        let problem = Problem::new(&g, &w);
        let start = odometry(&problem);
        let before = residuals(&problem, &start);
        assert!((before.iter().sum::<f64>() - closing_error).abs() < 1e-12);
        assert!(before.iter().any(|e| (e - closing_error).abs() < 1e-12));
        let refined = refine_rotations(&problem, start.clone());
        assert_eq!(refined[0], start[0], "r_0 is held");
        for e in residuals(&problem, &refined) {
            assert!(
                (e - closing_error / m as f64).abs() < 1e-7,
                "{e} against {}",
                closing_error / m as f64
            );
        }
        // Already at the minimum: the gate returns the rotations untouched.
        assert_eq!(refine_rotations(&problem, refined.clone()), refined);
        // A cycle that closes: the odometry is the minimum (cost 0), nothing to refine.
        let closed = Problem::new(&graph(0.0), &w);
        let start = odometry(&closed);
        assert_eq!(refine_rotations(&closed, start.clone()), start);
    }

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
