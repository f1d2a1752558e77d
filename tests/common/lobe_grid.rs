//! Cells on the sphere that are fine around one direction (a glossy lobe's centre) and coarse
//! far from it, for binning sampled directions and integrating a density or a BSDF: cells in
//! (s, phi) about `centre`, at an angle theta = 2 atan(c tan(pi s / 2)) from it. c sets the
//! finest cells' size (about pi c / `rings` radians); c = 1 is uniform in theta.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use glam::{DVec3, Vec3};
use kelvin::sampling::Frame;

pub struct LobeGrid {
    frame: Frame,
    c: f64,
    rings: usize,
    sectors: usize,
}

impl LobeGrid {
    pub fn new(centre: Vec3, c: f64, rings: usize, sectors: usize) -> Self {
        Self { frame: Frame::from_z(centre.normalize()), c, rings, sectors }
    }

    pub fn cells(&self) -> usize {
        self.rings * self.sectors
    }

    fn theta(&self, s: f64) -> f64 {
        2.0 * (self.c * (FRAC_PI_2 * s).tan()).atan()
    }

    fn dtheta_ds(&self, s: f64) -> f64 {
        let t = (FRAC_PI_2 * s).tan();
        PI * self.c * (1.0 + t * t) / (1.0 + self.c * self.c * t * t)
    }

    fn direction(&self, s: f64, phi: f64) -> Vec3 {
        let theta = self.theta(s);
        let local = DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        self.frame.from_local(local.as_vec3()).normalize()
    }

    /// The cell a unit direction falls in.
    pub fn cell_of(&self, w: Vec3) -> usize {
        let local = self.frame.to_local(w).as_dvec3();
        // atan2, not acos: an f32 z near 1 has no digits left for a small angle.
        let theta = local.x.hypot(local.y).atan2(local.z);
        let s = ((0.5 * theta).tan() / self.c).atan() / FRAC_PI_2;
        let phi = local.y.atan2(local.x).rem_euclid(TAU);
        let ring = ((s * self.rings as f64) as usize).min(self.rings - 1);
        let sector = ((phi / TAU * self.sectors as f64) as usize).min(self.sectors - 1);
        ring * self.sectors + sector
    }

    /// The integral of `f` over each cell (solid angle measure), by the midpoint rule on `sub` x
    /// `sub` points per cell, and on `fine` x `fine` in the cells that a plane through the origin
    /// with normal `edge` crosses (where `f` jumps, e.g. a BSDF at the horizon).
    pub fn integrate_cells(&self, sub: usize, edge: Vec3, fine: usize, f: impl Fn(Vec3) -> f64) -> Vec<f64> {
        (0..self.cells())
            .map(|k| {
                let (ring, sector) = (k / self.sectors, k % self.sectors);
                let lattice = (0..=6).flat_map(|i| (0..=6).map(move |j| (i as f64 / 6.0, j as f64 / 6.0)));
                let sides = lattice.map(|(a, b)| self.at(ring, sector, a, b).dot(edge) > 0.0).collect::<Vec<_>>();
                let crossed = sides.iter().any(|&x| x) && !sides.iter().all(|&x| x);
                self.integrate_cell(ring, sector, if crossed { fine } else { sub }, &f)
            })
            .collect()
    }

    /// The direction at fractions (a, b) across cell (ring, sector).
    fn at(&self, ring: usize, sector: usize, a: f64, b: f64) -> Vec3 {
        let s = (ring as f64 + a) / self.rings as f64;
        self.direction(s, TAU * (sector as f64 + b) / self.sectors as f64)
    }

    fn integrate_cell(&self, ring: usize, sector: usize, sub: usize, f: &impl Fn(Vec3) -> f64) -> f64 {
        let (ds, dphi) = (1.0 / (self.rings * sub) as f64, TAU / (self.sectors * sub) as f64);
        let mut sum = 0.0;
        for i in 0..sub {
            let s = (ring as f64 + (i as f64 + 0.5) / sub as f64) / self.rings as f64;
            let area = self.theta(s).sin() * self.dtheta_ds(s) * ds * dphi;
            for j in 0..sub {
                let phi = TAU * (sector as f64 + (j as f64 + 0.5) / sub as f64) / self.sectors as f64;
                sum += f(self.direction(s, phi)) * area;
            }
        }
        sum
    }
}
