//! A lightmap from its texels' samples: each covered texel's mean over its valid samples, then
//! dilation into the texels without one.

use glam::{DVec3, Vec3};

use super::targets::Target;
use super::texels::Coverage;
use super::{Lightmap, TexelState};
use crate::scene::image::LUMINANCE_WEIGHTS;

/// A covered texel's samples so far.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Accumulator {
    sum: DVec3,
    sum2: DVec3,
    valid: u32,
    leaked: u32,
}

impl Accumulator {
    /// Adds one sample's radiance; a leaked sample (or a non-finite one) is only counted.
    pub(super) fn add(&mut self, rgb: DVec3, leaked: bool) {
        if leaked {
            self.leaked += 1;
        } else if rgb.is_finite() {
            self.sum += rgb;
            self.sum2 += rgb * rgb;
            self.valid += 1;
        }
    }
}

impl Accumulator {
    /// The mean of the valid samples and its standard error (zero from one sample); None
    /// without a valid sample.
    pub(super) fn mean(&self) -> Option<(Vec3, Vec3)> {
        if self.valid == 0 {
            return None;
        }
        let count = self.valid as f64;
        let mean = self.sum / count;
        let mut std_error = DVec3::ZERO;
        if self.valid > 1 {
            // The unbiased sample variance over the count: the variance of the mean.
            let variance = ((self.sum2 - mean * mean * count) / (count - 1.0)).max(DVec3::ZERO);
            std_error = (variance / count).map(f64::sqrt);
        }
        Some((mean.as_vec3(), std_error.as_vec3()))
    }

    /// The sums of the valid samples and of their squares.
    pub(super) fn sums(&self) -> (DVec3, DVec3) {
        (self.sum, self.sum2)
    }

    /// An accumulator with these sums and counts (a part file's cell).
    pub(super) fn from_parts(sum: DVec3, sum2: DVec3, valid: u32, leaked: u32) -> Self {
        Self { sum, sum2, valid, leaked }
    }

    /// Valid samples, and samples dropped as leaks.
    pub(super) fn counts(&self) -> (u32, u32) {
        (self.valid, self.leaked)
    }
}

/// Luminance (nit) of a linear sRGB value.
pub(super) fn luminance(c: Vec3) -> f32 {
    c.dot(LUMINANCE_WEIGHTS)
}

/// The `size` x `size` lightmap of `target`: `sums[k]` are the samples of covered texel k of
/// `coverage`; dilation fills `margin` texels out.
pub(super) fn finish(target: Target, coverage: &Coverage, sums: &[Accumulator], size: u32, margin: u32) -> Lightmap {
    let n = (size * size) as usize;
    let (mut texels, mut std_error, mut state) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n], vec![TexelState::Empty; n]);
    let mut leaked_samples = 0;
    let (mut area, mut albedo) = (vec![0.0; n], vec![Vec3::ZERO; n]);
    for (&texel, (a, m)) in coverage.texels.iter().zip(coverage.areas(&target.surfaces, size)) {
        (area[texel as usize], albedo[texel as usize]) = (a, m);
    }
    for (&texel, a) in coverage.texels.iter().zip(sums) {
        leaked_samples += a.leaked as u64;
        if let Some((mean, error)) = a.mean() {
            let i = texel as usize;
            (texels[i], std_error[i], state[i]) = (mean, error, TexelState::Baked);
        }
    }
    dilate(&mut texels, &mut state, size as usize, margin);
    Lightmap {
        name: target.name,
        mesh_name: target.mesh_name,
        node_name: target.node_name,
        size,
        texels,
        std_error,
        state,
        leaked_samples,
        area,
        albedo,
    }
}

/// Fills empty texels ring by ring, `margin` rings at most: each texel next to (8-neighbourhood)
/// a texel with a value, baked or filled by an earlier ring, takes the mean of those neighbours.
fn dilate(texels: &mut [Vec3], state: &mut [TexelState], size: usize, margin: u32) {
    let mut ring = Vec::new();
    for _ in 0..margin {
        ring.clear();
        for (i, _) in state.iter().enumerate().filter(|(_, s)| **s == TexelState::Empty) {
            let (x, y) = (i % size, i / size);
            let (mut sum, mut count) = (Vec3::ZERO, 0);
            for ny in y.saturating_sub(1)..(y + 2).min(size) {
                for nx in x.saturating_sub(1)..(x + 2).min(size) {
                    let j = ny * size + nx;
                    if state[j] != TexelState::Empty {
                        (sum, count) = (sum + texels[j], count + 1);
                    }
                }
            }
            if count > 0 {
                ring.push((i, sum / count as f32));
            }
        }
        if ring.is_empty() {
            break;
        }
        for &(i, value) in &ring {
            (texels[i], state[i]) = (value, TexelState::Filled);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One baked texel in a 5x5 map: a margin of 1 fills its ring of 8 with its value, a margin
    /// of 2 the whole map, a margin of 0 nothing.
    #[test]
    fn dilation_fills_ring_by_ring() {
        for (margin, filled) in [(0, 0), (1, 8), (2, 24)] {
            let mut texels = vec![Vec3::ZERO; 25];
            let mut state = vec![TexelState::Empty; 25];
            (texels[12], state[12]) = (Vec3::new(1.0, 2.0, 3.0), TexelState::Baked);
            dilate(&mut texels, &mut state, 5, margin);
            assert_eq!(state.iter().filter(|s| **s == TexelState::Filled).count(), filled, "margin {margin}");
            for (t, s) in texels.iter().zip(&state) {
                assert_eq!(*t, if *s == TexelState::Empty { Vec3::ZERO } else { Vec3::new(1.0, 2.0, 3.0) });
            }
        }
    }
}
