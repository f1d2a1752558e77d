//! Counter-based random numbers: a value is a pure function of (seed, pixel, sample, dimension),
//! so images are bit-identical for any thread count and any batch order.

/// A stream of uniform numbers for one (seed, pixel, sample); `dim` advances per draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleStream {
    key: u64,
    dim: u32,
}

/// A 64-bit mix (splitmix64 finaliser, Steele et al. 2014).
#[inline]
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
}
