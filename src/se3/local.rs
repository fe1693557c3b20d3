//! Local optimization at rank p: Riemannian Newton on St(3, p)^n × ℝ^{p(n−1)}, damped
//! Levenberg-Marquardt style (the trust region of SE-Sync's Algorithm 2 as a damping μ, updated
//! by Nielsen's rule from the ratio of actual to predicted decrease), as the planar
//! [`crate::staircase`] does it: the exact Riemannian Hessian 2 Bᵀ (S ⊗ I_p) B in an orthonormal
//! tangent basis B ([`super::stiefel`]), one symbolic sparse Cholesky per rank reused by every
//! step, and variable projection: every trial point takes the translations optimal for its
//! rotations (t = −L⁻¹ V Y, one solve with a Cholesky factor of the anchored τ-Laplacian L).
//!
//! The gauge: the anchor's translation is 0 and its rotation rows are held where they are (the
//! cost is invariant under X → X Gᵀ, G ∈ O(p), so nothing is lost), which leaves the Hessian
//! nonsingular at a nondegenerate minimum of rank 3.

use super::problem::{Point3, Problem3};
use super::stiefel::{polar_rows, tangent_basis};
use crate::linalg::block_system::{BlockSystem, DENSE_MAX_ROWS};
use crate::linalg::factor::{Assembly, SparseFactor};

/// One step, for progress reports.
#[derive(Debug, Clone, Copy)]
pub struct Step3 {
    pub rank: usize,
    pub iteration: usize,
    pub cost: f64,
    pub gradient_norm: f64,
    pub damping: f64,
}

/// The result of [`optimize`].
#[derive(Debug, Clone)]
pub struct Local3 {
    pub point: Point3,
    pub cost: f64,
    pub gradient_norm: f64,
    pub iterations: usize,
    pub converged: bool,
    /// Real multiply-adds of the Newton factorizations.
    pub work: f64,
    /// The Newton factor's values, for a factor that follows to reuse ([`SparseFactor::reuse`]).
    pub room: Vec<f64>,
}

/// QX by Q's blocks (no rounding bounds; for the solver's own use).
pub fn apply_q(problem: &Problem3, x: &Point3) -> Vec<f64> {
    // Compiled for the ranks the staircase meets most, as [`hessian`]'s blocks.
    match x.p {
        3 => apply_q_at::<3>(problem, x),
        4 => apply_q_at::<4>(problem, x),
        5 => apply_q_at::<5>(problem, x),
        _ => apply_q_at::<0>(problem, x),
    }
}

/// [`apply_q`] with p = `P` known at compile time (0: read from x).
#[inline(always)]
fn apply_q_at<const P: usize>(problem: &Problem3, x: &Point3) -> Vec<f64> {
    let p = if P > 0 { P } else { x.p };
    let mut out = vec![0.0; problem.dim() * p];
    for (k, &(u, v)) in problem.pairs.iter().enumerate() {
        let b = &problem.blocks[k];
        for la in 0..4 {
            let Some(ra) = problem.local_row(u, la) else {
                continue;
            };
            for lb in 0..4 {
                let Some(rb) = problem.local_row(v, lb) else {
                    continue;
                };
                let q = b[la][lb];
                if q == 0.0 {
                    continue;
                }
                for c in 0..p {
                    out[ra * p + c] += q * x.x[rb * p + c];
                }
                if u != v {
                    for c in 0..p {
                        out[rb * p + c] += q * x.x[ra * p + c];
                    }
                }
            }
        }
    }
    out
}

/// The translation rows of QX at X's translations zeroed, VY (the translations' rows of Q by the
/// rotation rows' columns times Y), handed to `add(row, column, value)` product by product: the
/// terms of [`apply_q`]'s sums for those rows, in its order, without its products by the zeroed
/// translations and its rotation rows (which the projection does not read: 6 of Q's 16 entries
/// per pair of poses).
fn translation_rows_of_qy(problem: &Problem3, x: &Point3, mut add: impl FnMut(usize, usize, f64)) {
    let p = x.p;
    for (k, &(u, v)) in problem.pairs.iter().enumerate() {
        let b = &problem.blocks[k];
        // Row t_u by the rotation rows of v; for u ≠ v, row t_v by those of u (Q's symmetry).
        for (to, from, q) in [(u, v, b[0]), (v, u, [b[0][0], b[1][0], b[2][0], b[3][0]])] {
            let Some(r) = problem.position_row(to) else {
                continue;
            };
            for l in 1..4 {
                if q[l] == 0.0 {
                    continue;
                }
                let row = x.row(problem.rotation_row(from, l - 1));
                for c in 0..p {
                    add(r, c, q[l] * row[c]);
                }
            }
            if u == v {
                break;
            }
        }
    }
}

/// The Cholesky factor of the anchored τ-Laplacian, for the optimal translations.
pub struct Translations {
    factor: Option<LaplacianFactor>,
}

/// The anchored τ-Laplacian's factor: sparse, or dense up to [`DENSE_MAX_ROWS`] rows (a
/// [`BlockSystem`] of 1×1 blocks, for the reason the Newton systems have one: tinyGrid3D's whole
/// process 0.97-0.98 of the time with its 8 rows dense, 41 interleaved pairs in either order).
enum LaplacianFactor {
    Sparse(SparseFactor<f64>),
    Dense(BlockSystem),
}

