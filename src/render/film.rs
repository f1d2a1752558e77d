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
