//! Anchored weighted Laplacians Σ w (e_a − e_b)(e_a − e_b)ᵀ of a graph with one vertex held (its
//! row and column left out: positive definite on a connected graph) and their LLᴴ: the planar
//! positions' L (eq. (24)), the planar and 3D rotation refinements' Gauss-Newton matrices, the
//! chordal relaxation's anchored connection Laplacian.

use super::factor::{Assembly, Layout, Scalar, SparseFactor};

/// The upper triangle of an anchored weighted Laplacian Σ w (e_a − e_b)(e_a − e_b)ᵀ, entry by
/// entry in the terms' order (duplicates to be summed), each term given as its two rows and w; a
/// row `None` (the anchor's) is left out, its term adding to the other row's diagonal only.
pub fn anchored_laplacian(
    terms: impl ExactSizeIterator<Item = (Option<usize>, Option<usize>, f64)>,
) -> (Vec<(usize, usize)>, Vec<f64>) {
    let mut entries = Vec::with_capacity(3 * terms.len());
    let mut values = Vec::with_capacity(3 * terms.len());
    for (i, j, w) in terms {
        for a in [i, j].into_iter().flatten() {
            entries.push((a, a));
            values.push(w);
        }
        if let (Some(i), Some(j)) = (i, j)
            && i != j
        {
            entries.push((i.min(j), i.max(j)));
            values.push(-w);
        }
    }
    (entries, values)
}

/// The LLᴴ of a `dim` x `dim` Hermitian matrix (upper-triangle entries, duplicates summed), in
/// the given fill-reducing order. `None` if it is not numerically positive definite.
pub fn anchored_llt<T: Scalar>(
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
