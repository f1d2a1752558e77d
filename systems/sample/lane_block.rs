//! The sampling pass in blocks of lanes (RGB, f32, one sampled or resampled light): a block's
//! points as lane columns, light choice and the point, triangle and image lights' Sample_Li as lane
//! kernels, other kinds one lane at a time; the same entries as `Sampling::entry`, bit for bit.

use glam::Vec2;

use super::{EntryColumns, NO_LIGHT, Sampling, ShadowTarget};
use crate::lanes::{F32x16, LANES, U32x16, Vec3x16};
use crate::light::area::TriangleLightLanes;
use crate::light::point::PointLanes;
use crate::light::{ColorQuery, LiSample, LightId, LightKind};
use crate::rng::SampleStream;
use crate::shading::LightSelection;
use crate::spectrum::SampledSpectrum;

impl Sampling<'_> {
    /// [`Self::write`] of lane `l` of `lit`, point light `light` chosen with `pmf`, without
    /// building a `LiSample` (whose pdf would be 1).
    #[inline(always)]
    fn write_point(
        &self,
        cols: &mut EntryColumns,
        e: usize,
        (light, pmf): (LightId, f32),
        lit: &PointLanes,
        l: usize,
    ) -> bool {
        if !lit.valid.test(l) {
            return self.write(cols, e, light, None);
        }
        let radiance = SampledSpectrum([lit.radiance.x[l], lit.radiance.y[l], lit.radiance.z[l], 0.0]);
        (cols.light[e], cols.occluded[e]) = (light, false);
        let pdf = pmf * self.spp as f32;
        (cols.radiance[e], cols.wi[e], cols.pdf[e]) = (radiance, lit.wi.lane(l), pdf);
        cols.delta[e] = LightKind::Point.flags().is_delta();
        let ray = self.wants_shadow_ray(pdf, &radiance, light);
        cols.ray_kind[e] = if ray { ShadowTarget::Point } else { ShadowTarget::None };
        if ray {
            cols.target[e] = lit.target.lane(l);
        }
        ray
    }

    /// The batch points, random-stream keys, positions and normals of entries `e..e + n` of the
    /// chunk starting at global entry `first`, as lane columns.
    #[inline(always)]
    pub(super) fn block(&self, first: usize, e: usize, n: usize) -> Block {
        let (mut point, mut pixel, mut stream) = ([0usize; LANES], [0u32; LANES], [0u32; LANES]);
        let mut p = Vec3x16::ZERO;
        if self.k == 1 && n == LANES {
            // One entry per point: entries are points, read as contiguous runs (as
            // `point_and_stream`, whose slot and sample offset are then 0).
            let i = first + e;
            let (pixels, samples) = (&self.batch.pixel[i..i + LANES], &self.batch.sample[i..i + LANES]);
            for l in 0..LANES {
                (point[l], pixel[l], stream[l]) = (i + l, pixels[l], samples[l] * self.spp);
            }
            p = Vec3x16::load(&self.batch.position, i);
        } else {
            for l in 0..n {
                let (i, _, s) = self.point_and_stream(first + e + l);
                (point[l], pixel[l], stream[l]) = (i, self.batch.pixel[i], s);
                p.set_lane(l, self.batch.position[i]);
            }
        }
        // The shading normals, which the light BVH ranks clusters by (as the BSDF and RIS's target
        // weigh light).
        let mut normal = Vec3x16::ZERO;
        for l in 0..n {
            normal.set_lane(l, self.batch.shading_normal[point[l]]);
        }
        Block { point, pixel, stream, p, normal }
    }

    /// Samples entries `e..e + LANES` (or to the chunk's end) of the chunk starting at global
    /// entry `first` under `LightSelection::OneSampled` (or `Resampled`, through
    /// `resampled_block`), RGB and f32: random numbers, light choice, point, triangle and image
    /// lights in lanes, lights of other kinds (and triangles the f32 kernel leaves to the f64
    /// reference) one at a time. Same entries as [`Self::entry`], bit for bit. Returns the number
    /// of shadow rays.
    #[inline(always)]
    pub(super) fn lane_block(&self, first: usize, e: usize, cols: &mut EntryColumns) -> usize {
        let n = LANES.min(cols.len() - e);
        if let LightSelection::Resampled { candidates } = self.settings.selection {
            return self.resampled_block(first, e, n, cols, candidates);
        }
        let Block { point, pixel, stream, p, normal } = self.block(first, e, n);
        // The choice at dimension 0, the light's u at 1, 2 (as `entry`).
        let [u, u1, u2] = SampleStream::lanes::<3>(self.settings.light_pattern(), self.settings.seed, &pixel, &stream);
        // The choices as plain lane arrays: arrays of `Option<(LightId, f32)>` cost store-to-load
        // forwarding stalls on every read.
        let (mut light, mut pmf, mut chosen) = ([NO_LIGHT; LANES], [0.0f32; LANES], [false; LANES]);
        let (mut rows, mut points) = ([0u32; LANES], 0);
        let (mut area_rows, mut areas, mut images) = ([0u32; LANES], 0u32, 0u32);
        // `sample_lanes` leaves slots without a finite position unchosen (as `entry`).
        let choices = self.sampler.sample_lanes(&p, &normal, &u, (1u32 << n) - 1);
        for l in 0..n {
            if choices.chosen & (1 << l) == 0 {
                continue;
            }
            let id = choices.light[l];
            (light[l], pmf[l], chosen[l]) = (id, choices.pmf[l], true);
            if id.kind == LightKind::Point {
                (rows[l], points) = (id.row, points + 1);
            } else if id.kind == LightKind::Area {
                (area_rows[l], areas) = (id.row, areas | 1 << l);
            } else if id.kind == LightKind::ImageInfinite {
                images |= 1 << l;
            }
        }
        // Blocks where no entry chose a point light (scenes lit by other kinds) skip the kernel;
        // lanes that chose none sample row 0, which exists (see `sample_direct_lighting`).
        // `if`, not `bool::then`: a closure would keep the kernel out of the wide code.
        let lit = if points > 0 { Some(self.table.points.sample_li_rgb_lanes(U32x16(rows), &p)) } else { None };
        let triangles = if areas != 0 {
            Some(TriangleLightLanes::sample(&self.table.area.items, &area_rows, areas, &p, [u1, u2]))
        } else {
            None
        };
        let skies = self.image_lanes(images, &light, &p, [u1, u2]);
        let mut traced = 0;
        for l in 0..n {
            let chosen = chosen[l].then_some((light[l], pmf[l]));
            traced += match (&lit, &triangles, chosen) {
                (_, _, Some(c)) if images & 1 << l != 0 => self.write(cols, e + l, c.0, self.accept(c, skies[l])),
                (Some(lit), _, Some(c)) if c.0.kind == LightKind::Point => self.write_point(cols, e + l, c, lit, l),
                (_, Some(tri), Some(c)) if c.0.kind == LightKind::Area && tri.taken.test(l) => {
                    let light = &self.table.area.items[c.0.row as usize].light;
                    let (ctx, u) = (self.context(point[l]), Vec2::new(u1[l], u2[l]));
                    let ls = tri.sample_li(light, l, &ctx, u, ColorQuery::Rgb).flatten();
                    self.write(cols, e + l, c.0, self.accept(c, ls))
                }
                _ => {
                    let u = Vec2::new(u1[l], u2[l]);
                    let sampled = chosen.and_then(|c| {
                        self.evaluate_at(point[l], &self.context(point[l]), c, self.unless_delta(c.0, u))
                    });
                    self.write(cols, e + l, light[l], sampled)
                }
            } as usize;
        }
        traced
    }

    /// Sample_Li of the image lights that the lanes in `images` chose (`light`), from points `p`
    /// at `u`: one lane kernel call per image light among them.
    #[inline(always)]
    pub(super) fn image_lanes(
        &self,
        images: u32,
        light: &[LightId; LANES],
        p: &Vec3x16,
        u: [F32x16; 2],
    ) -> [Option<LiSample>; LANES] {
        let mut out = [None; LANES];
        let mut left = images;
        while left != 0 {
            let row = light[left.trailing_zeros() as usize].row;
            let same = (0..LANES).filter(|&l| left & 1 << l != 0 && light[l].row == row).fold(0, |m, l| m | 1 << l);
            let image = &self.table.image_infinite().items[row as usize];
            let found = image.sample_li_rgb_lanes(p, u, same, self.table.mis_compensation());
            for l in (0..LANES).filter(|&l| same & 1 << l != 0) {
                out[l] = found[l];
            }
            left &= !same;
        }
        out
    }
}

/// A block's points as lane columns (see `Sampling::block`).
pub(super) struct Block {
    pub(super) point: [usize; LANES],
    pub(super) pixel: [u32; LANES],
    pub(super) stream: [u32; LANES],
    pub(super) p: Vec3x16,
    /// Shading normals.
    pub(super) normal: Vec3x16,
}
