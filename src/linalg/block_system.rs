//! A real symmetric matrix of dense blocks ([`Assembly::try_blocked`]) with its supernodal LLᵀ,
//! assembled directly in its elimination order and in the triangle its factorizations read
//! (no permuted copy), analyzed once for its pattern: the Newton systems' form, planar and SE(3).
//!
//! Its row indices and positions are 32-bit where the counts fit (faer's indices are signed:
//! below 2³¹ entries), else `usize`: the 32-bit ones halve the assembly's and the analysis's
//! index arrays (at 10⁶ planar poses the assembly's 14·10⁶ row indices alone took 107 MB as
//! `usize`), and the factor's values are the same bits either way. Up to [`DENSE_MAX_ROWS`] rows
//! the LLᵀ is one dense block instead ([`Dense`]): no analysis.

use super::factor::{Assembly, Fill, Layout, NotFactorable, SparseFactor, block_coordinates};

/// The matrix and its factorization ([`BlockSystem::new`]).
pub struct BlockSystem {
    indexed: Indexed,
    /// The elimination order of the coordinates: `order[new] = old` (each block's together).
    order: Vec<usize>,
}

/// The assembly and the factor with 32-bit or with `usize` indices, or, up to
/// [`DENSE_MAX_ROWS`], the assembly and a dense factor.
enum Indexed {
    Narrow(Assembly<f64, u32>, SparseFactor<f64, u32>),
    Wide(Assembly<f64>, SparseFactor<f64>),
    Dense(Assembly<f64, u32>, Dense),
}

/// The largest system factored as one dense block ([`Dense`]), without the sparse analysis
/// (faer's symbolic factorization, the split between the cores): on graphs of a few poses that
/// analysis, its code run for the first time in the process, cost more than the factorizations
/// it orders. tinyGrid3D (its chordal and Newton systems 24 rows each), whole process against the
/// sparse factor, 41 interleaved pairs in three runs: 0.78-0.85 of the time with the binary's
/// pages as the linker or a read from disk leaves them in the page cache, 0.975 for fresh copies
/// of both (`scripts/compare-builds`, whose copies the kernel maps in fewer faults). Larger
/// bounds, on generated 3D worlds of 24 to 40 poses (69 to 117 rows): 128 rows 0.98-1.00, 256
/// rows 1.08-1.52 (the dense factor's n³/6 multiply-adds). The optima of 100 small graphs (3D
/// worlds of 8 to 40 poses, planar ones of 8 to 30 with `--method staircase`) agree with the
/// sparse factor's to 8.2e-15 relative, all certified alike; the certificates keep their sparse
/// LDLᵀ, whose rounding their proofs bound.
pub const DENSE_MAX_ROWS: usize = 64;

/// A system of at most [`DENSE_MAX_ROWS`] rows factored as one dense block: its lower triangle
/// column by column in the elimination order by the narrow supernodes' loops
/// ([`crate::linalg::tree_factor::llt_by_columns`]: a standard Cholesky), solved by forward and
/// backward substitution.
struct Dense {
    dim: usize,
    /// L (lower triangle, column-major, dim × dim) after a successful [`Dense::llt`].
    values: Vec<f64>,
}

impl Dense {
    /// L Lᵀ = A, A the assembly's values (its lower triangle, in the elimination order);
    /// `Err` where a pivot is not positive.
    fn llt(&mut self, assembly: &Assembly<f64, u32>) -> Result<(), NotFactorable> {
        let n = self.dim;
        self.values.clear();
        self.values.resize(n * n, 0.0);
        let matrix = assembly.matrix.as_ref();
        let (col_ptr, row_idx, vals) = (
            matrix.symbolic().col_ptr(),
            matrix.symbolic().row_idx(),
            matrix.val(),
        );
        for c in 0..n {
            for k in col_ptr[c] as usize..col_ptr[c + 1] as usize {
                self.values[c * n + row_idx[k] as usize] = vals[k];
            }
        }
        crate::linalg::tree_factor::llt_by_columns(&mut self.values, n, n)
            .map_err(|_| NotFactorable)
    }