impl Translations {
    pub fn new(problem: &Problem3) -> Self {
        let m = problem.n - 1;
        if m == 0 {
            return Translations { factor: None };
        }
        let entries = problem.laplacian();
        let pattern: Vec<(usize, usize)> = entries.iter().map(|&(r, c, _)| (r, c)).collect();
        let values: Vec<f64> = entries.iter().map(|e| e.2).collect();
        let factor = if m <= DENSE_MAX_ROWS {
            let order: Vec<usize> = (0..m).collect();
            let mut system =
                BlockSystem::new(&vec![1; m], &pattern, &order, f64::INFINITY, |_, _| {});
            system.fill(&values);
            system
                .llt()
                .is_ok()
                .then_some(LaplacianFactor::Dense(system))
        } else {
            let mut assembly = Assembly::<f64>::new(m, &pattern);
            assembly.fill(&values);
            let mut factor = SparseFactor::<f64>::analyze(assembly.matrix.symbolic());
            let ok = factor.llt(assembly.matrix.as_ref()).is_ok();
            // Kept to the end of the solve for solves alone.
            factor.keep_solves_only();
            ok.then_some(LaplacianFactor::Sparse(factor))
        };
        Translations { factor }
    }

    /// Sets the translations of `x` optimal for its rotations.
    pub fn project(&mut self, problem: &Problem3, x: &mut Point3) {
        let Some(factor) = self.factor.as_mut() else {
            return;
        };
        let (m, p) = (problem.n - 1, x.p);
        // Column-major right-hand sides −(V Y).
        let mut rhs = vec![0.0; m * p];
        translation_rows_of_qy(problem, x, |r, c, v| rhs[c * m + r] -= v);
        match factor {
            LaplacianFactor::Sparse(factor) => factor
                .solve_block_in_place(faer::MatMut::from_column_major_slice_mut(&mut rhs, m, p)),
            LaplacianFactor::Dense(system) => {
                for column in rhs.chunks_mut(m) {
                    let solved = system.solve(|k| column[k]);
                    column.copy_from_slice(&solved);
                }
            }
        }
        for r in 0..m {
            for c in 0..p {
                x.x[r * p + c] = rhs[c * m + r];
            }
        }
    }
}

/// The Newton system's layout at rank p: coordinates pose by pose (p translation coordinates
/// unless the anchor, then 3p − 6 rotation ones unless the anchor), its pattern analyzed once.
pub struct System {
    p: usize,
    offset: Vec<usize>,
    dims: Vec<usize>,
    /// H + μD and its factorization ([`BlockSystem`]: 32-bit indices where they fit).
    system: BlockSystem,
    /// Index of the first value of each pair's block in the value list.
    diagonal: Vec<usize>,
    count: usize,
}

impl System {
    /// The system of rank p (its pattern depends on p and the graph alone).
    pub fn new(problem: &Problem3, p: usize) -> Self {
        Self::announcing(problem, p, |_, _| ())
    }

    /// [`System::new`], telling `counted` the dimension and the factor's number of values once
    /// its analysis knows them ([`BlockSystem::new`]).
    pub fn announcing(problem: &Problem3, p: usize, counted: impl FnOnce(usize, usize)) -> Self {
        let n = problem.n;
        let dims: Vec<usize> = (0..n)
            .map(|u| {
                if u == problem.anchor {
                    0
                } else {
                    p + 3 * p - 6
                }
            })
            .collect();
        let mut offset = vec![0; n + 1];
        for u in 0..n {
            offset[u + 1] = offset[u] + dims[u];
        }
        let dim = offset[n];
        // The entries, pair by pair: the coordinates of u by those of v (a ≤ b when u = v).
        let mut count = 0;
        let mut diagonal = vec![usize::MAX; dim];
        for &(u, v) in &problem.pairs {
            for a in 0..dims[u] {
                for b in 0..dims[v] {
                    if u == v && b < a {
                        continue;
                    }
                    if u == v && a == b {
                        diagonal[offset[u] + a] = count;
                    }
                    count += 1;
                }
            }
        }
        // Poses in the fill-reducing order, each pose's coordinates together.
        let poses = problem.pose_order();
        // Supernodal, assembled directly in its elimination order and triangle (factored without
        // a permuted copy), as the planar systems: with 6x6 pose blocks these have flop ratios of
        // 27 to 199 on the public 3D files (9 on tinyGrid3D's 9 poses). By our own code
        // ([`SparseFactor::prepare_own_factorization`]); where it does not split, on one core
        // with the narrow supernodes by loops: smallGrid3D 0.96 of faer's time whole process (41
        // interleaved runs), tinyGrid3D 1.00.
        let system = BlockSystem::new(
            &dims,
            &problem.pairs,
            &poses,
            SPLIT_FACTOR_MIN_WORK,
            counted,
        );
        System {
            p,
            offset,
            dims,
            system,
            diagonal,
            count,
        }
    }

    /// The solution of the last factorization's system for b, b's coordinate k given by `b(k)`
    /// (coordinates in the pose order; [`BlockSystem::solve`]).
    fn solve(&mut self, b: impl Fn(usize) -> f64) -> Vec<f64> {
        self.system.solve(b)
    }

    fn dim(&self) -> usize {
        *self.offset.last().unwrap()
    }

    /// The number of values of its factor (the room of [`crate::linalg::heap::Room`]).
    pub fn values_len(&self) -> usize {
        self.system.values_len()
    }

