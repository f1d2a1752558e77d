//! Random numbers. Renders use counter-based streams: a value is a pure function of (seed, pixel,
//! sample, dimension), so images are bit-identical for any thread count and any batch order. Scene
//! generators, tests and benchmarks use the sequential [`SplitMix64`].

use crate::lanes::LANES;

/// A stream of uniform numbers for one (seed, pixel, sample); `dim` advances per draw.
///
/// Number `d` is 24 bits of `mix64(key + ((sample << 32) | d / 2) * GOLDEN)`: the high bits for
/// even `d`, the next 24 for odd `d`. The key hashes (seed, pixel) twice, so that seeds or pixels a
/// few bits apart give unrelated streams; within a pixel the counter is spread by the golden-ratio
/// multiply before the mix, as SplitMix64 spreads its state. A pixel's samples share one key, and
/// two numbers share one mix (lane kernels draw a block of one pixel's samples for two mixes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleStream {
    key: u64,
    sample: u32,
    dim: u32,
}

/// The golden-ratio increment of SplitMix64.
const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// A 64-bit mix (splitmix64 finaliser, Steele et al. 2014).
#[inline(always)]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The key of every stream of `pixel` under `seed`.
#[inline(always)]
fn pixel_key(seed: u64, pixel: u32) -> u64 {
    mix64(seed ^ mix64(pixel as u64))
}

/// `(sample << 32) * GOLDEN` (mod 2^64): only the low half of the constant reaches the product, so a
/// 32-bit multiply forms it.
#[inline(always)]
fn sample_offset(sample: u32) -> u64 {
    (sample.wrapping_mul(GOLDEN as u32) as u64) << 32
}

/// Number `dim` from the mix of its pair: a uniform value in [0, 1) on the 2^-24 grid (exact in f32).
#[inline(always)]
fn field(bits: u64, dim: u32) -> f32 {
    let shift = if dim.is_multiple_of(2) { 40 } else { 16 };
    ((bits >> shift) & 0xff_ffff) as f32 * (1.0 / (1u32 << 24) as f32)
}

impl SampleStream {
    /// The stream of `pixel`'s `sample`-th sample under `seed`.
    pub fn new(seed: u64, pixel: u32, sample: u32) -> Self {
        Self { key: pixel_key(seed, pixel), sample, dim: 0 }
    }

    /// The mix that numbers `dim` and `dim ^ 1` come from.
    #[inline]
    fn pair_bits(&self, dim: u32) -> u64 {
        let pair = (dim / 2) as u64;
        mix64(self.key.wrapping_add(sample_offset(self.sample)).wrapping_add(pair.wrapping_mul(GOLDEN)))
    }

    /// The next uniform number in [0, 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        let u = field(self.pair_bits(self.dim), self.dim);
        self.dim += 1;
        u
    }

    /// Two uniform numbers (one mix when they are a pair).
    #[inline]
    pub fn next_2d(&mut self) -> glam::Vec2 {
        if !self.dim.is_multiple_of(2) {
            return glam::Vec2::new(self.next_f32(), self.next_f32());
        }
        let bits = self.pair_bits(self.dim);
        self.dim += 2;
        glam::Vec2::new(field(bits, 0), field(bits, 1))
    }

    /// Skips to dimension `dim` (so each consumer of a sample uses fixed dimensions).
    pub fn at_dimension(mut self, dim: u32) -> Self {
        self.dim = dim;
        self
    }

    /// The first `D` numbers (dimensions 0..D) of `LANES` streams at once, for lane kernels:
    /// `[d][l]` is number `d` of `SampleStream::new(seed, pixel[l], sample[l])`, bit for bit.
    #[inline(always)]
    pub fn lanes<const D: usize>(seed: u64, pixel: &[u32; LANES], sample: &[u32; LANES]) -> [[f32; LANES]; D] {
        Self::lanes_from_keys(pixel.map(|p| pixel_key(seed, p)), sample)
    }

    /// [`Self::lanes`] of samples of one pixel: its key is hashed once (for blocks of one pixel's
    /// samples, as any spp of 16 or more gives).
    #[inline(always)]
    pub fn pixel_lanes<const D: usize>(seed: u64, pixel: u32, sample: &[u32; LANES]) -> [[f32; LANES]; D] {
        Self::lanes_from_keys([pixel_key(seed, pixel); LANES], sample)
    }

    #[inline(always)]
    fn lanes_from_keys<const D: usize>(key: [u64; LANES], sample: &[u32; LANES]) -> [[f32; LANES]; D] {
        let mut base = [0u64; LANES];
        for l in 0..LANES {
            base[l] = key[l].wrapping_add(sample_offset(sample[l]));
        }
        let mut out = [[0.0; LANES]; D];
        for pair in 0..D.div_ceil(2) {
            let step = (pair as u64).wrapping_mul(GOLDEN);
            let mut bits = [0u64; LANES];
            for l in 0..LANES {
                bits[l] = mix64(base[l].wrapping_add(step));
            }
            for (d, row) in out.iter_mut().enumerate().skip(2 * pair).take(2) {
                for (o, &b) in row.iter_mut().zip(&bits) {
                    *o = field(b, d as u32);
                }
            }
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
        self.0 = self.0.wrapping_add(GOLDEN);
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
            let one_pixel = SampleStream::pixel_lanes::<3>(seed, pixel[0], &sample);
            for l in 0..LANES {
                let (mut scalar, mut first) =
                    (SampleStream::new(seed, pixel[l], sample[l]), SampleStream::new(seed, pixel[0], sample[l]));
                for d in 0..3 {
                    assert_eq!(lanes[d][l].to_bits(), scalar.next_f32().to_bits(), "seed {seed} lane {l} dim {d}");
                    assert_eq!(one_pixel[d][l].to_bits(), first.next_f32().to_bits(), "seed {seed} lane {l} dim {d}");
                }
                // Pairs drawn at once, from an even and from an odd dimension.
                let (mut even, mut odd) = (SampleStream::new(seed, pixel[l], sample[l]), scalar.at_dimension(1));
                assert_eq!(even.next_2d(), glam::Vec2::new(lanes[0][l], lanes[1][l]));
                assert_eq!(odd.next_2d(), glam::Vec2::new(lanes[1][l], lanes[2][l]));
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
