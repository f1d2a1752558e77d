//! Triangle lights' Sample_Li for a block of lanes: the chosen rows' triangles gathered into lane
//! columns and sampled by the f32 kernel [`sample_triangle`], the one that scalar callers run at
//! one value, so a lane gives the bits of the scalar call. The radiance (sides, texture) is looked
//! up per lane afterwards; lanes whose error bounds the kernel refuses go to the f64 reference, as
//! the scalar call does.

use glam::Vec2;

use super::ResolvedArea;
use super::fast::{TriangleSample, sample_triangle};
use super::shapes::{AreaShape, ShapeSample, SurfacePoint};
use crate::lanes::{F32x16, LANES, Mask16, Vec3x16};
use crate::light::table::AreaRow;
use crate::light::{ColorQuery, LiSample, LightSampleContext};

/// The kernel's samples of a block's triangle lights, and the lanes it ran for.
pub struct TriangleLightLanes {
    /// The kernel's result per lane.
    pub sample: TriangleSample<F32x16>,
    /// Lanes whose light is a triangle the kernel takes (as [`AreaShape::sample_fast_with`]
    /// does: positive area, a plane normal, a finite point); the others were not sampled.
    pub taken: Mask16,
}

impl TriangleLightLanes {
    /// Samples light `rows[row[l]]` from `p` at `u` for each lane `l` set in `lanes` (bit `l`)
    /// whose light is a triangle.
    #[inline(always)]
    pub fn sample(rows: &[AreaRow], row: &[u32; LANES], lanes: u32, p: &Vec3x16, u: [F32x16; 2]) -> Self {
        let (mut v, mut normal, mut area) = ([Vec3x16::ZERO; 3], Vec3x16::ZERO, F32x16::ZERO);
        let mut taken = [false; LANES];
        for l in (0..LANES).filter(|l| lanes & (1 << l) != 0) {
            let light = &rows[row[l] as usize].light;
            if let AreaShape::Triangle { p: vertices, .. } = light.shape
                && light.area > 0.0
                && light.normal != glam::Vec3::ZERO
                && p.lane(l).is_finite()
            {
                for (column, vertex) in v.iter_mut().zip(vertices) {
                    column.set_lane(l, vertex);
                }
                normal.set_lane(l, light.normal);
                area[l] = light.area;
                taken[l] = true;
            }
        }
        Self { sample: sample_triangle(v, normal, area, *p, u), taken: Mask16::from_bools(taken) }
    }

    /// Whether lane `l` was sampled here and needs no reference.
    #[inline(always)]
    pub fn done(&self, l: usize) -> bool {
        self.taken.test(l) && !self.sample.reference.test(l)
    }

    /// [`ResolvedArea::sample_li`] of lane `l`'s light from `ctx` at `u` (those of the block), as
    /// the kernel left it: its sample, or the f64 reference's where its bounds call for it (as
    /// `sample_li` falls back, without running the f32 kernel again); None for a lane not taken.
    #[inline]
    pub fn sample_li(
        &self,
        light: &ResolvedArea,
        l: usize,
        ctx: &LightSampleContext,
        u: Vec2,
        query: ColorQuery,
    ) -> Option<Option<LiSample>> {
        if !self.taken.test(l) {
            None
        } else if self.sample.reference.test(l) {
            Some(light.sample_li_f64(ctx, u, query))
        } else {
            Some(light.sample_li_from_lane(self, l, query))
        }
    }
}

impl ResolvedArea {
    /// Sample_Li from lane `l` of `lanes` (a lane [`TriangleLightLanes::done`] with), as
    /// [`ResolvedArea::sample_li`] gives it.
    #[inline]
    pub fn sample_li_from_lane(&self, lanes: &TriangleLightLanes, l: usize, query: ColorQuery) -> Option<LiSample> {
        let (s, AreaShape::Triangle { uv, .. }) = (&lanes.sample, self.shape) else { return None };
        if !s.ok.test(l) {
            return None;
        }
        let b = [s.b[0][l], s.b[1][l], s.b[2][l]];
        let uv = b[0] * uv[0] + b[1] * uv[1] + b[2] * uv[2];
        let point = SurfacePoint { p: s.p.lane(l), n: self.normal, uv };
        self.li_sample(ShapeSample { point, wi: s.wi.lane(l), pdf: s.pdf[l] }, query)
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use glam::{Vec2, Vec3};

    use super::*;
    use crate::lanes::{Level, at_level};
    use crate::light::{Amount, Emitter, LightSampleContext, LightTexture};
    use crate::rng::SplitMix64;
    use crate::spectrum::Spectrum;

    fn row(p: [Vec3; 3], two_sided: bool, texture: Option<Arc<LightTexture>>) -> AreaRow {
        let shape = AreaShape::Triangle { p, uv: [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.3, 1.0)] };
        let emitter = Emitter::from_amount(Spectrum::d65(), Amount::Nits(100.0));
        AreaRow { light: ResolvedArea::new(shape, emitter, two_sided, texture), primitive: 0 }
    }

