//! Initializations for the scalable solver (DESIGN.md §3.2).
//!
//! - Chordal relaxation of the rotations: drop |r_i| = 1 and minimize the rotation part of the
//!   cost, Σ κ |r_j − R r_i|² = r* Q_κ r with r_0 = 1 (a sparse linear least-squares problem whose
//!   normal equations are the anchored connection Laplacian), then normalize each r_i. On a tree
//!   or a balanced graph this is exact (Appendix 8.1: the measurements compose consistently).
//! - Positions optimal for given rotations: ρ̃ = −L⁻¹ S̃ r̃ (eq. (24)), by a sparse Cholesky of the
//!   anchored Laplacian L.

use crate::factor::{Assembly, SparseFactor};
use crate::manifold::{Point, Problem};
use faer::c64;

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
    for t in &problem.terms {
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
    let mut assembly = Assembly::<c64>::new(n - 1, &entries);
    assembly.fill(&values);
    let mut factor = SparseFactor::analyze(assembly.matrix.symbolic());
    factor.llt(assembly.matrix.as_ref()).ok()?;
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

/// The rank-1 point [ρ̃; r̃] with the given rotations and the positions optimal for them.
/// `None` if the graph is not connected.
pub fn with_optimal_positions(problem: &Problem, r: &[c64]) -> Option<Point> {
    let n = problem.n;
    let mut x = Point {
        p: 1,
        x: vec![c64::new(0.0, 0.0); n - 1]
            .into_iter()
            .chain(r.iter().copied())
            .collect(),
    };
    if n == 1 {
        return Some(x);
    }
    // At ρ̃ = 0 the position rows of W̃x̃ are S̃r̃; then ρ̃ = −L⁻¹S̃r̃.
    let g = problem.half_gradient(&x);
    let mut rhs: Vec<c64> = g[..n - 1].iter().map(|z| -z).collect();
    let mut entries = Vec::with_capacity(3 * problem.terms.len());
    let mut values = Vec::with_capacity(3 * problem.terms.len());
    for t in &problem.terms {
        let tau = c64::new(t.tau, 0.0);
        let (i, j) = (t.i.checked_sub(1), t.j.checked_sub(1));
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
    let mut assembly = Assembly::<c64>::new(n - 1, &entries);
    assembly.fill(&values);
    let mut factor = SparseFactor::analyze(assembly.matrix.symbolic());
    factor.llt(assembly.matrix.as_ref()).ok()?;
    factor.solve_in_place(&mut rhs);
    x.x[..n - 1].copy_from_slice(&rhs);
    Some(x)
}
