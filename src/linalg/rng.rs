//! The seeded pseudorandom generator of the simulations ([`crate::simulate`]) and of the
//! eigensolver's random starts ([`crate::linalg::subspace`]): our own, not a crate whose stream
//! could change with its version, so that the same seed gives the same bits everywhere.

use std::f64::consts::{PI, TAU};

/// SplitMix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number generators", 2014;
/// Vigna's reference `splitmix64.c`): a Weyl sequence with step 0x9E3779B97F4A7C15 put through a
/// bijective mixer. Used only to expand a 64-bit seed into xoshiro256** states.
#[derive(Debug, Clone)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    pub fn new(seed: u64) -> Self {
        SplitMix64 { state: seed }
    }

    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// xoshiro256** 1.0 (Blackman and Vigna, "Scrambled linear pseudorandom number generators",
/// 2021; reference `xoshiro256starstar.c`), period 2²⁵⁶ − 1, with the deviates the simulation
/// needs. Its output depends on integer arithmetic only; see the module documentation for the
/// floating-point deviates.
#[derive(Debug, Clone)]
pub struct Rng {
    s: [u64; 4],
    /// The second normal of the last Box-Muller pair, not yet used.
    spare_normal: Option<f64>,
}

impl Rng {
    /// A generator whose state is the next four outputs of `seeder` (never all zero: SplitMix64's
    /// mixer is a bijection, so at most one of four consecutive outputs is zero).
    pub fn from_splitmix(seeder: &mut SplitMix64) -> Self {
        Rng {
            s: std::array::from_fn(|_| seeder.next_u64()),
            spare_normal: None,
        }
    }

    /// A generator seeded from `seed` through SplitMix64.
    pub fn new(seed: u64) -> Self {
        Self::from_splitmix(&mut SplitMix64::new(seed))
    }

    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let result = s[1].wrapping_mul(5).rotate_left(7).wrapping_mul(9);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// Uniform in [0, 1): the top 53 bits of a draw times 2⁻⁵³ (exact).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in (−π, π]: π − 2π·u, u uniform in [0, 1).
    pub fn angle(&mut self) -> f64 {
        let a = PI - TAU * self.uniform();
        // 2π·u rounds below 2π for every u < 1, so a > −π; kept as a guard.
        if a <= -PI { PI } else { a }
    }

    /// Standard normal by the Box-Muller transform: u₁ in (0, 1], u₂ in [0, 1),
    /// r = √(−2 ln u₁), z = (r cos 2πu₂, r sin 2πu₂); the second of the pair is returned by the
    /// next call.
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare_normal.take() {
            return z;
        }
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        let r = (-2.0 * u1.ln()).sqrt();
        let t = TAU * u2;
        self.spare_normal = Some(r * t.sin());
        r * t.cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vigna's reference splitmix64.c from state 0 (also the first values quoted for it in
    /// many ports).
    #[test]
    fn splitmix64_reference_values() {
        let mut g = SplitMix64::new(0);
        assert_eq!(g.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(g.next_u64(), 0x6E78_9E6A_A1B9_65F4);
        assert_eq!(g.next_u64(), 0x06C4_5D18_8009_454F);
    }

    /// The reference xoshiro256starstar.c from state {1, 2, 3, 4}.
    #[test]
    fn xoshiro256starstar_reference_values() {
        let mut g = Rng {
            s: [1, 2, 3, 4],
            spare_normal: None,
        };
        let v: Vec<u64> = (0..4).map(|_| g.next_u64()).collect();
        assert_eq!(v, [11520, 0, 1509978240, 1215971899390074240]);
    }

    #[test]
    fn angle_deviates_are_in_half_open_interval() {
        let mut g = Rng::new(7);
        for _ in 0..100_000 {
            let a = g.angle();
            assert!(a > -PI && a <= PI);
        }
    }
}
