//! The per-sample random numbers: a SplitMix64 stream (Steele, Lea & Flood 2014, the seeding
//! generator of `java.util.SplittableRandom` and of xoshiro) whose state starts at a hash of
//! `(seed, index)`, so sample `index` draws the same numbers whatever else is rendered, in
//! whatever order. Written out here rather than taken from a crate so a dataset's bytes cannot
//! change with a dependency's version.
//!
//! - state `s₀ = mix(mix(seed) ⊕ index·φ)`, `φ = 0x9E3779B97F4A7C15` (2⁶⁴ / golden ratio);
//! - each draw: `s += φ`, `z = s`, `z = (z ⊕ z≫30)·0xBF58476D1CE4E5B9`,
//!   `z = (z ⊕ z≫27)·0x94D049BB133111EB`, `z ⊕ z≫31`;
//! - a uniform in [0, 1): the top 53 bits of a draw over 2⁵³.

/// The SplitMix64 increment, 2⁶⁴ divided by the golden ratio.
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function (a bijection of `u64`).
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The random numbers of one sample.
#[derive(Clone, Debug)]
pub struct SampleRng {
    state: u64,
}

impl SampleRng {
    /// The stream of sample `index` of the dataset seeded `seed`.
    pub fn new(seed: u64, index: u64) -> SampleRng {
        SampleRng {
            state: mix(mix(seed) ^ index.wrapping_mul(GOLDEN)),
        }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN);
        mix(self.state)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi] (`lo` when they are equal).
    pub fn uniform(&mut self, [lo, hi]: [f64; 2]) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Log-uniform in [lo, hi] (both positive): each octave equally likely.
    pub fn log_uniform(&mut self, [lo, hi]: [f64; 2]) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.unit()).exp()
    }

    /// A whole number uniform in lo..=hi.
    pub fn int(&mut self, [lo, hi]: [u32; 2]) -> u32 {
        let n = u64::from(hi - lo) + 1;
        // `n` ≤ 2³²: the bias of the remainder is below 2⁻³².
        lo + (self.next_u64() % n) as u32
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }

    /// An index drawn with probability proportional to `weights` (positive, not all zero).
    pub fn weighted(&mut self, weights: &[f64]) -> usize {
        let total: f64 = weights.iter().sum();
        let mut x = self.unit() * total;
        for (i, w) in weights.iter().enumerate() {
            if x < *w {
                return i;
            }
            x -= w;
        }
        weights.len() - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_gives_the_published_sequence() {
        // SplitMix64 from state 0: the first outputs of the reference implementation
        // (prng.di.unimi.it/splitmix64.c).
        let mut r = SampleRng { state: 0 };
        assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
        assert_eq!(r.next_u64(), 0x06C4_5D18_8009_454F);
    }

    #[test]
    fn streams_depend_on_seed_and_index_only() {
        let a: Vec<u64> = (0..4).map(|_| SampleRng::new(7, 3).next_u64()).collect();
        assert!(a.iter().all(|&x| x == a[0]));
        assert_ne!(
            SampleRng::new(7, 3).next_u64(),
            SampleRng::new(7, 4).next_u64()
        );
        assert_ne!(
            SampleRng::new(7, 3).next_u64(),
            SampleRng::new(8, 3).next_u64()
        );
    }

    #[test]
    fn draws_stay_in_their_ranges() {
        let mut r = SampleRng::new(1, 2);
        for _ in 0..10_000 {
            let u = r.unit();
            assert!((0.0..1.0).contains(&u));
            let l = r.log_uniform([1.4, 16.0]);
            assert!((1.4..=16.0).contains(&l));
            let k = r.int([5, 9]);
            assert!((5..=9).contains(&k));
            assert!(r.weighted(&[1.0, 0.0, 2.0]) != 1);
        }
    }
}
