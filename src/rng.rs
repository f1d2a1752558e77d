//! Random numbers. Renders use counter-based streams: a value is a pure function of (seed, pixel,
//! sample, dimension), so images are bit-identical for any thread count and any batch order. Scene
//! generators, tests and benchmarks use the sequential [`SplitMix64`].

use crate::lanes::LANES;

/// A stream of uniform numbers for one (seed, pixel, sample); `dim` advances per draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleStream {
    key: u64,
    dim: u32,
}

/// A 64-bit mix (splitmix64 finaliser, Steele et al. 2014).
#[inline(always)]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl SampleStream {
    /// The stream of `pixel`'s `sample`-th sample under `seed`.
    pub fn new(seed: u64, pixel: u32, sample: u32) -> Self {
        let key = mix64(seed ^ mix64(((pixel as u64) << 32) | sample as u64));
        Self { key, dim: 0 }
    }

    /// The next uniform number in [0, 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        let bits = mix64(self.key.wrapping_add((self.dim as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)));
        self.dim += 1;
        // 24 high bits -> [0, 1) exactly representable.
        (bits >> 40) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Two uniform numbers.
    #[inline]
    pub fn next_2d(&mut self) -> glam::Vec2 {
        glam::Vec2::new(self.next_f32(), self.next_f32())
    }

    /// Skips to dimension `dim` (so each consumer of a sample uses fixed dimensions).
    pub fn at_dimension(mut self, dim: u32) -> Self {
        self.dim = dim;
        self
    }

    /// The first `D` numbers (dimensions 0..D) of [`LANES`] streams at once, for lane kernels:
    /// `[d][l]` is number `d` of `SampleStream::new(seed, pixel[l], sample[l])`, bit for bit.
    #[inline(always)]
    pub fn lanes<const D: usize>(seed: u64, pixel: &[u32; LANES], sample: &[u32; LANES]) -> [[f32; LANES]; D] {
        let mut key = [0u64; LANES];
        for l in 0..LANES {
            key[l] = mix64(seed ^ mix64(((pixel[l] as u64) << 32) | sample[l] as u64));
        }
        // All D rows as one flat loop of whole mixes: as a loop per row, LLVM vectorised across
        // the rows (two lanes at a time) rather than along them.
        let mut z = [[0u64; LANES]; D];
        for (d, row) in z.iter_mut().enumerate() {
            *row = key.map(|k| k.wrapping_add((d as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)));
        }
        let mut out = [[0.0; LANES]; D];
        for (o, z) in out.as_flattened_mut().iter_mut().zip(z.as_flattened()) {
            *o = (mix64(*z) >> 40) as f32 * (1.0 / (1u32 << 24) as f32);
        }
        out
    }
}

/// A sequential generator (SplitMix64, Steele, Lea and Flood 2014) for code that draws numbers in order:
/// scene generators, tests and benchmarks. Renders use the counter-based [`SampleStream`] instead.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator whose state starts at `seed` (the seed is used as is, not mixed).
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits: the state advances by the golden-ratio increment, then is mixed.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix64(self.0)
    }

    /// Uniform in [0, 1) on the 2^-24 grid, like a renderer's f32 samples.
    #[inline]
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Two uniform f32 in [0, 1), x drawn first.
    #[inline]
    pub fn vec2(&mut self) -> glam::Vec2 {
        glam::Vec2::new(self.f32(), self.f32())
    }

    /// Uniform in [0, 1) on the 2^-53 grid.
    #[inline]
    pub fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// Log-uniform in [lo, hi) (lo > 0).
    pub fn log_range(&mut self, lo: f32, hi: f32) -> f32 {
        lo * (hi / lo).powf(self.f32())
    }

    /// An index in 0..n by the modulo of 64 bits (bias below 2^-40 for n < 2^24); `n` must be > 0.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lane_streams_match_the_scalar_streams() {
        let mut rng = SplitMix64::new(7);
        for seed in [0, 42, u64::MAX] {
            let pixel: [u32; LANES] = std::array::from_fn(|_| rng.next_u64() as u32);
            let sample: [u32; LANES] = std::array::from_fn(|l| if l == 0 { u32::MAX } else { rng.next_u64() as u32 });
            let lanes = SampleStream::lanes::<3>(seed, &pixel, &sample);
            for l in 0..LANES {
                let mut scalar = SampleStream::new(seed, pixel[l], sample[l]);
                for (d, dim) in lanes.iter().enumerate() {
                    assert_eq!(dim[l].to_bits(), scalar.next_f32().to_bits(), "seed {seed} lane {l} dim {d}");
                }
            }
        }
    }

    /// The first outputs for seed 1234567 of the reference splitmix64.c (Vigna, prng.di.unimi.it).
    #[test]
    fn split_mix64_matches_the_reference_sequence() {
        let mut rng = SplitMix64::new(1234567);
        let got: Vec<u64> = (0..3).map(|_| rng.next_u64()).collect();
        assert_eq!(got, [6457827717110365317, 3203168211198807973, 9817491932198370423]);
    }

    #[test]
    fn split_mix64_floats_lie_in_the_unit_interval() {
        let mut rng = SplitMix64::new(0);
        for _ in 0..10_000 {
            let (a, b) = (rng.f32(), rng.f64());
            assert!((0.0..1.0).contains(&a) && (0.0..1.0).contains(&b));
            assert!(rng.below(7) < 7);
        }
    }
}
