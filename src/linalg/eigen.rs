//! Dense Hermitian eigendecompositions (faer's self-adjoint eigensolver, backward stable), for
//! the small graphs' full spectra and the dense certificate.

use faer::{Mat, Side, c64};

/// Eigenvalues (ascending) and eigenvectors (columns) of a Hermitian matrix.
pub fn hermitian_eigen(m: &Mat<c64>) -> (Vec<f64>, Mat<c64>) {
    let evd = m
        .self_adjoint_eigen(Side::Lower)
        .expect("the Hermitian eigensolver converges on finite matrices");
    let s = evd.S();
    let values = (0..m.nrows()).map(|k| s[k].re).collect();
    (values, evd.U().to_owned())
}

/// Eigenvalues (ascending) of a Hermitian matrix.
pub fn hermitian_eigenvalues(m: &Mat<c64>) -> Vec<f64> {
    m.self_adjoint_eigenvalues(Side::Lower)
        .expect("the Hermitian eigensolver converges on finite matrices")
}
