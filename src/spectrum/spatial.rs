//! Spectra of a 3D graph (issue 15): the smallest eigenvalues of SE-Sync's data matrix Q, of the
//! certificate matrix S = Q − blkdiag(0, Λ) at the solved estimate, and of the rotation-only
//! matrix M, and the count of eigenvalues of S at zero: the 3D counterparts of W̃, W̃(λ*), M and
//! the SZEP of [`super::sparse`].
//!
//! Rosen, Carlone, Bandeira, Leonard, "SE-Sync", IJRR 2019. With X = [t; Y] (the translations
//! but the anchor's, then the rows of each Y_iᵀ; [`crate::se3::problem`]'s layout), SE-Sync's
//! objective is f(X) = tr(XᵀQX) with, edge by edge (its Sec. 4.1: M = [[L(W^τ), Ṽ],
//! [Ṽᵀ, L(G̃^ρ) + Σ̃]], here anchored and in pgo's row order),
//!
//! ```text
//! xᵀQx = Σ_(i,j) τ_ij (t_j − t_i − t̃_ijᵀ y_i)² + κ_ij ‖y_j − R̃_ijᵀ y_i‖²
//! ```
//!
//! for one column x = [t; y] (t_i a scalar, y_i ∈ ℝ³ the column's entries on Y_iᵀ's rows).
//! The matrices:
//!
//! - **Q**, the analogue of the planar W̃ (eq. (24)). It is positive semidefinite; on a
//!   noise-free connected graph its null space is the global rotation: the three columns of the
//!   true X (the translation gauge is fixed by the anchor).
//! - **S = Q − blkdiag(0, Λ)**, Λ_i = sym((QX)_i X_iᵀ) at the solved estimate X (SE-Sync eq.
//!   (48): Λ = SymBlockDiag(XᵀQX) in its layout), the analogue of W̃(λ*). SE-Sync's Theorem 7:
//!   X is a global optimum (and the relaxation exact) when S ⪰ 0; then SX = 0, so S has (at
//!   least) three eigenvalues at zero, X's columns. "Exactly three" is the 3D single zero
//!   eigenvalue property.
//! - **M = Q_YY − Q_Yt L⁻¹ Q_tY** (L the anchored τ-weighted Laplacian, Q's translation block):
//!   the translations eliminated, SE-Sync's data matrix Q̃ of its rotation-only problem
//!   (Problem 4), the analogue of the planar M (eq. (38)). As there it is never formed: its
//!   eigenvalues are those of the pencil (Q, blkdiag(0, I)).
//!
//! Each component is solved by [`crate::se3::solve_graph3`] (pgo-solve's staircase with its
//! default options), then the K smallest eigenvalues of each matrix are computed sparse, as the
//! planar ones at scale ([`super::sparse_spectra`]): one sparse LLᴴ of A + σB per matrix and
//! shift-invert subspace iteration ([`crate::linalg::subspace`], the real matrices in its
//! Hermitian solver, imaginary parts zero), with Rayleigh-Ritz values computed edge by edge from
//! the residuals (the quadratic form above), so that small eigenvalues keep their relative
//! accuracy.
//!
//! **How zeros are counted** (`near_zero`): the certificate's deflated count
//! ([`crate::se3::certificate`]) where its deflated proof holds: one LDLᵀ's inertia proves
//! λ₄(S) ≥ θ > 0 (at most three eigenvalues below the gap θ), X's columns give XᵀSX ≈ 0, so
//! λ₃(S) ≤ 0 up to rounding (Courant-Fischer), and Lehmann-Maehly's bound gives λ₁(S) ≥ −η:
//! exactly three eigenvalues in [−η, 0], the fourth at least θ. Without that proof (a saddle, a
//! relaxation that is not exact, a gap the rounding hides), the computed eigenvalues of S at most
//! the planar zero threshold ([`crate::certify::szep`]'s rule): 1000 times the larger of the
//! gap cost − lower bound and the rounding allowance dim·u·‖Q‖_F, and at least 1e-12 of Q's
//! largest diagonal entry. `szep` is true exactly when the deflated proof counted three.