    /// x with L Lᵀ x = b in place (b in the elimination order), by the last successful
    /// [`Dense::llt`].
    fn solve_in_place(&self, x: &mut [f64]) {
        let (n, l) = (self.dim, &self.values);
        for j in 0..n {
            x[j] /= l[j * n + j];
            let xj = x[j];
            for i in j + 1..n {
                x[i] -= l[j * n + i] * xj;
            }
        }
        for j in (0..n).rev() {
            let mut s = x[j];
            for i in j + 1..n {
                s -= l[j * n + i] * x[i];
            }
            x[j] = s / l[j * n + j];
        }
    }
}

/// `$body` with `$assembly` and `$factor` bound to the system's, whichever their index type.
macro_rules! indexed {
    ($indexed:expr, |$assembly:ident, $factor:ident| $body:expr) => {
        match $indexed {
            Indexed::Narrow($assembly, $factor) => $body,
            Indexed::Wide($assembly, $factor) => $body,
            Indexed::Dense(..) => unreachable!("handled before"),
        }
    };
}

impl BlockSystem {
    /// The pattern of [`Assembly::try_blocked`] (block u of `sizes[u]` coordinates, the pairs
    /// `blocks`, the blocks in the elimination `order`, `order[new] = old`), stored and analyzed
    /// supernodally; its LLᵀ by our own code ([`SparseFactor::prepare_own_factorization`]: split
    /// between the cores from `split_min_work` multiply-adds), its solves split where large
    /// ([`SparseFactor::prepare_split`]); up to [`DENSE_MAX_ROWS`] rows, one dense block instead
    /// ([`Dense`]: no analysis). Coordinates are numbered block by block, in index order.
    /// `counted` is told the dimension and the factor's number of values as soon as the analysis
    /// knows them, before the rest of the preparation (the split between the cores, the own
    /// factorization's plan): a thread waiting for the system can map the pages of its values
    /// meanwhile ([`crate::linalg::heap::Room`]).
    pub fn new(
        sizes: &[usize],
        blocks: &[(usize, usize)],
        order: &[usize],
        split_min_work: f64,
        counted: impl FnOnce(usize, usize),
    ) -> Self {
        let layout = Layout::Supernodal;
        let side = layout.stored_side();
        let dim: usize = sizes.iter().sum();
        let dense = if dim <= DENSE_MAX_ROWS {
            Assembly::<f64, u32>::try_blocked(sizes, blocks, order, side)
        } else {
            None
        };
        let indexed = if let Some(assembly) = dense {
            counted(dim, dim * dim);
            Indexed::Dense(
                assembly,
                Dense {
                    dim,
                    values: Vec::new(),
                },
            )
        } else {
            let narrow = Assembly::<f64, u32>::try_blocked(sizes, blocks, order, side).and_then(
                |assembly| {
                    let factor = SparseFactor::try_analyze_in_order(
                        assembly.matrix.symbolic(),
                        side,
                        layout,
                    )?;
                    Some(Indexed::Narrow(assembly, factor))
                },
            );
            let mut indexed = narrow.unwrap_or_else(|| {
                let assembly = Assembly::blocked(sizes, blocks, order, side);
                let factor =
                    SparseFactor::analyze_in_order(assembly.matrix.symbolic(), side, layout);
                Indexed::Wide(assembly, factor)
            });
            indexed!(&indexed, |_assembly, factor| counted(
                factor.dim(),
                factor.values_len()
            ));
            indexed!(&mut indexed, |_assembly, factor| {
                factor.prepare_split();
                factor.prepare_own_factorization(split_min_work);
            });
            indexed
        };
        let mut offset = vec![0; sizes.len() + 1];
        for (u, &size) in sizes.iter().enumerate() {
            offset[u + 1] = offset[u] + size;
        }
        let order = block_coordinates(order, &offset);
        BlockSystem { indexed, order }
    }