    #[test]
    fn lanes_give_the_scalar_sample_li_bits_and_its_reference_cases_at_every_level() {
        let tex = LightTexture::new(2, 2, vec![Vec3::ONE, Vec3::ZERO, Vec3::new(0.2, 0.5, 0.9), Vec3::splat(3.0)]);
        let tri = [Vec3::new(-0.5, 2.0, -0.5), Vec3::new(0.5, 2.0, -0.5), Vec3::new(0.0, 2.0, 0.6)];
        let rows = vec![
            row(tri, false, None),                                              // seen from below: its back
            row(tri.map(|v| v * Vec3::new(1.0, -1.0, 1.0)), false, None),       // facing the points
            row(tri, true, Some(Arc::new(tex.unwrap()))),                       // two-sided, textured
            row(tri.map(|v| v * 1e-3 + Vec3::new(0.0, 30.0, 0.0)), true, None), // tiny and far: area sampling
            row(tri.map(|v| (v - Vec3::Y * 2.0) * 1e4 + Vec3::Y * 0.01), true, None), // near a hemisphere
        ];
        let mut rng = SplitMix64::new(5);
        let (mut done, mut referred) = (0, 0);
        for round in 0..400 {
            let mut row_of = [0u32; LANES];
            let mut p = Vec3x16::ZERO;
            let (mut u0, mut u1) = (F32x16::ZERO, F32x16::ZERO);
            for l in 0..LANES {
                row_of[l] = (rng.f32() * rows.len() as f32) as u32 % rows.len() as u32;
                // Points around the origin, some almost in the light's plane (y = 2) and one not finite.
                let q = Vec3::new(rng.f32() * 4.0 - 2.0, rng.f32() * 1.5, rng.f32() * 4.0 - 2.0);
                let q = if l == 3 { Vec3::new(q.x, 2.0 + (rng.f32() - 0.5) * 1e-4, q.z) } else { q };
                p.set_lane(l, if l == 7 && round % 2 == 0 { Vec3::NAN } else { q });
                (u0[l], u1[l]) = (rng.f32(), rng.f32());
            }
            let lanes = 0xffff & !(1 << 11); // a lane the block did not choose a triangle for
            for &level in Level::ALL {
                let Some(got) = at_level(level, || TriangleLightLanes::sample(&rows, &row_of, lanes, &p, [u0, u1]))
                else {
                    continue;
                };
                for l in 0..LANES {
                    let light = &rows[row_of[l] as usize].light;
                    let (ctx, u) = (LightSampleContext::at(p.lane(l)), Vec2::new(u0[l], u1[l]));
                    let scalar = sample_triangle::<f32>(
                        match light.shape {
                            AreaShape::Triangle { p, .. } => p,
                            _ => unreachable!(),
                        },
                        light.normal,
                        light.area,
                        ctx.p,
                        [u.x, u.y],
                    );
                    let taken = l != 11 && ctx.p.is_finite();
                    assert_eq!(got.taken.test(l), taken, "lane {l}");
                    if !taken {
                        continue;
                    }
                    assert_eq!(got.done(l), !scalar.reference, "lane {l} at {level:?} from {}", ctx.p);
                    // Sampled in the lane, or by the f64 reference where the scalar call falls back to it.
                    let lane = got.sample_li(light, l, &ctx, u, ColorQuery::Rgb).expect("a lane taken");
                    let want = light.sample_li(&ctx, u, ColorQuery::Rgb);
                    assert_eq!(format!("{lane:?}"), format!("{want:?}"), "lane {l} at {level:?} from {}", ctx.p);
                    if got.done(l) {
                        done += 1;
                    } else {
                        referred += 1;
                    }
                }
            }
        }
        // Both paths taken often enough to mean something.
        assert!(done > 1000 && referred > 50, "{done} lanes done, {referred} left to the reference");
    }
}