    /// Whether its factorizations split themselves between the cores.
    pub fn splits_factorizations(&self) -> bool {
        self.system.splits_factorizations()
    }
}

/// [`pose_basis`] of every pose, the two halves of the poses on two cores where the second is
/// idle.
fn pose_bases(problem: &Problem3, x: &Point3) -> Vec<Vec<f64>> {
    let (mut lower, upper) = crate::linalg::parallel::halves(problem.n, SPLIT_POSES, |poses| {
        poses
            .map(|u| pose_basis(problem, x, u, x.p))
            .collect::<Vec<_>>()
    });
    lower.extend(upper);
    lower
}

/// The dense basis of one pose's coordinates over its 4p entries (translation row, then the
/// three rotation rows): column-major, 4p × dims[u].
fn pose_basis(problem: &Problem3, x: &Point3, u: usize, p: usize) -> Vec<f64> {
    if u == problem.anchor {
        return Vec::new();
    }
    let d = 4 * p - 6;
    let mut b = vec![0.0; 4 * p * d];
    for c in 0..p {
        b[c * 4 * p + c] = 1.0;
    }
    let r0 = problem.rotation_row(u, 0);
    let tb = tangent_basis(&x.x[r0 * p..(r0 + 3) * p], p);
    for k in 0..3 * p - 6 {
        let col = p + k;
        b[col * 4 * p + p..(col + 1) * 4 * p].copy_from_slice(&tb[k * 3 * p..(k + 1) * 3 * p]);
    }
    b
}

/// The multipliers Λ_i (3x3) at x from QX.
fn lambda_blocks(problem: &Problem3, x: &Point3, qx: &[f64]) -> Vec<[[f64; 3]; 3]> {
    problem.multipliers(x, qx)
}

/// S's block of pose pair k (u, v): Q's, less Λ_u in the rotation rows where u = v.
fn s_block(problem: &Problem3, lambda: &[[[f64; 3]; 3]], k: usize) -> [[f64; 4]; 4] {
    let (u, v) = problem.pairs[k];
    let mut s = problem.blocks[k];
    if u == v {
        for a in 0..3 {
            for b in 0..3 {
                s[1 + a][1 + b] -= lambda[u][a][b];
            }
        }
    }
    s
}

/// One pose pair's block of the Hessian 2 B_uᵀ (S_uv ⊗ I_p) B_v.
struct PairBlock<'a> {
    s: &'a [[f64; 4]; 4],
    bu: &'a [f64],
    bv: &'a [f64],
    du: usize,
    dv: usize,
    /// u = v: the upper triangle only.
    diagonal: bool,
}

impl PairBlock<'_> {
    /// Appends the block's values (row by row, a ≤ b on the diagonal) to `values`; `P` is p
    /// where it is known at compile time, else 0 (then `p` is read).
    ///
    /// Each entry is the sum Σ_i B_u[i, a] K[i, b] taken in the order of i, K = (S_uv ⊗ I_p) B_v
    /// with each of its entries summed in the order of S's columns (zeros of S skipped): the
    /// entries of one row of the block are accumulated side by side (K stored row-major for it),
    /// which lets them share vector registers without reordering any sum.
    #[inline(always)]
    fn values<const P: usize>(&self, p: usize, k: &mut Vec<f64>, values: &mut Vec<f64>) {
        let p = if P > 0 { P } else { p };
        let (w, dv) = (4 * p, self.dv);
        debug_assert!(P == 0 || (self.du == 4 * P - 6 && dv == 4 * P - 6));
        let dv = if P > 0 { 4 * P - 6 } else { dv };
        let du = if P > 0 { 4 * P - 6 } else { self.du };
        // K (4p × dv, row-major), row (la, c) = Σ_lb S[la][lb] B_v[(lb, c)].
        k.clear();
        k.resize(w * dv, 0.0);
        for la in 0..4 {
            for lb in 0..4 {
                let q = self.s[la][lb];
                if q != 0.0 {
                    for c in 0..p {
                        let row = &mut k[(la * p + c) * dv..(la * p + c + 1) * dv];
                        for (b, out) in row.iter_mut().enumerate() {
                            *out += q * self.bv[b * w + lb * p + c];
                        }
                    }
                }
            }
        }
        // The empty sum (f64's `Sum` starts from it), so that each entry is the iterator sum.
        let start: f64 = std::iter::empty::<f64>().sum();
        // One row of the block: on the stack up to rank 6 (18 coordinates).
        let mut stack = [0.0; 4 * 6 - 6];
        let mut heap = Vec::new();
        let row = if dv <= stack.len() {
            &mut stack[..dv]
        } else {
            heap.resize(dv, 0.0);
            &mut heap[..]
        };
        for a in 0..du {
            let ua = &self.bu[a * w..(a + 1) * w];
            row.fill(start);
            for (i, &x) in ua.iter().enumerate() {
                for (acc, &y) in row.iter_mut().zip(&k[i * dv..(i + 1) * dv]) {
                    *acc += x * y;
                }
            }
            let from = if self.diagonal { a } else { 0 };
            values.extend(row[from..].iter().map(|v| 2.0 * v));
        }
    }
}

