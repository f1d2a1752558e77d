//! The film: per-pixel sums of photometric linear-sRGB samples (Y in cd/m^2).

use glam::{DVec3, Vec3};

/// Accumulated radiance per pixel, row-major from the top left.
#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    sum: Vec<DVec3>,
    count: Vec<u32>,
}

impl Film {
    /// A black film.
    pub fn new(width: u32, height: u32) -> Self {
        let n = (width as usize) * (height as usize);
        Self { width, height, sum: vec![DVec3::ZERO; n], count: vec![0; n] }
    }

    /// Adds one sample's radiance to `pixel`.
    #[inline]
    pub fn add(&mut self, pixel: u32, rgb: Vec3) {
        self.sum[pixel as usize] += rgb.as_dvec3();
        self.count[pixel as usize] += 1;
    }

    /// Adds the samples `first..first + rgb.len()` of a render in which pixel `k / spp` owns
    /// sample `k`, pixels in parallel. Each pixel adds its samples in sample order, so the sums
    /// are those of calling [`Self::add`] sample by sample.
    pub fn par_add_samples(&mut self, first: usize, spp: usize, rgb: &[Vec3]) {
        use rayon::prelude::*;
        let (spp, end) = (spp.max(1), first + rgb.len());
        if rgb.is_empty() {
            return;
        }
        let pixels = first / spp..(end - 1) / spp + 1;
        let sums = &mut self.sum[pixels.clone()];
        let counts = &mut self.count[pixels.clone()];
        // Small runs per task when a pixel has many samples; about 256 samples per task otherwise.
        let min_len = (256 / spp).max(1);
        (sums, counts).into_par_iter().enumerate().with_min_len(min_len).for_each(|(j, (sum, count))| {
            let p = pixels.start + j;
            let samples = (p * spp).max(first)..((p + 1) * spp).min(end);
            *count += samples.len() as u32;
            for k in samples {
                *sum += rgb[k - first].as_dvec3();
            }
        });
    }

    /// The mean of each pixel's samples.
    pub fn pixels(&self) -> Vec<Vec3> {
        self.sum
            .iter()
            .zip(&self.count)
            .map(|(s, &n)| if n > 0 { (*s / n as f64).as_vec3() } else { Vec3::ZERO })
            .collect()
    }

    /// Mean of a pixel.
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        let i = (y * self.width + x) as usize;
        if self.count[i] > 0 { (self.sum[i] / self.count[i] as f64).as_vec3() } else { Vec3::ZERO }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// Runs that start and end inside a pixel, and pixels with more samples than a run, give the
    /// same sums, bit for bit, as adding sample by sample.
    #[test]
    fn parallel_runs_add_exactly_like_single_samples() {
        let mut rng = SplitMix64::new(7);
        for (spp, runs) in [(3usize, [0usize, 5, 6, 40, 97]), (64, [0, 100, 128, 1000, 2048]), (1, [0, 1, 2, 3, 4])] {
            let total = *runs.last().unwrap();
            let rgb: Vec<Vec3> = (0..total).map(|_| Vec3::new(rng.f32(), rng.f32() * 1e4, rng.f32() * 1e-4)).collect();
            let width = total.div_ceil(spp) as u32;
            let (mut serial, mut parallel) = (Film::new(width, 1), Film::new(width, 1));
            for (k, &c) in rgb.iter().enumerate() {
                serial.add((k / spp) as u32, c);
            }
            for w in runs.windows(2) {
                parallel.par_add_samples(w[0], spp, &rgb[w[0]..w[1]]);
            }
            assert_eq!(serial.sum, parallel.sum, "spp {spp}");
            assert_eq!(serial.count, parallel.count, "spp {spp}");
        }
    }
}
