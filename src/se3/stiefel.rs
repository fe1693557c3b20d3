//! The product of Stiefel manifolds St(3, p)^n (SE-Sync §4.1, its eq. (37)-(41)) in pgo's row
//! layout: pose i's block X_i = Y_iᵀ is 3×p with orthonormal rows (X_i X_iᵀ = I₃).
//!
//! - Tangent space at X_i: {V : X_i Vᵀ + V X_iᵀ = 0}, dimension 3p − 6; an orthonormal basis is
//!   {(E_ab − E_ba) X_i / √2 : a < b} (the rotations of the block within its own row space)
//!   followed by {e_a w_kᵀ} for w_k an orthonormal basis of the complement of X_i's row space
//!   (the "horizontal" directions, none at p = 3). The normal space is {Σ X_i : Σ symmetric}.
//! - Projection onto it: V − sym(V X_iᵀ) X_i (SE-Sync eq. (39) in this layout).
//! - Retraction: the polar factor, R(X_i + V) = (AAᵀ)^{-1/2} A for A = X_i + V (SE-Sync uses
//!   the QR factor; the polar one is the nearest point, and at p = 3 the nearest rotation).
//! - Riemannian Hessian (SE-Sync eq. (40)-(41)): ⟨V, Hess f[V]⟩ = 2 tr(Vᵀ S V) with
//!   S = Q − SymBlockDiag(Λ), Λ_i = sym((QX)_i X_iᵀ): in the basis B, H = 2 Bᵀ (S ⊗ I_p) B,
//!   the same form as the planar 2 Bᵀ W̃(λ) B.

/// The polar factor of a 3×p block (row-major), in place: A ← (AAᵀ)^{-1/2} A. `false` if AAᵀ
/// is singular (then A is left as it is).
pub fn polar_rows(a: &mut [f64], p: usize) -> bool {
    let m =
        nalgebra::Matrix3::from_fn(|r, c| (0..p).map(|k| a[r * p + k] * a[c * p + k]).sum::<f64>());
    let eig = m.symmetric_eigen();
    if !eig.eigenvalues.iter().all(|&s| s > 0.0 && s.is_finite()) {
        return false;
    }
    let inv_sqrt = eig.eigenvectors
        * nalgebra::Matrix3::from_diagonal(&eig.eigenvalues.map(|s| 1.0 / s.sqrt()))
        * eig.eigenvectors.transpose();
    let old = a.to_vec();
    for r in 0..3 {
        for k in 0..p {
            a[r * p + k] = (0..3).map(|s| inv_sqrt[(r, s)] * old[s * p + k]).sum();
        }
    }
    true
}

/// The nearest rotation to a 3x3 matrix (polar factor with the determinant's sign fixed:
/// U diag(1, 1, det(UVᵀ)) Vᵀ), row-major.
pub fn nearest_rotation(m: &[f64; 9]) -> [f64; 9] {
    let a = nalgebra::Matrix3::from_row_slice(m);
    let svd = a.svd(true, true);
    let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
    let d = (u * vt).determinant().signum();
    let r = u * nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, d)) * vt;
    let mut out = [0.0; 9];
    for k in 0..9 {
        out[k] = r[(k / 3, k % 3)];
    }
    out
}

/// An orthonormal basis of the complement of the row space of a 3×p block with orthonormal
/// rows: (p − 3) rows of p entries (Gram-Schmidt, twice, over the coordinate vectors, each time
/// the one with the largest remainder).
pub fn complement(x: &[f64], p: usize) -> Vec<f64> {
    let mut basis: Vec<Vec<f64>> = (0..3).map(|r| x[r * p..(r + 1) * p].to_vec()).collect();
    let mut out = Vec::with_capacity((p - 3) * p);
    let mut used = vec![false; p];
    for _ in 3..p {
        let mut best: Option<(usize, Vec<f64>, f64)> = None;
        for c in (0..p).filter(|&c| !used[c]) {
            let mut v = vec![0.0; p];
            v[c] = 1.0;
            for _ in 0..2 {
                for b in &basis {
                    let d: f64 = b.iter().zip(&v).map(|(x, y)| x * y).sum();
                    for (vk, bk) in v.iter_mut().zip(b) {
                        *vk -= d * bk;
                    }
                }
            }
            let norm = v.iter().map(|z| z * z).sum::<f64>().sqrt();
            if best.as_ref().is_none_or(|b| norm > b.2) {
                best = Some((c, v, norm));
            }
        }
        let (c, mut v, norm) = best.expect("p > 3 leaves a coordinate vector");
        used[c] = true;
        for z in v.iter_mut() {
            *z /= norm;
        }
        out.extend_from_slice(&v);
        basis.push(v);
    }
    out
}

/// The orthonormal tangent basis at a 3×p block: 3p − 6 vectors of 3p entries (row-major
/// blocks), column k at `[k * 3p ..]`.
pub fn tangent_basis(x: &[f64], p: usize) -> Vec<f64> {
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let mut out = Vec::with_capacity((3 * p - 6) * 3 * p);
    for (a, b) in [(0, 1), (0, 2), (1, 2)] {
        let mut v = vec![0.0; 3 * p];
        for k in 0..p {
            v[a * p + k] = s * x[b * p + k];
            v[b * p + k] = -s * x[a * p + k];
        }
        out.extend(v);
    }
    if p > 3 {
        let w = complement(x, p);
        for a in 0..3 {
            for k in 0..p - 3 {
                let mut v = vec![0.0; 3 * p];
                v[a * p..(a + 1) * p].copy_from_slice(&w[k * p..(k + 1) * p]);
                out.extend(v);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(p: usize, seed: u64) -> Vec<f64> {
        let mut rng = crate::linalg::rng::Rng::new(seed);
        let mut a: Vec<f64> = (0..3 * p).map(|_| rng.normal()).collect();
        assert!(polar_rows(&mut a, p));
        a
    }

    #[test]
    fn the_tangent_basis_is_orthonormal_and_tangent() {
        for p in [3, 4, 6] {
            let x = block(p, 7 + p as u64);
            // Rows orthonormal after the polar factor.
            for r in 0..3 {
                for s in 0..3 {
                    let d: f64 = (0..p).map(|k| x[r * p + k] * x[s * p + k]).sum();
                    assert!((d - if r == s { 1.0 } else { 0.0 }).abs() < 1e-14);
                }
            }
            let b = tangent_basis(&x, p);
            let d = 3 * p - 6;
            assert_eq!(b.len(), d * 3 * p);
            for k in 0..d {
                let v = &b[k * 3 * p..(k + 1) * 3 * p];
                for l in 0..d {
                    let w = &b[l * 3 * p..(l + 1) * 3 * p];
                    let dot: f64 = v.iter().zip(w).map(|(a, b)| a * b).sum();
                    assert!((dot - if k == l { 1.0 } else { 0.0 }).abs() < 1e-13);
                }
                // X Vᵀ + V Xᵀ = 0.
                for r in 0..3 {
                    for s in 0..3 {
                        let xv: f64 = (0..p).map(|c| x[r * p + c] * v[s * p + c]).sum();
                        let vx: f64 = (0..p).map(|c| v[r * p + c] * x[s * p + c]).sum();
                        assert!((xv + vx).abs() < 1e-13);
                    }
                }
            }
        }
    }
}
