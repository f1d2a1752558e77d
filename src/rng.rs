//! Random numbers. Renders use counter-based streams: a value is a pure function of (seed, pixel,
//! sample, dimension), so images are bit-identical for any thread count and any batch order. Scene
//! generators, tests and benchmarks use the sequential [`SplitMix64`].

use crate::lanes::{F32x16, LANES};

/// Which numbers a render's samples draw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Pattern {
    /// An Owen-scrambled Sobol sequence padded in sets of 4 dimensions (Burley 2020, "Practical
    /// Hash-based Owen Scrambling", as Cycles' Sobol-Burley pattern): a pixel's first 2^m samples
    /// stratify every set, so smooth integrands converge faster than 1/spp.
    #[default]
    Sobol,
    /// Independent uniform numbers: error falls as 1/spp exactly, and any two samples of a pixel
    /// are independent (what reuse across samples, as ReSTIR's temporal reuse, needs).
    Independent,
}

/// A stream of uniform numbers for one (seed, pixel, sample); `dim` advances per draw.
///
/// Under [`Pattern::Sobol`], dimensions `4k..4k + 4` of a pixel's samples are a shuffled, scrambled
/// 4D Sobol sequence over the sample index, seeded by (seed, pixel, k): sets, pixels and seeds are
/// independent. By convention a consumer draws a 1D number at `4k` and a 2D one at `4k + 1`: a
/// set's dimensions are ordered so that `4k + 1, 4k + 2` are the Sobol pair that forms a
/// (0, 2)-sequence. Samples past 2^16 (the crate's sequence length) start new, independent
/// sequences of 2^16.
///
/// Under [`Pattern::Independent`], number `d` is 24 bits of `mix64(key + ((sample << 32) | d / 2) *
/// GOLDEN)`: the high bits for even `d`, the next 24 for odd `d`. The golden-ratio multiply spreads
/// the counter before the mix, as SplitMix64 spreads its state.
///
/// Either way the key hashes (seed, pixel) twice, so that seeds or pixels a few bits apart give
/// unrelated streams.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleStream {
    pattern: Pattern,
    key: u64,
    sample: u32,
    dim: u32,
    /// The last set of 4 (Sobol) or pair (independent) drawn, `u32::MAX` for none, and its numbers.
    group: u32,
    values: [f32; 4],
}

/// The golden-ratio increment of SplitMix64.
const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// Which Sobol dimension of a set each of its 4 dimensions takes: the (0, 2)-sequence pair (Sobol
/// dimensions 0, 1) at positions 1, 2, where 2D draws sit.
const SET_ORDER: [usize; 4] = [2, 0, 1, 3];

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

/// Sobol: numbers `4 set .. 4 set + 4` of `sample` of the pixel with `key`, in stream order.
#[inline(always)]
fn sobol_set(key: u64, sample: u32, set: u32) -> [f32; 4] {
    let which = ((set as u64) << 32) | (sample >> 16) as u64;
    let seed = (mix64(key ^ which.wrapping_mul(GOLDEN)) >> 32) as u32;
    let sobol = sobol_4d(sample & 0xffff, seed);
    SET_ORDER.map(|d| sobol[d])
}

/// The first 4 Sobol dimensions of the crate as a function of the top 16 bits of a reversed index,
/// a table per byte: Sobol points are linear over GF(2) in the index bits, so a byte's entry is the
/// XOR of its bits' direction vectors.
static SOBOL_BYTES: std::sync::LazyLock<[[[u32; 4]; 256]; 2]> = std::sync::LazyLock::new(|| {
    std::array::from_fn(|half| {
        std::array::from_fn(|b| sobol_burley::parts::sobol_int4_rev((b as u32) << (24 - 8 * half), 0).into())
    })
});

