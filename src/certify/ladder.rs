//! What the sparse certificates share, whatever the scalar (ℂ in 2D, ℝ in 3D) and the number k of
//! eigenvalues they deflate (1 in 2D, 3 in 3D: the estimate's null directions): the power-of-two
//! equilibration and the ladder of shifts μ that isolates the k smallest eigenvalues of an
//! equilibrated matrix B by the inertia of LDLᴴ factorizations of B − μI (Sylvester's law: with
//! at most k negative pivots, and E the factorization's backward error plus the rounding of B
//! itself, λ_{k+1}(B) ≥ θ = μ − ‖E‖). Used by [`super::sparse::SparseCertifier`] and
//! [`crate::se3::certificate`].

use crate::linalg::residual::Chunk;

/// D_k = 2^{−⌊log₂(a)/2⌋} for a diagonal entry a > 0: D_k² a lies in [1, 4), and scaling by it is
/// exact.
pub fn power_of_two_scale(a: f64) -> f64 {
    let e = (a.log2() / 2.0).floor();
    2f64.powi(-(e as i32))
}

/// Where a certifier's next ladder starts: what its last successful one found.
#[derive(Debug, Clone, Copy, Default)]
pub struct ShiftMemory {
    /// The shift that isolated the k eigenvalues last time.
    last: Option<f64>,
    /// The lowest shift of that ladder with more than k below it, if it tried one.
    above: Option<f64>,
}

impl ShiftMemory {
    /// The shift to start from: where none worked yet, [`first_shift`]; else 64 times the last
    /// one (its gap may have grown since, and a larger shift proves a larger θ), unless that
    /// ladder already saw more than k eigenvalues below a shift within those 64 times (the gap
    /// of a nearby point seldom moves that far): then the last shift itself. At most 1/16.
    pub fn start(&self, k: usize, n: usize) -> f64 {
        match (self.last, self.above) {
            (None, _) => first_shift(k, n),
            (Some(m), Some(a)) if a <= 64.0 * m => m.min(CEILING),
            (Some(m), _) => (64.0 * m).min(CEILING),
        }
    }

    /// Records a ladder's outcome: a [`Ladder::Found`] becomes the next start; anything else
    /// leaves the memory as it was.
    pub fn remember(&mut self, ladder: &Ladder) {
        if let Ladder::Found { mu, above, .. } = *ladder {
            *self = ShiftMemory {
                last: Some(mu),
                above,
            };
        }
    }

    /// Records a shift proven outside the ladder (the double-double retry).
    pub fn remember_shift(&mut self, mu: f64) {
        *self = ShiftMemory {
            last: Some(mu),
            above: None,
        };
    }

    /// The next ladder is for the same gap (the same minimum, polished): it starts at the last
    /// shift itself.
    pub fn hold(&mut self) {
        self.above = self.above.or(self.last);
    }
}

