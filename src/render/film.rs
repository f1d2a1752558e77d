//! The film: per-pixel sums of photometric linear-sRGB samples (Y in cd/m^2).

use glam::{DVec3, Vec3};

/// Accumulated radiance per pixel, row-major from the top left.
#[derive(Clone, Debug)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    sum: Vec<DVec3>,
    count: Vec<u32>,
}

/// Pixels whose samples [`PixelRun::add_whole_pixels`] adds side by side.
const PIXEL_GROUP: usize = 4;

/// Consecutive pixels of a film, for one task to add their samples.
pub struct PixelRun<'a> {
    sum: &'a mut [DVec3],
    count: &'a mut [u32],
}

impl PixelRun<'_> {
    /// Adds `spp` samples to each pixel of the run: `rgb[j * spp..(j + 1) * spp]` to pixel j, in
    /// sample order (as [`Film::add`] sample by sample). `rgb` holds every sample of the run.
    pub fn add_whole_pixels(self, spp: usize, rgb: &[Vec3]) {
        assert_eq!(rgb.len(), self.sum.len() * spp, "samples of whole pixels");
        let groups = self.sum.chunks_mut(PIXEL_GROUP).zip(self.count.chunks_mut(PIXEL_GROUP));
        for ((sums, counts), rgb) in groups.zip(rgb.chunks(PIXEL_GROUP * spp)) {
            counts.iter_mut().for_each(|c| *c += spp as u32);
            let Ok(sums) = <&mut [DVec3; PIXEL_GROUP]>::try_from(&mut *sums) else {
                // The run's last few pixels.
                for (sum, rgb) in sums.iter_mut().zip(rgb.chunks(spp)) {
                    *sum = rgb.iter().fold(*sum, |s, c| s + c.as_dvec3());
                }
                continue;
            };
            // The group's pixels add their samples side by side: independent chains of
            // additions overlap, where one pixel's chain waits on each addition. Each pixel
            // still adds its own samples in order.
            let mut acc = *sums;
            for k in 0..spp {
                for (j, acc) in acc.iter_mut().enumerate() {
                    *acc += rgb[j * spp + k].as_dvec3();
                }
            }
            *sums = acc;
        }
    }
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
        // Groups of pixels per task: small runs when a pixel has many samples, about 256 samples
        // per task otherwise.
        let min_len = (256 / (spp * PIXEL_GROUP)).max(1);
        let groups = (sums.par_chunks_mut(PIXEL_GROUP), counts.par_chunks_mut(PIXEL_GROUP));
        groups.into_par_iter().enumerate().with_min_len(min_len).for_each(|(g, (sums, counts))| {
            let p0 = pixels.start + g * PIXEL_GROUP;
            let n = sums.len();
            if p0 * spp >= first && (p0 + n) * spp <= end {
                let samples = &rgb[p0 * spp - first..(p0 + n) * spp - first];
                return PixelRun { sum: sums, count: counts }.add_whole_pixels(spp, samples);
            }
            for (j, (sum, count)) in sums.iter_mut().zip(counts).enumerate() {
                let p = p0 + j;
                let samples = (p * spp).max(first)..((p + 1) * spp).min(end);
                *count += samples.len() as u32;
                for k in samples {
                    *sum += rgb[k - first].as_dvec3();
                }
            }
        });
    }

    /// The pixels of samples `first..first + len` as runs of `run_samples / spp` pixels, in
    /// order, for tasks that each hold `run_samples` consecutive samples (the last run may be
    /// shorter): None unless every run is whole pixels (`spp` divides `first`, `len` and
    /// `run_samples`).
    pub fn pixel_runs_mut(
        &mut self,
        first: usize,
        len: usize,
        spp: usize,
        run_samples: usize,
    ) -> Option<impl rayon::iter::IndexedParallelIterator<Item = PixelRun<'_>>> {
        use rayon::prelude::*;
        let spp = spp.max(1);
        let whole = |samples: usize| samples.is_multiple_of(spp);
        if !whole(first) || !whole(len) || !whole(run_samples) || run_samples == 0 {
            return None;
        }
        let pixels = first / spp..(first + len) / spp;
        let run = run_samples / spp;
        let (sums, counts) = (&mut self.sum[pixels.clone()], &mut self.count[pixels]);
        let runs = sums.par_chunks_mut(run).zip(counts.par_chunks_mut(run));
        Some(runs.map(|(sum, count)| PixelRun { sum, count }))
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

    /// Runs of whole pixels, each added by its own task (runs of 3 pixels, so the last group of
    /// each run is short), give the sample-by-sample sums; runs that would split a pixel are refused.
    #[test]
    fn pixel_runs_add_exactly_like_single_samples() {
        use rayon::prelude::*;
        let mut rng = SplitMix64::new(11);
        let (spp, pixels) = (4usize, 14usize);
        let rgb: Vec<Vec3> =
            (0..spp * pixels).map(|_| Vec3::new(rng.f32(), rng.f32() * 1e4, rng.f32() * 1e-4)).collect();
        let (mut serial, mut runs) = (Film::new(pixels as u32, 1), Film::new(pixels as u32, 1));
        for (k, &c) in rgb.iter().enumerate() {
            serial.add((k / spp) as u32, c);
        }
        // Two batches: samples 0..24 and 24..56, in runs of 12 samples (3 pixels).
        for (first, len) in [(0, 24), (24, 32)] {
            let batch = &rgb[first..first + len];
            let pixel_runs = runs.pixel_runs_mut(first, len, spp, 12).expect("whole pixels");
            batch.par_chunks(12).zip(pixel_runs).for_each(|(rgb, run)| run.add_whole_pixels(spp, rgb));
        }
        assert_eq!(serial.sum, runs.sum);
        assert_eq!(serial.count, runs.count);
        for (first, len, run) in [(2, 24, 12), (0, 26, 12), (0, 24, 10), (0, 24, 0)] {
            assert!(runs.pixel_runs_mut(first, len, spp, run).is_none(), "{first} {len} {run}");
        }
    }

    /// Sums in which order matters (1e20 + 1 - 1e20 is 0 in f64; 1e20 - 1e20 + 1 is 1) come out as
    /// the sample-by-sample sums, in whole groups of pixels and in the partial ones around them.
    #[test]
    fn each_pixel_adds_its_samples_in_order() {
        let (spp, pixels) = (4usize, 13usize);
        let pattern = [1e20, 1.0, -1e20, 0.5];
        let rgb: Vec<Vec3> = (0..spp * pixels).map(|k| Vec3::splat(pattern[(k + k / spp) % spp])).collect();
        let (mut serial, mut parallel) = (Film::new(pixels as u32, 1), Film::new(pixels as u32, 1));
        for (k, &c) in rgb.iter().enumerate() {
            serial.add((k / spp) as u32, c);
        }
        parallel.par_add_samples(0, spp, &rgb[..6]);
        parallel.par_add_samples(6, spp, &rgb[6..]);
        assert_eq!(serial.sum, parallel.sum);
        assert!(serial.sum.iter().any(|s| s.x == 0.0) && serial.sum.iter().any(|s| s.x != 0.0));
    }
}