use super::sparse::SparseSpectra;
use super::{SPARSE_DEFAULT_COUNT, SPARSE_MAX_COUNT, smallest};
use crate::certify::szep::ZERO_FACTOR;
use crate::error::Error;
use crate::graph3::Graph3;
use crate::linalg::subspace::{Pencil, SubspaceOptions, smallest_eigenvalues};
use crate::problem::weights::Weights;
use crate::se3::problem::{Problem3, weights3};
use crate::se3::rounding::point_of;
use crate::se3::{Options3, anchor_of, check3, components3, solve_graph3};
use faer::{Mat, c64};
use serde::Serialize;

/// The spectra of one connected component of a 3D graph.
#[derive(Debug, Serialize)]
pub struct ComponentSpectrum3 {
    pub first_id: u32,
    pub poses: usize,
    pub edges: usize,
    /// The smallest eigenvalues of Q, ascending.
    pub eigenvalues: Vec<f64>,
    /// The smallest eigenvalues of S = Q − blkdiag(0, Λ) at the solved estimate, ascending.
    pub penalized_eigenvalues: Vec<f64>,
    /// The smallest eigenvalues of M = Q_YY − Q_Yt L⁻¹ Q_tY, ascending.
    pub rotation_eigenvalues: Vec<f64>,
    /// Eigenvalues of S at zero (module docs: how they are counted).
    pub near_zero: usize,
    /// The certificate's deflated proof counted exactly three eigenvalues of S at zero.
    pub szep: bool,
    /// Σ_i tr Λ_i, the dual value of the multipliers (the planar d* = Σλ*).
    pub dual_objective: f64,
    /// The proven lower bound on f* (pgo-solve's `lower_bound`: Σ tr Λ_i − 3nη).
    pub lower_bound: f64,
    /// Whether the certificate proved the estimate optimal within 1e-6 relative (pgo-solve's
    /// `certified`).
    pub certified: bool,
    /// Whether the three subspace iterations converged; if not, the eigenvalues are upper
    /// bounds.
    #[serde(skip)]
    pub eigen_converged: bool,
}

/// What `pgo-spectrum --json` prints for a 3D graph; lists are ascending.
#[derive(Debug, Serialize)]
pub struct Spectrum3 {
    /// 3.
    pub dimension: u8,
    pub weights: Weights,
    pub poses: usize,
    pub edges: usize,
    /// Eigenvalues of Q (all components merged).
    pub eigenvalues: Vec<f64>,
    /// Eigenvalues of S.
    pub penalized_eigenvalues: Vec<f64>,
    /// Eigenvalues of M.
    pub rotation_eigenvalues: Vec<f64>,
    /// Eigenvalues of S at zero, summed over components.
    pub near_zero: usize,
    /// Every component's S has exactly three eigenvalues at zero, proven.
    pub szep: bool,
    /// Every component is certified.
    pub certified: bool,
    pub components: Vec<ComponentSpectrum3>,
}