/// The smallest j in 0..=`top` with `proves(j)`, for a test that holds from some j on (a
/// shifted factorization η_j = η₀·2^j of a matrix whose PSD-ness is monotone in η), or `None` if
/// it fails at `top`: j = 0 first (the common case: a proof at the resolution), then `top` (if
/// even that fails, none will), then bisection between. At most 2 + ⌈log₂ top⌉ tests. Where
/// rounding makes the test not quite monotone, the j returned still passed it.
pub fn smallest_doubling(top: i32, mut proves: impl FnMut(i32) -> bool) -> Option<i32> {
    if proves(0) {
        return Some(0);
    }
    if top <= 0 || !proves(top) {
        return None;
    }
    // Fails at lo, holds at hi.
    let (mut lo, mut hi) = (0, top);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if proves(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(hi)
}

/// The first shift of the ladder for a matrix of `n` poses with k eigenvalues at zero, when no
/// earlier certificate of the same matrix suggests one: μ₀ = (k / (c·n))² / 16 with c = 1/2,
/// that is (k/n)²/4, at most 1/16 (B's diagonal lies in [1, 4)). The count of eigenvalues of an
/// equilibrated pose graph matrix below μ grows like c·n·√(16μ) (the bending modes of a
/// corridor: Weyl's law in one dimension), with c from 0.03 (city10000) to 0.25
/// (parking-garage) on the public pose graphs at μ = 1/16, and more on the long landmark
/// trajectory of victoriaPark (two eigenvalues below (1/n)²); at μ₀ at most about k lie below,
/// so one factorization usually isolates them, where starting at 1/16 took three (the first with
/// 100-1400 negative pivots). c is above the largest seen because the costs are lopsided: a
/// shift too high costs a whole factorization (the next rung, 64 times lower), one too low only
/// θ, the proven gap, by the same factor, and the deflated bound is set by the estimate's
/// residual more than by θ. With c = 1/10 ten public planar files took two factorizations and
/// ring three; with 1/4 eight of the ten (FRH, M3500a-c, MIT, kitti_02, 07, 09) take one, ring
/// two. With 1/2 victoriaPark and kitti_08 take one instead of two, ais2klinik four instead
/// of five, parking-garage two instead of three, and no file of the 38 certified ones more;
/// their bounds loosen by at most 4x (cubicle 1.1e-9 to 4.4e-9 relative, cityTrees10000 9.1e-10
/// to 3.3e-9), far within the tolerance, and tighten where a rung is saved (parking-garage
/// 1.1e-8 to 1.6e-9). With 1 tinyGrid3D takes one instead of two but ais2klinik five again,
/// and the bounds loosen 16x. Only the number of factorizations and θ depend on it: the proof
/// holds at whatever shift [`isolate`] stops.
pub fn first_shift(k: usize, n: usize) -> f64 {
    let c = 0.5;
    ((k as f64 / (c * n.max(1) as f64)).powi(2) / 16.0).min(CEILING)
}

/// The outcome of [`isolate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Ladder {
    /// λ_{k+1}(B) ≥ θ > 0 proven at shift μ, with `negative` ≤ k negative pivots.
    Found {
        theta: f64,
        negative: usize,
        mu: f64,
        /// The lowest shift tried with more than k below it, if any.
        above: Option<f64>,
    },
    /// At most k pivots are negative at μ, but the rounding hides the gap there: the error bound
    /// `floor` (the factorization's backward error plus `assembly`) is at least μ (the caller
    /// may retry in higher precision).
    Hidden { mu: f64, floor: f64 },
    /// No shift isolates k eigenvalues, or a factorization could not be formed.
    Failed,
}

/// θ = μ − ‖E‖ − `rest` at a rung the rounding hid ([`Ladder::Hidden`]), with ‖E‖ the LDLᴴ's
/// residual measured (`measure(chunk)`: `SparseFactor::ldlt_residual_bound` of the factor at μ,
/// by the wide chunks, then the narrow) in place of its a-priori bound; `rest` the other
/// roundings (the shifted diagonal's and the assembly's). `Ok(θ)` where positive, else
/// `Err(‖E‖)` as last measured (`None`: not measurable).
pub fn measured_theta(
    mu: f64,
    rest: f64,
    measure: impl Fn(Chunk) -> Option<f64>,
) -> Result<f64, Option<f64>> {
    let mut measured = None;
    for chunk in [Chunk::Wide, Chunk::Narrow] {
        let error = measure(chunk).ok_or(measured)?;
        let theta = mu - error - rest;
        if theta > 0.0 {
            return Ok(theta);
        }
        measured = Some(error);
    }
    Err(measured)
}

/// The highest shift of the ladder: B's diagonal lies in [1, 4) before the shift.
const CEILING: f64 = 1.0 / 16.0;