/// `sobol_burley::sample_4d(index, 0, seed)` bit for bit, with two table lookups in place of the
/// crate's loop over the index bits (a branch per set bit, half of 16 after the shuffle). The
/// constants are the crate's (0.5.0), so that the test can hold it to the crate.
#[inline(always)]
fn sobol_4d(index: u32, seed: u32) -> [f32; 4] {
    use sobol_burley::parts::{Int4, hash, hash_int4, owen_scramble_int4_rev, owen_scramble_rev};
    let rev = owen_scramble_rev(index.reverse_bits(), hash(seed ^ 0x79c6_8e4a));
    let bytes = &*SOBOL_BYTES;
    let (hi, lo) = (bytes[0][(rev >> 24) as usize], bytes[1][((rev >> 16) & 0xff) as usize]);
    let sobol = Int4::from([hi[0] ^ lo[0], hi[1] ^ lo[1], hi[2] ^ lo[2], hi[3] ^ lo[3]]);
    let scramble = Int4::from([seed.wrapping_mul(0x9c8f_2d3b); 4])
        ^ Int4::from([0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8]);
    owen_scramble_int4_rev(sobol, hash_int4(scramble)).reverse_bits().to_f32_norm()
}

/// Independent: numbers `2 pair` and `2 pair + 1` of `sample` of the pixel with `key`.
#[inline(always)]
fn independent_pair(key: u64, sample: u32, pair: u32) -> [f32; 2] {
    // `(sample << 32) * GOLDEN`: only the low half of the constant reaches the product.
    let offset = (sample.wrapping_mul(GOLDEN as u32) as u64) << 32;
    let bits = mix64(key.wrapping_add(offset).wrapping_add((pair as u64).wrapping_mul(GOLDEN)));
    // Uniform values in [0, 1) on the 2^-24 grid (exact in f32).
    [(bits >> 40) as f32, ((bits >> 16) & 0xff_ffff) as f32].map(|x| x * (1.0 / (1u32 << 24) as f32))
}

impl SampleStream {
    /// The stream of `pixel`'s `sample`-th sample under `seed`.
    pub fn new(pattern: Pattern, seed: u64, pixel: u32, sample: u32) -> Self {
        Self { pattern, key: pixel_key(seed, pixel), sample, dim: 0, group: u32::MAX, values: [0.0; 4] }
    }