/// The spectra of Q, S and M of every connected component of a 3D graph and merged: the
/// `count` smallest of each ([`SPARSE_DEFAULT_COUNT`] with 0, at most [`SPARSE_MAX_COUNT`]), at
/// the estimate of [`solve_graph3`].
///
/// # Errors
///
/// `count` above [`SPARSE_MAX_COUNT`]; the graphs [`check3`] refuses; information matrices
/// without isotropic weights; entries of Q that overflow.
pub fn spectrum3(graph: &Graph3, weights: Weights, count: usize) -> crate::Result<Spectrum3> {
    let count = match count {
        0 => SPARSE_DEFAULT_COUNT,
        k if k > SPARSE_MAX_COUNT => {
            return Err(Error::Invalid(format!(
                "-k {k} is more than the {SPARSE_MAX_COUNT} smallest eigenvalues computed for 3D graphs"
            )));
        }
        k => k,
    };
    let parts = components3(graph);
    check3(graph, &parts)?;
    let unit = weights == Weights::Unit;
    let mut components = Vec::new();
    for (part, _) in &parts {
        let w = weights3(part, unit)?;
        crate::progress::phase("staircase (SE(3), for Λ)");
        let solution = solve_graph3(part, &w, &Options3::default(), &mut |_| {});
        let problem = Problem3::new(part, &w, anchor_of(part));
        let point = point_of(&problem, &solution.poses);
        let ev = problem.evaluate(&point);
        let lambda = problem.multipliers(&point, &ev.qx);
        crate::progress::phase("eigenvalues");
        let spectra = sparse_spectra3(&problem, &lambda, count)?;
        let deflated = solution.bound.and_then(|b| b.deflated);
        let near_zero = match deflated {
            Some(d) if d > 0 => d,
            _ => {
                let gap = (solution.cost - solution.lower_bound).max(0.0);
                let threshold = zero_threshold3(&problem, gap);
                spectra
                    .penalized_eigenvalues
                    .iter()
                    .take_while(|&&v| v <= threshold)
                    .count()
            }
        };
        let dual_objective = lambda
            .iter()
            .map(|l| l[0][0] + l[1][1] + l[2][2])
            .fold(0.0, |a, b| a + b);
        components.push(ComponentSpectrum3 {
            first_id: part.ids[0],
            poses: part.num_poses(),
            edges: part.edges.len(),
            eigenvalues: spectra.eigenvalues,
            penalized_eigenvalues: spectra.penalized_eigenvalues,
            rotation_eigenvalues: spectra.rotation_eigenvalues,
            near_zero,
            szep: deflated == Some(3),
            dual_objective,
            lower_bound: solution.lower_bound,
            certified: solution.certified,
            eigen_converged: spectra.converged,
        });
    }
    let merge = |f: fn(&ComponentSpectrum3) -> &Vec<f64>| {
        smallest(
            components
                .iter()
                .flat_map(|c| f(c).iter().copied())
                .collect(),
            count,
        )
    };
    Ok(Spectrum3 {
        dimension: 3,
        weights,
        poses: graph.num_poses(),
        edges: graph.edges.len(),
        eigenvalues: merge(|c| &c.eigenvalues),
        penalized_eigenvalues: merge(|c| &c.penalized_eigenvalues),
        rotation_eigenvalues: merge(|c| &c.rotation_eigenvalues),
        near_zero: components.iter().map(|c| c.near_zero).sum(),
        szep: components.iter().all(|c| c.szep),
        certified: components.iter().all(|c| c.certified),
        components,
    })
}

/// The zero threshold of [`crate::certify::szep::zero_threshold`] for Q: ZERO_FACTOR times the
/// larger of `gap` and dim·u·‖Q‖_F, at least 1e-12 of Q's largest diagonal entry (and of 1).
fn zero_threshold3(problem: &Problem3, gap: f64) -> f64 {
    let mut max_diag = 1.0f64;
    let mut fro2 = 0.0;
    for (r, c, v, _) in problem.upper() {
        if r == c {
            max_diag = max_diag.max(v);
            fro2 += v * v;
        } else {
            fro2 += 2.0 * v * v;
        }
    }
    let rounding = problem.dim() as f64 * f64::EPSILON * fro2.sqrt();
    (ZERO_FACTOR * gap.abs().max(rounding)).max(1e-12 * max_diag)
}