/// The shift ladder: μ from `start` down by 64 (by 4096 while 100 or more pivots are negative:
/// the count of eigenvalues below μ falls like a power of μ, Weyl's law) while more than k are
/// negative, at most 8 rungs and not below 4·`assembly`. Neither the start nor a step down goes
/// below 4·`error_floor` ([`crate::linalg::factor::ldlt_error_floor`]: a rung below it is hidden
/// by the rounding whatever its inertia, one at 4·`error_floor` is likely to show the gap),
/// unless a rung there had more than k below. (At 10⁶ poses the first shift, 1e-12, lay under a
/// floor of 1.3e-11: its factorization, a third of the certificate's, showed nothing.) Once,
/// where a step down would land within 9/8 of the error bound the last rung measured, the
/// log-scale middle between that bound and μ instead. Where the
/// rounding hides the gap at the first rung with at most k: up while no rung above was tried (a
/// first shift guessed below the rounding level, [`first_shift`]), to twice the error bound that
/// rung showed (by 2 to 64), then three log-scale bisections between the hidden rung and the rung
/// above. `inertia(μ)` factors B − μI: `Some(Some((negative pivots, backward error)))`,
/// `Some(None)` on a zero pivot, `None` when the matrix cannot be formed (then no shift will do).
/// `assembly` bounds the difference between the stored B and the exact one.
pub fn isolate(
    k: usize,
    start: f64,
    assembly: f64,
    error_floor: f64,
    mut inertia: impl FnMut(f64) -> Option<Option<(usize, f64)>>,
) -> Ladder {
    let lowest = 4.0 * error_floor;
    let mut mu = if start < lowest {
        lowest.min(CEILING)
    } else {
        start
    };
    // The lowest shift with more than k negative pivots, and the last with at most k where the
    // rounding hid the gap.
    let mut above: Option<f64> = None;
    let mut hidden: Option<(f64, f64)> = None;
    let mut middle_tried = false;
    for _ in 0..8 {
        match rung(k, mu, assembly, &mut inertia) {
            Rung::Proven { theta, negative } => {
                return Ladder::Found {
                    theta,
                    negative,
                    mu,
                    above,
                };
            }
            Rung::Failed => return Ladder::Failed,
            Rung::Hidden { floor } => {
                hidden = Some((mu, floor));
                match above {
                    // λ_{k+1} may lie well above μ: try higher first, at twice the level the
                    // rounding showed (θ = μ − floor then is that level), up by 64 at most.
                    None if mu < CEILING => {
                        mu = (2.0 * floor).clamp(2.0 * mu, 64.0 * mu).min(CEILING)
                    }
                    _ => return bisect(k, (mu, floor), above, assembly, &mut inertia),
                }
                continue;
            }
            Rung::Above { many, floor } => {
                if let Some(low) = hidden {
                    // Too many below μ, the gap hidden at the shift below: in between.
                    return bisect(k, low, Some(mu), assembly, &mut inertia);
                }
                above = Some(mu);
                let next = mu / if many { 4096.0 } else { 64.0 };
                let next = if mu > lowest { next.max(lowest) } else { next };
                // The error bound barely moves with μ: a rung at most 9/8 of the one just
                // measured would show θ ≤ 0 whatever its inertia. Once, the log-scale middle
                // between that bound and μ instead, where there is room: a gap there is proven
                // one rung sooner (ais2klinik: 4 factorizations to 3); below it (or under the
                // rounding) the ladder goes on down as before, one rung later, so that a rung
                // with the gap hidden is still reached for the double-double retry.
                mu = match floor {
                    Some(f) if !middle_tried && next <= 1.125 * f && mu > 1.125 * f => {
                        middle_tried = true;
                        (f * mu).sqrt()
                    }
                    _ => next,
                };
            }
        }
        if mu < 4.0 * assembly {
            break;
        }
    }
    match hidden {
        Some((mu, floor)) => Ladder::Hidden { mu, floor },
        None => Ladder::Failed,
    }
}

/// What one factorization of B − μI shows.
enum Rung {
    /// At most k negative pivots and θ = μ − ‖E‖ > 0: [`Ladder::Found`].
    Proven { theta: f64, negative: usize },
    /// At most k negative pivots, but θ ≤ 0: the error bound ‖E‖ (`floor`) is at least μ.
    Hidden { floor: f64 },
    /// More than k negative pivots (`many`: 100 or more), or a zero pivot; `floor`, the error
    /// bound ‖E‖ plus `assembly` of the factorization, where one was completed.
    Above { many: bool, floor: Option<f64> },
    /// The matrix could not be formed.
    Failed,
}

fn rung(
    k: usize,
    mu: f64,
    assembly: f64,
    inertia: &mut impl FnMut(f64) -> Option<Option<(usize, f64)>>,
) -> Rung {
    match inertia(mu) {
        None => Rung::Failed,
        Some(Some((negative, error))) if negative <= k => {
            let theta = mu - error - assembly;
            if theta > 0.0 {
                Rung::Proven { theta, negative }
            } else {
                Rung::Hidden {
                    floor: error + assembly,
                }
            }
        }
        Some(other) => Rung::Above {
            many: matches!(other, Some((negative, _)) if negative >= 100),
            floor: other.map(|(_, error)| error + assembly),
        },
    }
}