/// Hessian values (pattern order) and gradient coordinates at x.
fn hessian(
    problem: &Problem3,
    sys: &System,
    x: &Point3,
    qx: &[f64],
    bases: &[Vec<f64>],
) -> (Vec<f64>, Vec<f64>) {
    let p = sys.p;
    let lambda = lambda_blocks(problem, x, qx);
    // Pair by pair, each pair's values appended in order: the two halves of the pairs on two
    // cores give the same list.
    let (mut values, upper) =
        crate::linalg::parallel::halves(problem.pairs.len(), SPLIT_POSES, |pairs| {
            let mut values = Vec::with_capacity(sys.count / 2 + 1);
            let mut kb: Vec<f64> = Vec::new();
            for k in pairs {
                pair_values(problem, sys, &lambda, bases, k, &mut kb, &mut values);
            }
            values
        });
    values.extend(upper);
    (values, gradient(problem, sys, p, qx, bases))
}

/// The Hessian's values of pair k (its upper triangle's block, [`hessian`]), appended to
/// `values`; `kb` is room for (S_uv ⊗ I_p) B_v.
fn pair_values(
    problem: &Problem3,
    sys: &System,
    lambda: &[[[f64; 3]; 3]],
    bases: &[Vec<f64>],
    k: usize,
    kb: &mut Vec<f64>,
    values: &mut Vec<f64>,
) {
    let p = sys.p;
    let (u, v) = problem.pairs[k];
    let (du, dv) = (sys.dims[u], sys.dims[v]);
    if du == 0 || dv == 0 {
        return;
    }
    // S_uv (4x4) ⊗ I_p.
    let s = s_block(problem, lambda, k);
    let block = PairBlock {
        s: &s,
        bu: &bases[u],
        bv: &bases[v],
        du,
        dv,
        diagonal: u == v,
    };
    // Compiled for the ranks the staircase meets most (sizes known, loops unrolled), the
    // same operations in the same order at every rank.
    match p {
        3 => block.values::<3>(p, kb, values),
        4 => block.values::<4>(p, kb, values),
        5 => block.values::<5>(p, kb, values),
        _ => block.values::<0>(p, kb, values),
    }
}

/// The gradient's coordinates Bᵀ 2QX (the normal part ΛX is orthogonal to B).
fn gradient(
    problem: &Problem3,
    sys: &System,
    p: usize,
    qx: &[f64],
    bases: &[Vec<f64>],
) -> Vec<f64> {
    let mut grad = vec![0.0; sys.dim()];
    let mut local = vec![0.0; 4 * p];
    for u in 0..problem.n {
        if sys.dims[u] == 0 {
            continue;
        }
        for l in 0..4 {
            let r = problem.local_row(u, l).expect("not the anchor");
            local[l * p..(l + 1) * p].copy_from_slice(&qx[r * p..(r + 1) * p]);
        }
        for a in 0..sys.dims[u] {
            let col = &bases[u][a * 4 * p..(a + 1) * 4 * p];
            grad[sys.offset[u] + a] = 2.0 * col.iter().zip(&local).map(|(x, y)| x * y).sum::<f64>();
        }
    }
    grad
}

/// The decrease −(gᵀδ + ½ δᵀHδ) that the quadratic model at a point predicts along δ, H applied
/// through its stored upper triangle (`values`, in the system's pattern order).
fn model_decrease(
    problem: &Problem3,
    sys: &System,
    values: &[f64],
    grad: &[f64],
    delta: &[f64],
) -> f64 {
    let mut hd = vec![0.0; sys.dim()];
    let mut k = 0;
    for &(u, v) in &problem.pairs {
        let (du, dv) = (sys.dims[u], sys.dims[v]);
        if du == 0 || dv == 0 {
            continue;
        }
        for a in 0..du {
            for b in 0..dv {
                if u == v && b < a {
                    continue;
                }
                let (r, c) = (sys.offset[u] + a, sys.offset[v] + b);
                let h = values[k];
                k += 1;
                hd[r] += h * delta[c];
                if r != c {
                    hd[c] += h * delta[r];
                }
            }
        }
    }
    let gd: f64 = grad.iter().zip(delta).map(|(a, b)| a * b).sum();
    let dhd: f64 = hd.iter().zip(delta).map(|(a, b)| a * b).sum();
    -(gd + 0.5 * dhd)
}

/// B_uδ_u, pose u's step over its 4p entries (translation row, then rotation rows), added to
/// `out` (4p long): Σ_a δ_a times column a of the pose's tangent basis ([`pose_basis`]).
fn pose_step(basis: &[f64], d: &[f64], out: &mut [f64]) {
    let w = out.len();
    for (a, &da) in d.iter().enumerate() {
        for (o, b) in out.iter_mut().zip(&basis[a * w..(a + 1) * w]) {
            *o += da * b;
        }
    }
}

