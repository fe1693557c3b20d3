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
/// is singular (then A is left as it is). Near the manifold, where the retraction meets it
/// (AAᵀ = I + VVᵀ for a tangent step V), by Björck and Bowie's iteration
/// ([`polar_by_iteration`]); farther, or where that has not converged, from the eigenvectors of
/// AAᵀ.
pub fn polar_rows(a: &mut [f64], p: usize) -> bool {
    let gram = match polar_by_iteration(a, p) {
        Ok(()) => return true,
        Err(gram) => gram,
    };
    let m = nalgebra::Matrix3::from_fn(|r, c| gram[r][c]);
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

/// The largest entry of |AAᵀ − I| for a 3×p block A (row-major), and AAᵀ.
fn gram_deviation(a: &[f64], p: usize) -> (f64, [[f64; 3]; 3]) {
    let mut m = [[0.0; 3]; 3];
    let mut deviation: f64 = 0.0;
    for r in 0..3 {
        for c in r..3 {
            let v: f64 = (0..p).map(|k| a[r * p + k] * a[c * p + k]).sum();
            (m[r][c], m[c][r]) = (v, v);
            deviation = deviation.max((v - if r == c { 1.0 } else { 0.0 }).abs());
        }
    }
    (deviation, m)
}

/// The largest entry of |AAᵀ − I| from which [`polar_by_iteration`] starts: AAᵀ's eigenvalues
/// σ² then lie within 3/4 of 1 (its 2-norm is at most 3 times its largest entry), well inside
/// the iteration's region of convergence, σ² in (0, 3).
const ITERATION_START: f64 = 0.25;

/// The most steps of [`polar_by_iteration`]: from the farthest start, σ² = 1/4, 1 − σ² falls
/// as 0.75, 0.53, 0.25, 0.049, 1.8·10⁻³, 2.5·10⁻⁶, 4.6·10⁻¹², then to rounding in the seventh
/// step; a retraction's blocks (σ² = 1 + |V|² for its step's singular values |V|) start nearer.
const ITERATION_STEPS: usize = 8;

/// Björck and Bowie's iteration for the polar factor (SIAM J. Numer. Anal. 8, 1971; the
/// Newton–Schulz iteration), in the rows' form A ← (3I − AAᵀ) A / 2, column by column of A, in
/// place: each singular value σ of A goes to σ(3 − σ²)/2 (1 − σ to about (3/2)(1 − σ)²) while
/// the singular vectors stay, so the limit is the polar factor. Started where AAᵀ is within
/// [`ITERATION_START`] of I, it stops once AAᵀ is within (p + 3)ε of I, entrywise; `Err` with
/// AAᵀ of A as left where it does not start (A untouched) or has not converged in
/// [`ITERATION_STEPS`] steps (A then holds its last iterate, whose polar factor is A's), for
/// [`polar_rows`]'s eigen-solver. A few hundred flops per block at rank 3 against the symmetric
/// eigen-solver's iterations. With [`rotation_by_newton`], whole process
/// against the eigen-solver and the SVD, each binary copied 8 times (4 for the large files) and
/// copy paired with copy, 25 interleaved rounds (4): tinyGrid3D 0.99, smallGrid3D 0.96-0.98,
/// parking-garage 0.95, sphere2500 0.93, sphere_bignoise_vertex3 0.95, torus3D 1.00, cubicle
/// 1.01. (Copies of one binary alone differ by up to 13% on tinyGrid3D, where the kernel holds
/// their pages: a pair of binaries measured once is not enough for a small file.)
fn polar_by_iteration(a: &mut [f64], p: usize) -> Result<(), [[f64; 3]; 3]> {
    let (mut deviation, mut m) = gram_deviation(a, p);
    // Also where A holds a NaN: the eigen-solver's path refuses it.
    if deviation.is_nan() || deviation >= ITERATION_START {
        return Err(m);
    }
    let tolerance = (p + 3) as f64 * f64::EPSILON;
    for _ in 0..ITERATION_STEPS {
        if deviation <= tolerance {
            return Ok(());
        }
        // (3I − AAᵀ)A/2 = A − EA with E = (AAᵀ − I)/2, the small correction computed apart
        // (at smallGrid3D's optimum the form T·A, T = (3I − AAᵀ)/2, left a gradient of 10⁻⁵
        // where the eigen-solver's retraction reached 3·10⁻⁹): each column of A (its three
        // entries) less E times it.
        let e: [[f64; 3]; 3] = std::array::from_fn(|r| {
            std::array::from_fn(|s| (m[r][s] - if r == s { 1.0 } else { 0.0 }) / 2.0)
        });
        for k in 0..p {
            let column = [a[k], a[p + k], a[2 * p + k]];
            for r in 0..3 {
                a[r * p + k] =
                    column[r] - (e[r][0] * column[0] + e[r][1] * column[1] + e[r][2] * column[2]);
            }
        }
        (deviation, m) = gram_deviation(a, p);
    }
    if deviation <= tolerance {
        Ok(())
    } else {
        Err(m)
    }
}

/// The nearest rotation to a 3x3 matrix (polar factor with the determinant's sign fixed:
/// U diag(1, 1, det(UVᵀ)) Vᵀ), row-major: by Newton's iteration where det M is positive and M
/// far from singular ([`rotation_by_newton`]), else by the SVD.
pub fn nearest_rotation(m: &[f64; 9]) -> [f64; 9] {
    rotation_by_newton(m).unwrap_or_else(|| nearest_rotation_by_svd(m))
}

/// The inverse of a 3x3 matrix (row-major) by its cofactors, and its determinant.
fn inverse3(x: &[f64; 9]) -> ([f64; 9], f64) {
    let c = |r: usize, s: usize| x[r * 3 + s];
    // The cofactor of (r, s), at (s, r) of the adjugate.
    let cof = |r: usize, s: usize| {
        let (r1, r2, s1, s2) = ((r + 1) % 3, (r + 2) % 3, (s + 1) % 3, (s + 2) % 3);
        c(r1, s1) * c(r2, s2) - c(r1, s2) * c(r2, s1)
    };
    let det = c(0, 0) * cof(0, 0) + c(0, 1) * cof(0, 1) + c(0, 2) * cof(0, 2);
    (std::array::from_fn(|k| cof(k % 3, k / 3) / det), det)
}

/// The Frobenius norm.
fn frobenius(x: &[f64; 9]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// The smallest det M / (‖M‖_F/√3)³ (1 for a rotation, 0 for a singular M) from which
/// [`rotation_by_newton`] is used: below it M is near a reflection or a singular matrix, where
/// the SVD decides the sign and the direction.
const NEWTON_MIN_DETERMINANT: f64 = 1e-3;

/// The most steps of [`rotation_by_newton`]: with Higham's scaling it settled in 4 or 5 steps
/// on every chordal block of the public 3D files, in at most 6 on the test's matrices.
const NEWTON_STEPS: usize = 12;

/// The polar factor of M by Newton's iteration X ← (ζX + (ζX)⁻ᵀ)/2 with Higham's scaling
/// ζ = (‖X⁻¹‖_F / ‖X‖_F)^{1/2} (Higham, SIAM J. Sci. Stat. Comput. 7, 1986), which converges
/// quadratically to it from any nonsingular M; where det M > 0 the polar factor is the nearest
/// rotation. `None` where det M is below [`NEWTON_MIN_DETERMINANT`] of ‖M‖_F³'s scale or the
/// iteration has not settled (the change of a step within 4ε of X) in [`NEWTON_STEPS`].
fn rotation_by_newton(m: &[f64; 9]) -> Option<[f64; 9]> {
    let scale = frobenius(m) / 3f64.sqrt();
    let mut x = *m;
    for step in 0..NEWTON_STEPS {
        let (inverse, det) = inverse3(&x);
        // M's own determinant against its scale, then each iterate's sign.
        let least = if step == 0 {
            NEWTON_MIN_DETERMINANT * scale * scale * scale
        } else {
            0.0
        };
        if !(det > least && det.is_finite()) {
            return None;
        }
        let zeta = (frobenius(&inverse) / frobenius(&x)).sqrt();
        // (ζX + X⁻ᵀ/ζ)/2: X⁻ᵀ's entry (r, s) is X⁻¹'s (s, r).
        let next: [f64; 9] =
            std::array::from_fn(|k| (zeta * x[k] + inverse[(k % 3) * 3 + k / 3] / zeta) / 2.0);
        let change = next
            .iter()
            .zip(&x)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        x = next;
        if change <= 4.0 * f64::EPSILON * frobenius(&x) {
            return Some(x);
        }
    }
    None
}

/// [`nearest_rotation`] by nalgebra's SVD.
fn nearest_rotation_by_svd(m: &[f64; 9]) -> [f64; 9] {
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

    /// The polar factor U Vᵀ of a 3×p block from nalgebra's SVD (A = U Σ Vᵀ), row-major.
    fn polar_by_svd(a: &[f64], p: usize) -> Vec<f64> {
        let m = nalgebra::DMatrix::from_row_slice(3, p, a);
        let svd = m.svd(true, true);
        let q = svd.u.unwrap() * svd.v_t.unwrap();
        (0..3 * p).map(|k| q[(k / p, k % p)]).collect()
    }

    /// The largest entry of |a − b|.
    fn max_difference(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    }

    /// Björck and Bowie's iteration from blocks A near St(3, p) (X + V for a random V of size
    /// 10⁻⁸ to 0.2, as retractions meet them) gives the factor Q that characterizes the polar
    /// one, rows orthonormal to (p + 3)ε and AQᵀ symmetric to 4ε, and the SVD's U Vᵀ to
    /// 5·10⁻¹⁴ (which the SVD's vectors of clustered singular values hold to no better); from
    /// blocks far from it (random Gaussian ones) it does not start, and `polar_rows` gives the
    /// SVD's factor by the eigenvectors instead.
    #[test]
    fn the_polar_factor_is_the_svds() {
        let mut rng = crate::linalg::rng::Rng::new(5);
        for p in [3, 4, 5, 8, 12] {
            for size in [1e-8, 1e-4, 1e-2, 0.1, 0.2] {
                let mut a = block(p, 100 + p as u64);
                for z in a.iter_mut() {
                    *z += size * rng.normal() / (3.0 * p as f64).sqrt();
                }
                let expected = polar_by_svd(&a, p);
                let mut b = a.clone();
                assert!(polar_by_iteration(&mut b, p).is_ok(), "p {p} size {size}");
                let worst = max_difference(&b, &expected);
                assert!(worst < 5e-14, "p {p} size {size}: {worst:e}");
                assert!(gram_deviation(&b, p).0 <= (p + 3) as f64 * f64::EPSILON);
                // The polar factor Q of A is the Q with orthonormal rows and AQᵀ symmetric
                // (positive definite): A = (AQᵀ) Q.
                for r in 0..3 {
                    for c in 0..r {
                        let rc: f64 = (0..p).map(|k| a[r * p + k] * b[c * p + k]).sum();
                        let cr: f64 = (0..p).map(|k| a[c * p + k] * b[r * p + k]).sum();
                        assert!((rc - cr).abs() < 4.0 * f64::EPSILON, "p {p} size {size}");
                    }
                }
            }
            let mut far: Vec<f64> = (0..3 * p).map(|_| rng.normal()).collect();
            let expected = polar_by_svd(&far, p);
            let mut untouched = far.clone();
            assert!(polar_by_iteration(&mut untouched, p).is_err());
            assert_eq!(untouched, far);
            assert!(polar_rows(&mut far, p));
            let worst = max_difference(&far, &expected);
            assert!(worst < 1e-11, "p {p} far: {worst:e}");
        }
    }

    /// A rotation row-major: Rᵀ R = I to 4ε and det R = 1 to 8ε.
    fn assert_rotation(r: &[f64; 9], what: &str) {
        for a in 0..3 {
            for b in 0..3 {
                let d: f64 = (0..3).map(|k| r[k * 3 + a] * r[k * 3 + b]).sum();
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((d - want).abs() <= 4.0 * f64::EPSILON, "{what}: RᵀR {d}");
            }
        }
        let det = inverse3(r).1;
        assert!((det - 1.0).abs() <= 8.0 * f64::EPSILON, "{what}: det {det}");
    }

    /// Newton's iteration gives the SVD's nearest rotation to 2·10⁻¹³, and a rotation, on
    /// rotations scaled along their axes by 1, 1 to 2 and 1 or 10, exact or perturbed (10⁻⁶,
    /// 0.1); it does not start where the third scale is 10³ (det M / (‖M‖_F/√3)³ near 10⁻⁵), for
    /// a reflection or a singular M, and there `nearest_rotation` is the SVD's bit for bit.
    #[test]
    fn the_nearest_rotation_is_the_svds() {
        let mut rng = crate::linalg::rng::Rng::new(11);
        for trial in 0..400 {
            // Q diag(s) plus noise, Q a random rotation (a polar factor of a Gaussian block).
            let q = block(3, 1000 + trial);
            let q: [f64; 9] = std::array::from_fn(|k| q[k]);
            let q = nearest_rotation_by_svd(&q);
            let spread = [1.0, 10.0, 1e3][trial as usize % 3];
            let s = [1.0, 1.0 + rng.normal().abs(), spread];
            let noise = [0.0, 1e-6, 0.1][(trial as usize / 3) % 3];
            let m: [f64; 9] = std::array::from_fn(|k| q[k] * s[k % 3] + noise * rng.normal());
            let expected = nearest_rotation_by_svd(&m);
            match rotation_by_newton(&m) {
                Some(r) => {
                    assert_rotation(&r, &format!("trial {trial}"));
                    let worst = max_difference(&r, &expected);
                    assert!(worst < 2e-13, "trial {trial}: {worst:e}");
                }
                None => assert!(spread == 1e3, "trial {trial} refused"),
            }
            // det M / (‖M‖_F/√3)³ about 10⁻⁵: left to the SVD.
            if spread == 1e3 {
                assert!(rotation_by_newton(&m).is_none(), "trial {trial}");
            }
            // A reflection, and a singular matrix: the SVD's answer.
            let reflected: [f64; 9] =
                std::array::from_fn(|k| if k / 3 == 2 { -m[k] } else { m[k] });
            assert!(rotation_by_newton(&reflected).is_none());
            assert_eq!(
                nearest_rotation(&reflected),
                nearest_rotation_by_svd(&reflected)
            );
            let singular: [f64; 9] = std::array::from_fn(|k| if k % 3 == 2 { 0.0 } else { m[k] });
            assert!(rotation_by_newton(&singular).is_none());
        }
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