/// Three log-scale bisections between `hidden` (a shift with at most k negative pivots, the gap
/// hidden by the rounding, and its error bound) and the shift `above` it with more than k, if
/// any: the first midpoint where the gap shows, else [`Ladder::Hidden`] at the highest shift
/// with at most k.
fn bisect(
    k: usize,
    hidden: (f64, f64),
    mut above: Option<f64>,
    assembly: f64,
    inertia: &mut impl FnMut(f64) -> Option<Option<(usize, f64)>>,
) -> Ladder {
    let (mut mu, mut floor) = hidden;
    if let Some(mut hi) = above {
        for _ in 0..3 {
            let mid = (mu * hi).sqrt();
            match rung(k, mid, assembly, inertia) {
                Rung::Proven { theta, negative } => {
                    return Ladder::Found {
                        theta,
                        negative,
                        mu: mid,
                        above,
                    };
                }
                Rung::Failed => return Ladder::Failed,
                Rung::Hidden { floor: f } => (mu, floor) = (mid, f),
                Rung::Above { .. } => {
                    hi = mid;
                    above = Some(mid);
                }
            }
        }
    }
    Ladder::Hidden { mu, floor }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::factor::ldlt_error_floor;

    /// A diagonal "matrix" with known eigenvalues: the inertia of B − μI counts those below μ.
    fn ladder(eigenvalues: &[f64], k: usize, error: f64) -> (Ladder, Vec<f64>) {
        ladder_from(1.0 / 16.0, eigenvalues, k, error)
    }

    fn ladder_from(start: f64, eigenvalues: &[f64], k: usize, error: f64) -> (Ladder, Vec<f64>) {
        ladder_above(start, 0.0, eigenvalues, k, error)
    }

    /// The ladder with an a-priori rounding floor.
    fn ladder_above(
        start: f64,
        floor: f64,
        eigenvalues: &[f64],
        k: usize,
        error: f64,
    ) -> (Ladder, Vec<f64>) {
        let mut shifts = Vec::new();
        let l = isolate(k, start, 0.0, floor, |mu| {
            shifts.push(mu);
            Some(Some((
                eigenvalues.iter().filter(|&&e| e < mu).count(),
                error,
            )))
        });
        (l, shifts)
    }

    #[test]
    fn the_ladder_isolates_k_eigenvalues_and_proves_the_next_one() {
        // Three at zero, the fourth at 1e-3: μ = 1/16 sees 5 below, 1/1024 sees 3.
        let eig = [0.0, 0.0, 0.0, 1e-3, 2e-3, 1.0];
        let (l, shifts) = ladder(&eig, 3, 1e-9);
        assert_eq!(shifts, vec![1.0 / 16.0, 1.0 / 1024.0]);
        match l {
            Ladder::Found {
                theta, negative, ..
            } => {
                assert_eq!(negative, 3);
                assert!(theta > 0.0 && theta <= 1e-3, "{theta}");
            }
            other => panic!("{other:?}"),
        }
        // With k = 1 the same matrix never isolates: three are at zero.
        assert_eq!(ladder(&eig, 1, 1e-9).0, Ladder::Failed);
        // An error above the shift: the gap is hidden, reported with that error (the last
        // shift tried with at most 3 below; here the error holds at every shift).
        let (l, shifts) = ladder(&eig, 3, 1.0);
        match l {
            Ladder::Hidden { mu, floor } => {
                assert_eq!(floor, 1.0);
                assert!(shifts.contains(&mu) && eig.iter().filter(|&&e| e < mu).count() <= 3);
            }
            other => panic!("{other:?}"),
        }
        assert!((power_of_two_scale(10.0).powi(2) * 10.0 - 2.5).abs() < 1e-15);
    }

    #[test]
    fn a_first_shift_below_the_rounding_climbs_to_twice_its_error_and_bisects() {
        // Hidden at 1e-8 (error 1e-6): up to 2e-6 but by 64 at most, so 6.4e-7, hidden again,
        // then 2e-6, where θ = 2e-6 − 1e-6 is proven.
        let (l, shifts) = ladder_from(1e-8, &[0.0, 1e-3, 1.0], 1, 1e-6);
        assert_eq!(shifts, vec![1e-8, 64.0 * 1e-8, 2e-6]);
        match l {
            Ladder::Found {
                theta, mu, above, ..
            } => {
                assert_eq!((mu, above), (2e-6, None));
                assert!((theta - 1e-6).abs() < 1e-20, "{theta}");
            }
            other => panic!("{other:?}"),
        }
        // Hidden at 1e-7 (error 5e-7), up to 1e-6 where three lie below (8e-7 twice): bisection
        // between 1e-7 and 1e-6, hidden at √(1e-13) ≈ 3.2e-7, proven at √(3.2e-7 · 1e-6) ≈ 5.6e-7.
        let (l, shifts) = ladder_from(1e-7, &[0.0, 8e-7, 8e-7, 1.0], 1, 5e-7);
        let (m1, m2) = (
            (1e-7f64 * 1e-6).sqrt(),
            ((1e-7f64 * 1e-6).sqrt() * 1e-6).sqrt(),
        );
        assert_eq!(shifts, vec![1e-7, 1e-6, m1, m2]);
        match l {
            Ladder::Found {
                theta, mu, above, ..
            } => {
                assert_eq!((mu, above), (m2, Some(1e-6)));
                assert!((theta - (m2 - 5e-7)).abs() < 1e-20, "{theta}");
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn no_rung_below_four_times_the_error_floor_unless_one_there_saw_too_many() {
        // The 10⁶-pose case: a first shift of 1e-12 under a floor of 1.3e-11 (error 3.3e-11)
        // would be hidden; the ladder starts at 5.2e-11 and proves θ = 1.9e-11 there.
        let eig = [0.0, 2e-10, 1.0];
        let (l, shifts) = ladder_above(1e-12, 1.3e-11, &eig, 1, 3.3e-11);
        assert_eq!(shifts, vec![4.0 * 1.3e-11]);
        assert!(matches!(l, Ladder::Found { mu, .. } if mu == 4.0 * 1.3e-11));
        // A step down by 64 from 1e-8 would land at 1.6e-10, under 4·floor = 4e-10: it stops
        // there, where only the one at zero lies below.
        let eig = [0.0, 5e-10, 5e-9, 1.0];
        let (_, shifts) = ladder_above(1e-8, 1e-10, &eig, 1, 2e-10);
        assert_eq!(shifts, vec![1e-8, 4e-10]);
        // Too many below 4·floor too: once the middle between the error bound measured there
        // (2e-10) and 4e-10, then down by 64 from there as before (hidden), then bisection
        // between, ending hidden (λ₂ lies under the rounding) for the double-double retry.
        let eig = [0.0, 1e-10, 1.0];
        let (l, shifts) = ladder_above(1e-8, 1e-10, &eig, 1, 2e-10);
        let middle = (2e-10f64 * 4e-10).sqrt();
        assert_eq!(&shifts[..4], &[1e-8, 4e-10, middle, middle / 64.0]);
        assert!(matches!(l, Ladder::Hidden { .. }), "{l:?}");
        // The floor: γ_{2k+8}·(row sum) at its largest, here the row with k = 6 (40u against 10u
        // and 36u).
        let floor = ldlt_error_floor(&[1, 6, 2], &[1.0, 2.0, 3.0]);
        assert_eq!(floor, crate::linalg::roundoff::gamma(20) * 2.0);
        // A floor above the ceiling: the start is capped at 1/16.
        assert_eq!(
            ladder_above(1e-3, 1.0, &[0.0, 1.0], 1, 0.0).1[0],
            1.0 / 16.0
        );
    }

    #[test]
    fn the_next_ladder_starts_where_the_last_one_ended() {
        let mut memory = ShiftMemory::default();
        assert_eq!(memory.start(1, 10_000), first_shift(1, 10_000));
        let found = |mu: f64, above: Option<f64>| Ladder::Found {
            theta: mu / 2.0,
            negative: 1,
            mu,
            above,
        };
        // Nothing above tried: 64 times the last shift, at most 1/16.
        memory.remember(&found(0.5f64.powi(20), None));
        assert_eq!(memory.start(1, 10_000), 0.5f64.powi(14));
        // Too many below a shift 8 times the last: the last shift itself.
        memory.remember(&found(0.5f64.powi(20), Some(0.5f64.powi(17))));
        assert_eq!(memory.start(1, 10_000), 0.5f64.powi(20));
        // Too many only 1024 times above: 64 times again.
        memory.remember(&found(0.5f64.powi(20), Some(0.5f64.powi(10))));
        assert_eq!(memory.start(1, 10_000), 0.5f64.powi(14));
        // A failed or hidden ladder leaves the memory; a large shift is capped at 1/16.
        memory.remember(&Ladder::Failed);
        memory.remember(&Ladder::Hidden {
            mu: 1.0,
            floor: 2.0,
        });
        assert_eq!(memory.start(1, 10_000), 0.5f64.powi(14));
        memory.remember(&found(0.5f64.powi(8), None));
        assert_eq!(memory.start(3, 10), 1.0 / 16.0);
        memory.remember_shift(0.5f64.powi(30));
        assert_eq!(memory.start(3, 10), 0.5f64.powi(24));
        // Held for the same gap: the last shift itself, until a ladder is remembered again.
        memory.hold();
        assert_eq!(memory.start(3, 10), 0.5f64.powi(30));
        memory.remember(&found(0.5f64.powi(20), None));
        assert_eq!(memory.start(1, 10_000), 0.5f64.powi(14));
        // Nothing to hold before any shift worked.
        let mut fresh = ShiftMemory::default();
        fresh.hold();
        assert_eq!(fresh.start(1, 10_000), first_shift(1, 10_000));
    }

    #[test]
    fn the_smallest_doubling_is_the_one_a_scan_upward_finds() {
        // Every threshold t (the test holds from j = t on; t > top: never) against the scan
        // j = 0, 1, ... that certify_cholesky ran before, with the number of tests.
        for top in 0..=79 {
            for t in 0..=top + 1 {
                let mut tests = 0;
                let found = smallest_doubling(top, |j| {
                    tests += 1;
                    j >= t
                });
                let scan = (0..=top).find(|&j| j >= t);
                assert_eq!(found, scan, "top {top}, threshold {t}");
                let bound = 2 + (top.max(1) as f64).log2().ceil() as i32;
                assert!(tests <= bound, "top {top}, threshold {t}: {tests} tests");
            }
        }
        // A negative top (the search range is empty above j = 0): only j = 0 is tried.
        assert_eq!(smallest_doubling(-1, |j| j >= 0), Some(0));
        assert_eq!(smallest_doubling(-1, |j| j >= 1), None);
    }

    #[test]
    fn a_rung_between_the_error_bound_just_measured_and_the_last_shift() {
        // A corridor's spectrum near the rounding (ais2klinik's: a gap of ~1.2e-11 just above
        // an error bound of 1.0e-11, the a-priori floor five times lower). From 1.1e-9 the rung
        // 64 times lower, 1.7e-11, sees three below; the next step down (to 4 × the a-priori
        // floor, 8e-12) lies under the error those rungs measured and could only be hidden.
        // Instead the log-scale middle of (1e-11, 1.7e-11) isolates λ₁ and proves θ ≈ 3e-12.
        let eig = [0.0, 1.4e-11, 1.5e-11, 3e-10, 1e-3];
        let (l, shifts) = ladder_above(1.1e-9, 2e-12, &eig, 1, 1e-11);
        let middle = (1e-11f64 * (1.1e-9 / 64.0)).sqrt();
        assert_eq!(shifts, vec![1.1e-9, 1.1e-9 / 64.0, middle]);
        match l {
            Ladder::Found {
                theta, negative, ..
            } => {
                assert_eq!(negative, 1);
                assert!((theta - (middle - 1e-11)).abs() < 1e-24, "{theta}");
            }
            other => panic!("{other:?}"),
        }
        // Where that middle still sees too many, down as before (to 8e-12, hidden) and the
        // bisection between: one rung more than without the middle, the gap proven all the same.
        let eig = [0.0, 1.2e-11, 1.5e-11, 3e-10, 1e-3];
        let (l, shifts) = ladder_above(1.1e-9, 2e-12, &eig, 1, 1e-11);
        assert_eq!(&shifts[..4], &[1.1e-9, 1.1e-9 / 64.0, middle, 8e-12]);
        assert_eq!(shifts.len(), 5, "{shifts:?}");
        assert!(matches!(l, Ladder::Found { negative: 1, .. }), "{l:?}");
    }

    #[test]
    fn the_first_shift_follows_the_one_dimensional_weyl_law() {
        // (k / (n/2))² / 16 = (k/n)²/4, at most 1/16.
        assert_eq!(first_shift(1, 2), 1.0 / 16.0);
        assert!((first_shift(1, 10) - 2.5e-3).abs() < 1e-18);
        assert!((first_shift(1, 10_000) - 2.5e-9).abs() < 1e-24);
        assert!((first_shift(3, 5_000) - 9e-8).abs() < 1e-22);
        assert_eq!(first_shift(1, 0), 1.0 / 16.0);
    }
}
