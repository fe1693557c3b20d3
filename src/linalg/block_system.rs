//! A real symmetric matrix of dense blocks ([`Assembly::try_blocked`]) with its supernodal LLᵀ,
//! assembled directly in its elimination order and in the triangle its factorizations read
//! (no permuted copy), analyzed once for its pattern: the Newton systems' form, planar and SE(3).
//!
//! Its row indices and positions are 32-bit where the counts fit (faer's indices are signed:
//! below 2³¹ entries), else `usize`: the 32-bit ones halve the assembly's and the analysis's
//! index arrays (at 10⁶ planar poses the assembly's 14·10⁶ row indices alone took 107 MB as
//! `usize`), and the factor's values are the same bits either way.

use super::factor::{Assembly, Fill, Layout, NotFactorable, SparseFactor, block_coordinates};

/// The matrix and its factorization ([`BlockSystem::new`]).
pub struct BlockSystem {
    indexed: Indexed,
    /// The elimination order of the coordinates: `order[new] = old` (each block's together).
    order: Vec<usize>,
}

/// The assembly and the factor with 32-bit or with `usize` indices.
enum Indexed {
    Narrow(Assembly<f64, u32>, SparseFactor<f64, u32>),
    Wide(Assembly<f64>, SparseFactor<f64>),
}

/// `$body` with `$assembly` and `$factor` bound to the system's, whichever their index type.
macro_rules! indexed {
    ($indexed:expr, |$assembly:ident, $factor:ident| $body:expr) => {
        match $indexed {
            Indexed::Narrow($assembly, $factor) => $body,
            Indexed::Wide($assembly, $factor) => $body,
        }
    };
}

impl BlockSystem {
    /// The pattern of [`Assembly::try_blocked`] (block u of `sizes[u]` coordinates, the pairs
    /// `blocks`, the blocks in the elimination `order`, `order[new] = old`), stored and analyzed
    /// supernodally; its LLᵀ by our own code ([`SparseFactor::prepare_own_factorization`]: split
    /// between the cores from `split_min_work` multiply-adds), its solves split where large
    /// ([`SparseFactor::prepare_split`]). Coordinates are numbered block by block, in index order.
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
        let narrow =
            Assembly::<f64, u32>::try_blocked(sizes, blocks, order, side).and_then(|assembly| {
                let factor =
                    SparseFactor::try_analyze_in_order(assembly.matrix.symbolic(), side, layout)?;
                Some(Indexed::Narrow(assembly, factor))
            });
        let mut indexed = narrow.unwrap_or_else(|| {
            let assembly = Assembly::blocked(sizes, blocks, order, side);
            let factor = SparseFactor::analyze_in_order(assembly.matrix.symbolic(), side, layout);
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
        let mut offset = vec![0; sizes.len() + 1];
        for (u, &size) in sizes.iter().enumerate() {
            offset[u + 1] = offset[u] + size;
        }
        let order = block_coordinates(order, &offset);
        BlockSystem { indexed, order }
    }

    /// Rewrites the values ([`Assembly::fill`]).
    pub fn fill(&mut self, values: &[f64]) {
        indexed!(&mut self.indexed, |assembly, _factor| assembly.fill(values))
    }

    /// Rewrites the values one at a time ([`Assembly::fill_with`]).
    pub fn fill_with(&mut self, produce: impl FnOnce(&mut Fill<'_, f64>)) {
        indexed!(&mut self.indexed, |assembly, _factor| assembly
            .fill_with(produce))
    }

    /// Numeric LLᵀ of the values last written; `Err` if the matrix is not numerically positive
    /// definite.
    pub fn llt(&mut self) -> Result<(), NotFactorable> {
        indexed!(&mut self.indexed, |assembly, factor| factor
            .llt(assembly.matrix.as_ref()))
    }

    /// x with A x = b by the last successful LLᵀ, b's coordinate k given by `b(k)`, gathered
    /// straight into the elimination order and x scattered out of it
    /// ([`SparseFactor::solve_gathered`]).
    pub fn solve(&mut self, b: impl Fn(usize) -> f64) -> Vec<f64> {
        let order = &self.order;
        indexed!(&mut self.indexed, |_assembly, factor| factor
            .solve_gathered(order, b))
    }

    /// The dimension.
    pub fn dim(&self) -> usize {
        indexed!(&self.indexed, |_assembly, factor| factor.dim())
    }

    /// The multiply-adds of one factorization ([`SparseFactor::multiply_adds`]).
    pub fn multiply_adds(&self) -> f64 {
        indexed!(&self.indexed, |_assembly, factor| factor.multiply_adds())
    }

    /// The number of values of the numeric factor ([`SparseFactor::values_len`]).
    pub fn values_len(&self) -> usize {
        indexed!(&self.indexed, |_assembly, factor| factor.values_len())
    }

    /// Whether its factorizations are split between the cores
    /// ([`SparseFactor::splits_factorizations`]).
    pub fn splits_factorizations(&self) -> bool {
        indexed!(&self.indexed, |_assembly, factor| factor
            .splits_factorizations())
    }

    /// The room of the first factorization's values ([`SparseFactor::reuse`]).
    pub fn reuse(&mut self, values: Vec<f64>) {
        indexed!(&mut self.indexed, |_assembly, factor| factor.reuse(values))
    }

    /// The numeric factor's values, handed over, the factor released
    /// ([`SparseFactor::take_values`]).
    pub fn take_values(&mut self) -> Vec<f64> {
        indexed!(&mut self.indexed, |_assembly, factor| factor.take_values())
    }
}