    /// Rewrites the values ([`Assembly::fill`]).
    pub fn fill(&mut self, values: &[f64]) {
        match &mut self.indexed {
            Indexed::Dense(assembly, _) => assembly.fill(values),
            indexed => indexed!(indexed, |assembly, _factor| assembly.fill(values)),
        }
    }

    /// Rewrites the values one at a time ([`Assembly::fill_with`]).
    pub fn fill_with(&mut self, produce: impl FnOnce(&mut Fill<'_, f64>)) {
        match &mut self.indexed {
            Indexed::Dense(assembly, _) => assembly.fill_with(produce),
            indexed => indexed!(indexed, |assembly, _factor| assembly.fill_with(produce)),
        }
    }

    /// Numeric LLᵀ of the values last written; `Err` if the matrix is not numerically positive
    /// definite.
    pub fn llt(&mut self) -> Result<(), NotFactorable> {
        match &mut self.indexed {
            Indexed::Dense(assembly, dense) => dense.llt(assembly),
            indexed => indexed!(indexed, |assembly, factor| factor
                .llt(assembly.matrix.as_ref())),
        }
    }

    /// x with A x = b by the last successful LLᵀ, b's coordinate k given by `b(k)`, gathered
    /// straight into the elimination order and x scattered out of it
    /// ([`SparseFactor::solve_gathered`]).
    pub fn solve(&mut self, b: impl Fn(usize) -> f64) -> Vec<f64> {
        let order = &self.order;
        match &mut self.indexed {
            Indexed::Dense(_, dense) => {
                let mut permuted: Vec<f64> = order.iter().map(|&old| b(old)).collect();
                dense.solve_in_place(&mut permuted);
                let mut x = vec![0.0; permuted.len()];
                for (p, &old) in permuted.into_iter().zip(order) {
                    x[old] = p;
                }
                x
            }
            indexed => indexed!(indexed, |_assembly, factor| factor.solve_gathered(order, b)),
        }
    }

    /// The dimension.
    pub fn dim(&self) -> usize {
        match &self.indexed {
            Indexed::Dense(_, dense) => dense.dim,
            indexed => indexed!(indexed, |_assembly, factor| factor.dim()),
        }
    }

    /// The multiply-adds of one factorization ([`SparseFactor::multiply_adds`]).
    pub fn multiply_adds(&self) -> f64 {
        match &self.indexed {
            Indexed::Dense(_, dense) => (dense.dim as f64).powi(3) / 6.0,
            indexed => indexed!(indexed, |_assembly, factor| factor.multiply_adds()),
        }
    }

    /// The number of values of the numeric factor ([`SparseFactor::values_len`]).
    pub fn values_len(&self) -> usize {
        match &self.indexed {
            Indexed::Dense(_, dense) => dense.dim * dense.dim,
            indexed => indexed!(indexed, |_assembly, factor| factor.values_len()),
        }
    }

    /// Whether its factorizations are split between the cores
    /// ([`SparseFactor::splits_factorizations`]).
    pub fn splits_factorizations(&self) -> bool {
        match &self.indexed {
            Indexed::Dense(..) => false,
            indexed => indexed!(indexed, |_assembly, factor| factor.splits_factorizations()),
        }
    }

    /// The room of the first factorization's values ([`SparseFactor::reuse`]).
    pub fn reuse(&mut self, values: Vec<f64>) {
        match &mut self.indexed {
            Indexed::Dense(_, dense) => dense.values = values,
            indexed => indexed!(indexed, |_assembly, factor| factor.reuse(values)),
        }
    }

    /// The numeric factor's values, handed over, the factor released
    /// ([`SparseFactor::take_values`]).
    pub fn take_values(&mut self) -> Vec<f64> {
        match &mut self.indexed {
            Indexed::Dense(_, dense) => std::mem::take(&mut dense.values),
            indexed => indexed!(indexed, |_assembly, factor| factor.take_values()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::rng::Rng;

    /// A random block system: `nb` blocks of 1 to 3 coordinates, the diagonal pairs, a path and
    /// random pairs (some repeated), a random elimination order. Returns the system filled with
    /// random values (large enough on the diagonal for A ≻ 0, or negated) and A itself, dense, in
    /// the coordinates numbered block by block, summed from the same values independently.
    fn random_system(nb: usize, seed: u64, negated: bool) -> (BlockSystem, Vec<Vec<f64>>) {
        let mut rng = Rng::new(seed);
        let sizes: Vec<usize> = (0..nb).map(|_| 1 + (rng.next_u64() % 3) as usize).collect();
        let mut blocks: Vec<(usize, usize)> = (0..nb).map(|u| (u, u)).collect();
        blocks.extend((1..nb).map(|u| (u - 1, u)));
        for _ in 0..nb {
            let (a, b) = (
                (rng.next_u64() % nb as u64) as usize,
                (rng.next_u64() % nb as u64) as usize,
            );
            blocks.push((a.min(b), a.max(b)));
        }
        let mut order: Vec<usize> = (0..nb).collect();
        for k in (1..nb).rev() {
            order.swap(k, (rng.next_u64() % (k as u64 + 1)) as usize);
        }
        let mut offset = vec![0; nb + 1];
        for u in 0..nb {
            offset[u + 1] = offset[u] + sizes[u];
        }
        let dim = offset[nb];
        let mut a = vec![vec![0.0; dim]; dim];
        let mut values = Vec::new();
        let sign = if negated { -1.0 } else { 1.0 };
        for &(u, v) in &blocks {
            for i in 0..sizes[u] {
                for j in 0..sizes[v] {
                    if u == v && j < i {
                        continue;
                    }
                    let (r, c) = (offset[u] + i, offset[v] + j);
                    let x = sign
                        * if r == c {
                            4.0 * dim as f64
                        } else {
                            rng.uniform() - 0.5
                        };
                    values.push(x);
                    a[r][c] += x;
                    if r != c {
                        a[c][r] += x;
                    }
                }
            }
        }
        let mut system = BlockSystem::new(&sizes, &blocks, &order, f64::INFINITY, |_, _| {});
        system.fill(&values);
        (system, a)
    }

    /// The dense factor below DENSE_MAX_ROWS rows and the sparse one above solve A x = b to
    /// their rounding (the residual against A summed independently), and the dense one refuses
    /// a negative definite A.
    #[test]
    fn dense_and_sparse_factors_solve_the_system() {
        for (nb, seed) in [(1, 1), (5, 2), (20, 3), (30, 4), (60, 5), (200, 6)] {
            let (mut system, a) = random_system(nb, seed, false);
            let dim = a.len();
            assert_eq!(system.dim(), dim);
            assert_eq!(
                matches!(system.indexed, Indexed::Dense(..)),
                dim <= DENSE_MAX_ROWS
            );
            system.llt().expect("positive definite");
            let b: Vec<f64> = (0..dim).map(|k| (k as f64 * 0.7).sin()).collect();
            let x = system.solve(|k| b[k]);
            let scale: f64 = a.iter().flatten().map(|v| v.abs()).sum::<f64>();
            for r in 0..dim {
                let ax: f64 = (0..dim).map(|c| a[r][c] * x[c]).sum();
                assert!(
                    (ax - b[r]).abs() <= 1e-13 * scale,
                    "nb {nb}: row {r}: {ax} against {}",
                    b[r]
                );
            }
            let (mut negative, _) = random_system(nb, seed, true);
            assert!(negative.llt().is_err(), "nb {nb}");
        }
    }
}