/// δᵀHδ with H = 2Bᵀ(S ⊗ I_p)B at the point of `bases` and multipliers `lambda`, without
/// assembling H: 2 Σ (B_uδ_u)ᵀ(S_uv ⊗ I_p)(B_vδ_v) over the pose pairs, those off the diagonal
/// twice. The chord step's model curvature (a chord step needs no new factorization, and the
/// Hessian's values took 2.3 ms of each of torus3D's chord steps).
fn curvature(
    problem: &Problem3,
    sys: &System,
    bases: &[Vec<f64>],
    lambda: &[[[f64; 3]; 3]],
    delta: &[f64],
) -> f64 {
    let p = sys.p;
    let w = 4 * p;
    // B_uδ_u for every pose (4p entries each; none for the anchor).
    let mut moved = vec![0.0; problem.n * w];
    for u in 0..problem.n {
        let d = &delta[sys.offset[u]..sys.offset[u + 1]];
        pose_step(&bases[u], d, &mut moved[u * w..(u + 1) * w]);
    }
    let mut sum = 0.0;
    for (k, &(u, v)) in problem.pairs.iter().enumerate() {
        if sys.dims[u] == 0 || sys.dims[v] == 0 {
            continue;
        }
        let s = s_block(problem, lambda, k);
        let (mu, mv) = (&moved[u * w..(u + 1) * w], &moved[v * w..(v + 1) * w]);
        let mut pair = 0.0;
        for la in 0..4 {
            for lb in 0..4 {
                if s[la][lb] != 0.0 {
                    let inner: f64 = (0..p).map(|c| mu[la * p + c] * mv[lb * p + c]).sum();
                    pair += s[la][lb] * inner;
                }
            }
        }
        sum += if u == v { 2.0 } else { 4.0 } * pair;
    }
    sum
}

/// The point x + Bδ, each rotation block retracted to the Stiefel manifold by its polar factor
/// (translations not yet projected).
fn retract(
    problem: &Problem3,
    sys: &System,
    bases: &[Vec<f64>],
    x: &Point3,
    delta: &[f64],
) -> Point3 {
    let p = sys.p;
    // Each pose's four rows moved by its step, the rotation rows then made orthonormal: pose by
    // pose, so the two halves of the poses on two cores give the same rows.
    let moved = |poses: std::ops::Range<usize>| {
        let mut rows = Vec::new();
        let mut v = vec![0.0; 4 * p];
        for u in poses.filter(|&u| sys.dims[u] > 0) {
            v.fill(0.0);
            pose_step(&bases[u], &delta[sys.offset[u]..sys.offset[u + 1]], &mut v);
            let start = rows.len();
            for l in 0..4 {
                let r = problem.local_row(u, l).expect("not the anchor");
                rows.extend((0..p).map(|c| x.x[r * p + c] + v[l * p + c]));
            }
            polar_rows(&mut rows[start + p..start + 4 * p], p);
        }
        rows
    };
    let (lower, upper) = crate::linalg::parallel::halves(problem.n, SPLIT_POSES, moved);
    let mut trial = x.clone();
    let mut rows = lower.chunks_exact(4 * p).chain(upper.chunks_exact(4 * p));
    for u in (0..problem.n).filter(|&u| sys.dims[u] > 0) {
        let pose = rows.next().expect("one block of rows per pose with a step");
        for l in 0..4 {
            let r = problem.local_row(u, l).expect("not the anchor");
            trial.x[r * p..(r + 1) * p].copy_from_slice(&pose[l * p..(l + 1) * p]);
        }
    }
    trial
}

/// The poses (or pairs) from which the per-pose work of a Newton step (the retraction, the
/// tangent bases, the Hessian's blocks) is split between two cores where the second is idle
/// ([`crate::linalg::parallel::halves`]). Whole process, split/not, 21 interleaved pairs:
/// sphere2500 (2 500 poses) 0.95, cubicle 0.97, torus3D 0.98, sphere_bignoise (2 200) 0.98;
/// parking-garage (1 661) 1.00.
const SPLIT_POSES: usize = 2048;

/// The multiply-adds from which the Newton systems' LLᵀ is split between two cores
/// ([`crate::linalg::tree_factor`]). Alone, faer's against the split on two cores (medians of
/// 9, rank 3): sphere_bignoise (5.6·10⁸) 16.6 against 8.6 ms, cubicle (7.4·10⁸) 24.7 against
/// 12.7, sphere2500 (3.9·10⁸) 9.8 against 5.7, torus3D (1.2·10⁹, its top set the heaviest)
/// 27.7 against 18.1; on one core the split took 0.90-1.04 of faer's time. Whole process,
/// split/not, 15 interleaved pairs: sphere_bignoise 0.86, cubicle 0.95, torus3D 0.96,
/// sphere2500 0.98. parking-garage (2.2·10⁷) factored in 1.0 ms instead of 1.9 ms, but its whole
/// process took 1.02-1.04 of the time in three runs of 11 to 21 pairs, and is left to faer.
const SPLIT_FACTOR_MIN_WORK: f64 = 5e7;

/// The chord steps of [`optimize`]: after a step that gained at most `CHORD_AFTER`·f, the next
/// one first solves with the last factorization, of the point just left (its Hessian differs
/// from the current one by the length of that step). Near a nondegenerate minimum Newton
/// converges quadratically, and such a step contracts the error about as a new factorization
/// would (by a factor of the order of the last step's length). Factorizations, with 1e-6 here
/// before (the confirming last step only) and 1e-3 now: tinyGrid3D 3 to 2, smallGrid3D 7 to 6,
/// sphere2500 3 to 2, torus3D 3 to 2, cubicle 3 to 2, sphere_bignoise 5 to 4, parking-garage
/// 5 and 5; the optima agree to 1e-14 relative, and every bound stays below 1.2e-8 relative.
const CHORD_AFTER: f64 = 1e-3;