    /// The next uniform number in [0, 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        let per_group = if self.pattern == Pattern::Sobol { 4 } else { 2 };
        let (group, d) = (self.dim / per_group, self.dim % per_group);
        if group != self.group {
            self.values = match self.pattern {
                Pattern::Sobol => sobol_set(self.key, self.sample, group),
                Pattern::Independent => {
                    let [a, b] = independent_pair(self.key, self.sample, group);
                    [a, b, 0.0, 0.0]
                }
            };
            self.group = group;
        }
        self.dim += 1;
        self.values[d as usize]
    }

    /// Two uniform numbers.
    #[inline]
    pub fn next_2d(&mut self) -> glam::Vec2 {
        let x = self.next_f32();
        glam::Vec2::new(x, self.next_f32())
    }

    /// Skips to dimension `dim` (so each consumer of a sample uses fixed dimensions).
    pub fn at_dimension(mut self, dim: u32) -> Self {
        self.dim = dim;
        self
    }

    /// The first `D` numbers (dimensions 0..D) of `LANES` streams at once, for lane kernels:
    /// `[d][l]` is number `d` of `SampleStream::new(pattern, seed, pixel[l], sample[l])`, bit for bit.
    #[inline(always)]
    pub fn lanes<const D: usize>(
        pattern: Pattern,
        seed: u64,
        pixel: &[u32; LANES],
        sample: &[u32; LANES],
    ) -> [F32x16; D] {
        Self::lanes_from_keys(pattern, pixel.map(|p| pixel_key(seed, p)), sample)
    }

    /// [`Self::lanes`] of samples of one pixel: its key is hashed once (for blocks of one pixel's
    /// samples, as any spp of 16 or more gives).
    #[inline(always)]
    pub fn pixel_lanes<const D: usize>(pattern: Pattern, seed: u64, pixel: u32, sample: &[u32; LANES]) -> [F32x16; D] {
        Self::lanes_from_keys(pattern, [pixel_key(seed, pixel); LANES], sample)
    }

    #[inline(always)]
    fn lanes_from_keys<const D: usize>(pattern: Pattern, key: [u64; LANES], sample: &[u32; LANES]) -> [F32x16; D] {
        let mut out = [F32x16::ZERO; D];
        match pattern {
            Pattern::Sobol => {
                for set in 0..D.div_ceil(4) {
                    for l in 0..LANES {
                        let values = sobol_set(key[l], sample[l], set as u32);
                        for (d, row) in out.iter_mut().enumerate().skip(4 * set).take(4) {
                            row[l] = values[d % 4];
                        }
                    }
                }
            }
            Pattern::Independent => {
                for pair in 0..D.div_ceil(2) {
                    let values: [[f32; 2]; LANES] =
                        std::array::from_fn(|l| independent_pair(key[l], sample[l], pair as u32));
                    for (d, row) in out.iter_mut().enumerate().skip(2 * pair).take(2) {
                        for (o, v) in row.0.iter_mut().zip(&values) {
                            *o = v[d % 2];
                        }
                    }
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
        for (pattern, seed) in
            [Pattern::Sobol, Pattern::Independent].into_iter().flat_map(|p| [(p, 0), (p, 42), (p, u64::MAX)])
        {
            let pixel: [u32; LANES] = std::array::from_fn(|_| rng.next_u64() as u32);
            let sample: [u32; LANES] = std::array::from_fn(|l| if l == 0 { u32::MAX } else { rng.next_u64() as u32 });
            let lanes = SampleStream::lanes::<6>(pattern, seed, &pixel, &sample);
            let one_pixel = SampleStream::pixel_lanes::<6>(pattern, seed, pixel[0], &sample);
            for l in 0..LANES {
                let mut scalar = SampleStream::new(pattern, seed, pixel[l], sample[l]);
                let mut first = SampleStream::new(pattern, seed, pixel[0], sample[l]);
                for d in 0..6 {
                    let what = format!("{pattern:?} seed {seed} lane {l} dim {d}");
                    assert_eq!(lanes[d][l].to_bits(), scalar.next_f32().to_bits(), "{what}");
                    assert_eq!(one_pixel[d][l].to_bits(), first.next_f32().to_bits(), "{what}");
                    // Drawn after a skip, as consumers at fixed dimensions do.
                    let skipped = SampleStream::new(pattern, seed, pixel[l], sample[l]).at_dimension(d as u32);
                    assert_eq!(lanes[d][l].to_bits(), skipped.clone().next_f32().to_bits(), "{what}");
                }
                // Pairs drawn at once, within a group and across groups.
                for d in [1, 3] {
                    let mut pair = SampleStream::new(pattern, seed, pixel[l], sample[l]).at_dimension(d);
                    assert_eq!(pair.next_2d(), glam::Vec2::new(lanes[d as usize][l], lanes[d as usize + 1][l]));
                }
            }
        }
    }

    /// The table-driven Sobol set is the crate's `sample_4d`, bit for bit, over every index and
    /// seeds from 0 to all ones.
    #[test]
    fn sobol_sets_are_the_crates() {
        let mut rng = SplitMix64::new(11);
        let seeds = [0, 1, u32::MAX].into_iter().chain((0..5).map(|_| rng.next_u64() as u32));
        for seed in seeds {
            for index in 0..1u32 << 16 {
                let (mine, crate_) = (sobol_4d(index, seed), sobol_burley::sample_4d(index, 0, seed));
                assert_eq!(mine.map(f32::to_bits), crate_.map(f32::to_bits), "index {index} seed {seed}");
            }
        }
    }

    /// Every dimension of a pixel's first 2^m samples has one number in each 1/2^m interval, and
    /// the 2D pair of every set one point in each of the 16 x 16 cells of 256 samples: the Sobol
    /// net survives the shuffling and scrambling, in the first set, in padded sets and past 2^16.
    #[test]
    fn a_pixels_samples_stratify_every_set() {
        for (seed, pixel, first) in [(0, 0, 0), (42, 123_456, 0), (7, 9, 1 << 16)] {
            let draws: Vec<[f32; 12]> = (first..first + 256)
                .map(|s| {
                    let mut r = SampleStream::new(Pattern::Sobol, seed, pixel, s);
                    std::array::from_fn(|_| r.next_f32())
                })
                .collect();
            for d in 0..12 {
                let mut hits = [0u32; 256];
                draws.iter().for_each(|x| hits[(x[d] * 256.0) as usize] += 1);
                assert!(hits.iter().all(|&h| h == 1), "seed {seed} sample {first}.. dimension {d}");
            }
            for d in [1, 5, 9] {
                let mut cells = [0u32; 256];
                draws.iter().for_each(|x| cells[(x[d] * 16.0) as usize * 16 + (x[d + 1] * 16.0) as usize] += 1);
                assert!(cells.iter().all(|&h| h == 1), "seed {seed} sample {first}.. pair {d}, {}", d + 1);
            }
        }
    }

    /// Sets, pixels, seeds and blocks of 2^16 samples are independent sequences: no correlation
    /// beyond that of independent numbers (|r| < 4 / sqrt(n)), and no repeat of a block.
    #[test]
    fn sets_pixels_and_seeds_are_independent() {
        let n = 4096u32;
        let corr = |a: &dyn Fn(u32) -> f32, b: &dyn Fn(u32) -> f32| {
            let (mut sab, mut sa, mut sb, mut saa, mut sbb) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
            for s in 0..n {
                let (x, y) = (a(s) as f64, b(s) as f64);
                (sab, sa, sb, saa, sbb) = (sab + x * y, sa + x, sb + y, saa + x * x, sbb + y * y);
            }
            let n = n as f64;
            (sab / n - sa * sb / n / n) / ((saa / n - (sa / n).powi(2)) * (sbb / n - (sb / n).powi(2))).sqrt()
        };
        let at = |seed: u64, pixel: u32, dim: u32| {
            move |s: u32| SampleStream::new(Pattern::Sobol, seed, pixel, s).at_dimension(dim).next_f32()
        };
        let bound = 4.0 / (n as f64).sqrt();
        for (what, r) in [
            ("sets 0 and 1", corr(&at(1, 5, 1), &at(1, 5, 5))),
            ("sets 0 and 7", corr(&at(1, 5, 2), &at(1, 5, 30))),
            ("neighbour pixels", corr(&at(1, 5, 1), &at(1, 6, 1))),
            ("neighbour seeds", corr(&at(1, 5, 1), &at(2, 5, 1))),
            ("blocks of 2^16", corr(&at(1, 5, 1), &|s| at(1, 5, 1)(s + (1 << 16)))),
        ] {
            assert!(r.abs() < bound, "{what}: correlation {r}");
        }
    }

    /// What the Sobol pattern is for: a smooth integrand over a pixel's 64 samples is estimated
    /// with a tenth of the error of independent numbers (sigma / 8 = 0.028 for x y on the unit
    /// square), which the independent pattern meets (within 20%, over 400 pixels).
    #[test]
    fn a_smooth_integral_converges_faster_under_sobol() {
        let (pixels, spp) = (400u32, 64u32);
        let rms = |pattern| {
            let mut squared = 0.0f64;
            for pixel in 0..pixels {
                let sum: f64 = (0..spp)
                    .map(|s| {
                        let u = SampleStream::new(pattern, 3, pixel, s).at_dimension(5).next_2d();
                        (u.x * u.y) as f64
                    })
                    .sum();
                squared += (sum / spp as f64 - 0.25).powi(2);
            }
            (squared / pixels as f64).sqrt()
        };
        let theory = (1.0f64 / 9.0 - 1.0 / 16.0).sqrt() / (spp as f64).sqrt();
        let (sobol, independent) = (rms(Pattern::Sobol), rms(Pattern::Independent));
        assert!(sobol < 0.1 * theory, "Sobol: RMS error {sobol}, independent numbers' {theory}");
        assert!((independent / theory - 1.0).abs() < 0.2, "independent: RMS error {independent} vs {theory}");
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