/// The `count` smallest eigenvalues of Q, of S = Q − blkdiag(0, Λ) (`lambda`: Λ_i, one 3x3
/// symmetric block per pose) and of M (the pencil (Q, blkdiag(0, I)) on the rotation rows) of a
/// connected 3D problem, by shift-invert subspace iteration (module docs). At most as many as the
/// matrix has rows.
pub fn sparse_spectra3(
    problem: &Problem3,
    lambda: &[[[f64; 3]; 3]],
    count: usize,
) -> Result<SparseSpectra, Error> {
    assert_eq!(lambda.len(), problem.n, "one Λ_i per pose");
    let dim = problem.dim();
    let translations = problem.n - 1;
    let overflow = || {
        Error::Invalid(
            "the data matrix Q has entries that overflow a 64-bit float: the weighted squared translations of the edges at one pose add up to more than 1.8e308".into(),
        )
    };
    if lambda.iter().flatten().flatten().any(|l| !l.is_finite()) {
        return Err(Error::Invalid(
            "the multipliers Λ are not all finite".into(),
        ));
    }
    let q: Vec<(usize, usize, c64)> = problem
        .upper()
        .into_iter()
        .map(|(r, c, v, _)| (r, c, c64::new(v, 0.0)))
        .collect();
    // Λ_i[a][b] sits at rows (rotation_row(i, a), rotation_row(i, b)), within Q's stored
    // 3x3 rotation block of pose i (every pose's full block is stored).
    let penalized: Vec<(usize, usize, c64)> = q
        .iter()
        .map(|&(r, c, v)| {
            if r >= translations && c >= translations {
                let (i, a) = ((r - translations) / 3, (r - translations) % 3);
                let (j, b) = ((c - translations) / 3, (c - translations) % 3);
                if i == j {
                    return (r, c, v - c64::new(lambda[i][a][b], 0.0));
                }
            }
            (r, c, v)
        })
        .collect();
    let order = problem.row_order();
    let options = SubspaceOptions::default();
    let q_form = |z: &Mat<c64>| edge_form3(problem, None, z);
    let s_form = |z: &Mat<c64>| edge_form3(problem, Some(lambda), z);
    let pencil = |upper, rows, form| Pencil {
        dim,
        upper,
        rows,
        order: &order,
        form: Some(form),
    };
    let qv = smallest_eigenvalues(&pencil(&q, 0..dim, &q_form), count, &options)
        .map_err(|_| overflow())?;
    let sv = smallest_eigenvalues(&pencil(&penalized, 0..dim, &s_form), count, &options)
        .map_err(|_| overflow())?;
    let mv = smallest_eigenvalues(&pencil(&q, translations..dim, &q_form), count, &options)
        .map_err(|_| overflow())?;
    Ok(SparseSpectra {
        converged: qv.converged && sv.converged && mv.converged,
        eigenvalues: qv.values,
        penalized_eigenvalues: sv.values,
        rotation_eigenvalues: mv.values,
    })
}

/// Z*QZ for a block Z (N x b), edge by edge (module docs: x*Qx = f at x):
/// Σ_e τ ε_t*ε_t + κ Σ_b ε_b*ε_b with the residual rows ε_t = z_{t_j} − z_{t_i} − Σ_a t̃_a z_{y_ia}
/// and ε_b = z_{y_jb} − Σ_a R̃_ab z_{y_ia} (the anchor's translation row absent: 0), less
/// Σ_i Σ_ab z_{y_ia}* Λ_i[a][b] z_{y_ib} for S. Formed from differences, as the planar
/// [`super::sparse`]'s form: the small eigenvalues keep their relative accuracy.
fn edge_form3(problem: &Problem3, lambda: Option<&[[[f64; 3]; 3]]>, z: &Mat<c64>) -> Mat<c64> {
    let b = z.ncols();
    let zero = c64::new(0.0, 0.0);
    let mut h = Mat::<c64>::zeros(b, b);
    let mut et = vec![zero; b];
    let mut er = vec![[zero; 3]; b];
    for t in &problem.terms {
        let (pi, pj) = (problem.position_row(t.i), problem.position_row(t.j));
        let yi = |a: usize| problem.rotation_row(t.i, a);
        let yj = |a: usize| problem.rotation_row(t.j, a);
        for c in 0..b {
            let p = |row: Option<usize>| row.map_or(zero, |r| z[(r, c)]);
            let mut e = p(pj) - p(pi);
            for a in 0..3 {
                e -= z[(yi(a), c)] * t.t[a];
            }
            et[c] = e;
            for bb in 0..3 {
                let mut e = z[(yj(bb), c)];
                for a in 0..3 {
                    e -= z[(yi(a), c)] * t.r[a][bb];
                }
                er[c][bb] = e;
            }
        }
        for c in 0..b {
            for a in 0..b {
                let mut v = et[a].conj() * et[c] * t.tau;
                for (ea, ec) in er[a].iter().zip(&er[c]) {
                    v += ea.conj() * ec * t.kappa;
                }
                h[(a, c)] += v;
            }
        }
    }
    if let Some(lambda) = lambda {
        for (i, l) in lambda.iter().enumerate() {
            for c in 0..b {
                for a in 0..b {
                    let mut v = zero;
                    for (ra, row) in l.iter().enumerate() {
                        let za = z[(problem.rotation_row(i, ra), a)].conj();
                        for (rb, &lv) in row.iter().enumerate() {
                            v += za * z[(problem.rotation_row(i, rb), c)] * lv;
                        }
                    }
                    h[(a, c)] -= v;
                }
            }
        }
    }
    h
}