/// The largest decrease, as a fraction of f, that the model predicts for a chord step that is
/// taken: at most this the point is well inside Newton's quadratic region. (With 1e-5 and
/// without the rule that a chord step follows a chord step only where the error shrank tenfold,
/// sphere_bignoise took 24 chord steps: a slow linear contraction from a point further out.)
const CHORD_TAKEN: f64 = 1e-6;

/// A chord step whose first-order decrease −gᵀδ exceeds this multiple of [`CHORD_TAKEN`]·f is
/// not taken, its model's curvature δᵀHδ not computed (a pass over the edges: about 1.5 ms on
/// parking-garage). The model's decrease −gᵀδ − ½δᵀHδ would be that small only with δᵀHδ near
/// −2gᵀδ, twice the curvature of the factorization that gave δ. Over the public 3D files and 72
/// generated worlds the 135 chord steps taken had −gᵀδ of at most 1.62 times the bound, and 15
/// of the 40 not taken more than 4 times it: the same steps, the same bytes.
const CHORD_FAR: f64 = 4.0;

/// The least damping μ (relative to D, [`optimize`]) after a step that failed: a factorization
/// of H + μD that was not positive definite (β of Nocedal and Wright's Algorithm 3.3, Cholesky
/// with an added multiple of the identity), or a trial point that did not decrease f enough.
/// From μ = 1e-6 Nielsen's doubling alone barely moves the step: smallGrid3D's chordal start
/// rejected the steps of μ = 1e-6 and 2e-6, the same step twice (8 Newton steps to its optimum,
/// 7 so); of 54 generated graphs (grid, sphere and torus worlds of 125-1000 poses, rotation
/// noise 0.05-0.3) one rejected a step, 9 steps then 7; the rest are unchanged.
const FAILED_STEP_DAMPING: f64 = 1e-3;

/// Options of [`optimize`].
#[derive(Debug, Clone, Copy)]
pub struct LocalOptions {
    pub max_iterations: usize,
}

/// The norm of the Riemannian gradient at `x` (one pass for QX, one for the tangent bases).
fn gradient_norm_at(problem: &Problem3, sys: &System, x: &Point3) -> f64 {
    let qx = apply_q(problem, x);
    let bases = pose_bases(problem, x);
    let g = gradient(problem, sys, x.p, &qx, &bases);
    g.iter().map(|g| g * g).sum::<f64>().sqrt()
}

/// Riemannian Newton (damped) from `x` at its rank, translations projected first.
pub fn optimize(
    problem: &Problem3,
    translations: &mut Translations,
    x: Point3,
    options: &LocalOptions,
    report: &mut dyn FnMut(Step3),
) -> Local3 {
    optimize_with(
        problem,
        translations,
        x,
        options,
        report,
        &|| None,
        &Vec::new,
    )
}

/// As [`optimize`], with the Newton system of `x`'s rank when one was built ahead: `system()`
/// hands it over (waiting for it if it is still being built), asked once the start's
/// translations are projected; `None` builds it here. `room()` gives the room of the first
/// factorization's values ([`SparseFactor::reuse`]), asked just before it: pages mapped ahead on
/// the second core, or an empty vector (the factorization allocates its own).
pub fn optimize_with(
    problem: &Problem3,
    translations: &mut Translations,
    mut x: Point3,
    options: &LocalOptions,
    report: &mut dyn FnMut(Step3),
    system: &dyn Fn() -> Option<System>,
    room: &dyn Fn() -> Vec<f64>,
) -> Local3 {
    let p = x.p;
    translations.project(problem, &mut x);
    let mut sys = system()
        .filter(|s| s.p == p)
        .unwrap_or_else(|| System::new(problem, p));
    let total_weight: f64 = problem.terms.iter().map(|t| t.tau + t.kappa).sum();
    let mut cost = problem.cost(&x);
    let mut mu = 1e-6;
    let mut nu = 2.0;
    // Nielsen's rule μ·max(1 − (2ρ − 1)³, c), with c = 1/1000 at rank 3 (the planar staircase's
    // choice at rank 1, for the same reason: the damping slows Newton along the graph's soft
    // directions, and at the lowest rank the gauge-fixed minimum is nondegenerate); his 1/3
    // above, where minima are degenerate along the rank-deficient directions. Against 1/100:
    // sphere_bignoise_vertex3 7 Newton steps to 6, the other public 3D files as many; of 54
    // generated worlds 9 took one or two fewer (whole process 0.89-0.96 of the time on two of
    // them), one one more.
    let fastest_decrease: f64 = if p == 3 { 1e-3 } else { 1.0 / 3.0 };
    let mut work = 0.0;
    let mut gradient_norm = f64::INFINITY;
    let mut converged = false;
    let mut iterations = 0;
    let dim = sys.dim();
    if dim == 0 {
        return Local3 {
            point: x,
            cost,
            gradient_norm: 0.0,
            iterations: 0,
            converged: true,
            work,
            room: Vec::new(),
        };
    }
    let mut fresh = true;
    let mut first_factorization = true;
    let mut chord_next = false;
    let mut last_gain = f64::INFINITY;
    let (mut values, mut grad, mut bases) = (Vec::new(), Vec::new(), Vec::new());
    let (mut qx, mut lambda) = (Vec::new(), Vec::new());
    // Whether `values` holds the Hessian at x: a chord step needs only the gradient and the
    // model's curvature along its step ([`curvature`]); the values follow where it is not taken.
    let mut assembled = false;
    while iterations < options.max_iterations {
        if fresh {
            qx = apply_q(problem, &x);
            bases = pose_bases(problem, &x);
            if chord_next {
                lambda = lambda_blocks(problem, &x, &qx);
                grad = gradient(problem, &sys, p, &qx, &bases);
                assembled = false;
            } else {
                (values, grad) = hessian(problem, &sys, &x, &qx, &bases);
                assembled = true;
            }
            gradient_norm = grad.iter().map(|g| g * g).sum::<f64>().sqrt();
            fresh = false;
        }
        if gradient_norm == 0.0 {
            converged = true;
            break;
        }
        // The stopping rule's bound on a predicted decrease.
        let stop = 1e-12 * cost + 1e-24 * total_weight;
        let negligible = |predicted: f64| predicted <= stop;
        // The chord step ([`CHORD_AFTER`]): δ = −(the last factorization)⁻¹ g and the decrease
        // the model at x (its own Hessian) predicts along it, taken where that is at most
        // [`CHORD_TAKEN`]·f (or negligible, where that is larger: f near 0); otherwise a new
        // factorization. Far outside that bound the model's curvature is not computed
        // ([`CHORD_FAR`]).
        let chord_bound = (CHORD_TAKEN * cost).max(stop);
        let chord = std::mem::take(&mut chord_next)
            .then(|| {
                let delta = sys.solve(|k| -grad[k]);
                let gd: f64 = grad.iter().zip(&delta).map(|(a, b)| a * b).sum();
                (-gd <= CHORD_FAR * chord_bound).then(|| {
                    let dhd = curvature(problem, &sys, &bases, &lambda, &delta);
                    (delta, -(gd + 0.5 * dhd))
                })
            })
            .flatten()
            .filter(|&(_, predicted)| predicted >= 0.0 && predicted <= chord_bound);
        let is_chord = chord.is_some();
        let (delta, predicted) = match chord {
            Some(step) => step,
            None => {
                if !assembled {
                    (values, _) = hessian(problem, &sys, &x, &qx, &bases);
                    assembled = true;
                }
                // (H + μ D) δ = −g, D = max(|diag H|, floor), written into the system as the
                // values are handed over (the diagonal's value indices ascend with the
                // coordinates), without a damped copy of them (torus3D: 4 MB a step).
                let dmax = sys
                    .diagonal
                    .iter()
                    .fold(0.0f64, |m, &k| m.max(values[k].abs()));
                let floor = 1e-12 * dmax;
                let System {
                    system, diagonal, ..
                } = &mut sys;
                system.fill_with(|fill| {
                    let mut diagonal = diagonal.iter().copied().peekable();
                    for (k, &v) in values.iter().enumerate() {
                        fill.push(match diagonal.next_if_eq(&k) {
                            Some(_) => v + mu * v.abs().max(floor),
                            None => v,
                        });
                    }
                    debug_assert!(diagonal.next().is_none(), "the diagonal's indices ascend");
                });
                work += sys.system.multiply_adds();
                if first_factorization {
                    first_factorization = false;
                    sys.system.reuse(room());
                }
                if sys.system.llt().is_err() {
                    // H + μD is not positive definite: at least FAILED_STEP_DAMPING, then
                    // doubling. Doubling from 1e-6 took four failed factorizations, each as
                    // dear as a successful one, on sphere_bignoise's chordal start.
                    mu = (mu * nu).max(FAILED_STEP_DAMPING);
                    nu *= 2.0;
                    iterations += 1;
                    continue;
                }
                let delta = sys.solve(|k| -grad[k]);
                let predicted = model_decrease(problem, &sys, &values, &grad, &delta);
                (delta, predicted)
            }
        };
        let mut trial = retract(problem, &sys, &bases, &x, &delta);
        translations.project(problem, &mut trial);
        let trial_cost = problem.cost(&trial);
        iterations += 1;
        let actual = cost - trial_cost;
        let rho = if predicted > 0.0 {
            actual / predicted
        } else {
            -1.0
        };
        report(Step3 {
            rank: p,
            iteration: iterations,
            cost: trial_cost.min(cost),
            gradient_norm,
            damping: mu,
        });
        let negligible = negligible(predicted);
        if negligible && (actual.is_nan() || actual <= 0.0) {
            // Converged: no step predicts a decrease above the rounding of f. Where f cannot
            // tell the trial point from x (within the rounding the stopping rule allows) but
            // its gradient is smaller, the trial point is the better first-order point, and the
            // certificate's bound, which grows with the gradient, is tighter there.
            if actual.is_finite() && -actual <= stop {
                let norm = gradient_norm_at(problem, &sys, &trial);
                if norm < gradient_norm {
                    (x, cost, gradient_norm) = (trial, trial_cost, norm);
                }
            }
            converged = true;
            break;
        }
        if rho > 1e-4 || (actual >= 0.0 && negligible) {
            // A chord step follows a chord step only where that one gained at most 1/100 of
            // the step before it: the error (its square root) shrank at least tenfold.
            chord_next = actual <= CHORD_AFTER * cost && (!is_chord || actual <= 1e-2 * last_gain);
            last_gain = actual;
            x = trial;
            cost = trial_cost;
            fresh = true;
            mu *= fastest_decrease.max(1.0 - (2.0 * rho - 1.0).powi(3));
            nu = 2.0;
            if negligible {
                // One more gradient evaluation for the report.
                gradient_norm = gradient_norm_at(problem, &sys, &x);
                converged = true;
                break;
            }
        } else {
            mu = (mu * nu).max(FAILED_STEP_DAMPING);
            nu *= 2.0;
            if mu > 1e20 {
                break;
            }
        }
    }
    Local3 {
        point: x,
        cost,
        gradient_norm,
        iterations,
        converged,
        work,
        room: sys.system.take_values(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::rng::Rng;
    use crate::se3::grid_problem as grid;

    /// A random point of St(3, p)^n × ℝ^{p(n−1)} (normal entries, each rotation block's rows
    /// made orthonormal), with QX and the poses' tangent bases there.
    fn random_point(
        problem: &Problem3,
        p: usize,
        rng: &mut Rng,
    ) -> (Point3, Vec<f64>, Vec<Vec<f64>>) {
        let mut x = Point3 {
            p,
            x: (0..problem.dim() * p).map(|_| rng.normal()).collect(),
        };
        for u in 0..problem.n {
            let r0 = problem.rotation_row(u, 0);
            assert!(polar_rows(&mut x.x[r0 * p..(r0 + 3) * p], p));
        }
        let qx = apply_q(problem, &x);
        let bases = pose_bases(problem, &x);
        (x, qx, bases)
    }

    /// The Hessian's values as the formula 2 B_uᵀ (S_uv ⊗ I_p) B_v reads, entry by entry: each
    /// entry of K = (S_uv ⊗ I_p) B_v summed over S's columns in order, then each value the sum
    /// over i of B_u[i, a] K[i, b] in order (f64's iterator sum).
    fn values_by_formula(problem: &Problem3, sys: &System, x: &Point3, qx: &[f64]) -> Vec<f64> {
        let p = x.p;
        let w = 4 * p;
        let lambda = lambda_blocks(problem, x, qx);
        let bases: Vec<Vec<f64>> = (0..problem.n)
            .map(|u| pose_basis(problem, x, u, p))
            .collect();
        let mut values = Vec::new();
        for (k, &(u, v)) in problem.pairs.iter().enumerate() {
            let (du, dv) = (sys.dims[u], sys.dims[v]);
            if du == 0 || dv == 0 {
                continue;
            }
            let s = s_block(problem, &lambda, k);
            for a in 0..du {
                for b in 0..dv {
                    if u == v && b < a {
                        continue;
                    }
                    let mut kb = vec![0.0; w];
                    for la in 0..4 {
                        for lb in 0..4 {
                            if s[la][lb] != 0.0 {
                                for c in 0..p {
                                    kb[la * p + c] += s[la][lb] * bases[v][b * w + lb * p + c];
                                }
                            }
                        }
                    }
                    let ua = &bases[u][a * w..(a + 1) * w];
                    values.push(2.0 * ua.iter().zip(&kb).map(|(a, c)| a * c).sum::<f64>());
                }
            }
        }
        values
    }

    /// `hessian` (blocks compiled per rank, a block's row accumulated side by side) gives the
    /// formula's values bit for bit at every rank, the compiled ones (3, 4, 5) and the general
    /// code (6, and 7 and 9 with rows longer than the stack's room), at random points of
    /// St(3, p)^n × ℝ^{p(n−1)}.
    #[test]
    fn hessian_values_are_the_formula_bit_for_bit() {
        let problem = grid(3, 0, 0.05);
        let mut rng = Rng::new(11);
        for p in [3, 4, 5, 6, 7, 9] {
            let (x, qx, bases) = random_point(&problem, p, &mut rng);
            let sys = System::new(&problem, p);
            let (values, _) = hessian(&problem, &sys, &x, &qx, &bases);
            let expected = values_by_formula(&problem, &sys, &x, &qx);
            assert_eq!(values.len(), sys.count, "rank {p}");
            let same = values
                .iter()
                .zip(&expected)
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "rank {p}");
        }
    }

    /// The chord step's curvature δᵀHδ without H ([`curvature`]) against δᵀHδ from H's
    /// assembled upper triangle ([`model_decrease`] with a zero gradient is −½δᵀHδ), at random
    /// points and directions of ranks 3 to 5, to rounding.
    #[test]
    fn the_curvature_without_the_hessian_is_the_assembled_one() {
        let problem = grid(5, 4, 0.05);
        let mut rng = Rng::new(17);
        for p in [3, 4, 5] {
            let (x, qx, bases) = random_point(&problem, p, &mut rng);
            let sys = System::new(&problem, p);
            let (values, _) = hessian(&problem, &sys, &x, &qx, &bases);
            let lambda = lambda_blocks(&problem, &x, &qx);
            let zero = vec![0.0; sys.dim()];
            for _ in 0..3 {
                let delta: Vec<f64> = (0..sys.dim()).map(|_| rng.normal()).collect();
                let assembled = -2.0 * model_decrease(&problem, &sys, &values, &zero, &delta);
                let free = curvature(&problem, &sys, &bases, &lambda, &delta);
                let scale: f64 = values.iter().map(|v| v.abs()).sum::<f64>()
                    * delta.iter().map(|d| d * d).sum::<f64>();
                assert!(
                    (free - assembled).abs() <= 1e-13 * scale,
                    "rank {p}: {free} {assembled}"
                );
            }
        }
    }
}
