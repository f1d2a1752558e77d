//! One `match` per Light operation over the `LightTable`'s blocks.

use glam::{Vec2, Vec3};

use super::table::LightTable;
use super::{ColorQuery, LiSample, LightFlags, LightId, LightKind, LightSampleContext};

impl LightTable {
    /// Sample_Li of light `id` at `ctx` with uniform numbers `u`.
    #[inline]
    pub fn sample_li(&self, id: LightId, ctx: &LightSampleContext, u: Vec2, query: ColorQuery) -> Option<LiSample> {
        let i = id.row as usize;
        match id.kind {
            LightKind::Point => self.points.sample_li(i, ctx, query),
            LightKind::Spot => self.spots.sample_li(i, ctx, query),
            LightKind::Distant => self.distant.items[i].sample_li(ctx, u, query),
            LightKind::UniformInfinite => self.uniform_infinite.items[i].sample_li(ctx, u, query),
            LightKind::ImageInfinite if self.mis_compensation => {
                self.image_infinite.items[i].sample_li_mis(ctx, u, query)
            }
            LightKind::ImageInfinite => self.image_infinite.items[i].sample_li(ctx, u, query),
            LightKind::SunSky => self.sun_sky.items[i].sample_li(ctx, u, query),
            LightKind::Projection => self.projection.items[i].sample_li(ctx, query),
            LightKind::Goniometric => self.goniometric.items[i].sample_li(ctx, query),
            LightKind::Area => self.area.items[i].light.sample_li(ctx, u, query),
        }
    }

    /// [`Self::sample_li`] with point, spot and area lights evaluated in f64, their references
    /// (`LightPrecision::F64`); every other kind has only its f32 form.
    #[inline]
    pub fn sample_li_f64(&self, id: LightId, ctx: &LightSampleContext, u: Vec2, query: ColorQuery) -> Option<LiSample> {
        let i = id.row as usize;
        match id.kind {
            LightKind::Point => self.points.sample_li_f64(i, ctx, query),
            LightKind::Spot => self.spots.sample_li_f64(i, ctx, query),
            LightKind::Area => self.area.items[i].light.sample_li_f64(ctx, u, query),
            LightKind::Projection
            | LightKind::Goniometric
            | LightKind::Distant
            | LightKind::UniformInfinite
            | LightKind::ImageInfinite
            | LightKind::SunSky => self.sample_li(id, ctx, u, query),
        }
    }

    /// Pdf_Li: solid-angle density with which `sample_li` returns `wi` (0 for delta lights).
    pub fn pdf_li(&self, id: LightId, ctx: &LightSampleContext, wi: Vec3) -> f32 {
        let i = id.row as usize;
        match id.kind {
            LightKind::Point | LightKind::Spot | LightKind::Projection | LightKind::Goniometric => 0.0,
            LightKind::Distant => self.distant.items[i].pdf_li(wi),
            LightKind::UniformInfinite => self.uniform_infinite.items[i].pdf_li(ctx, wi),
            LightKind::ImageInfinite if self.mis_compensation => self.image_infinite.items[i].pdf_li_mis(wi),
            LightKind::ImageInfinite => self.image_infinite.items[i].pdf_li(wi),
            LightKind::SunSky => self.sun_sky.items[i].pdf_li(wi),
            LightKind::Area => self.area.items[i].light.pdf_li(ctx, wi),
        }
    }

    /// The emission flags of light `id`.
    pub fn flags(&self, id: LightId) -> LightFlags {
        match id.kind {
            LightKind::Distant => self.distant.items[id.row as usize].flags(),
            kind @ (LightKind::Point
            | LightKind::Spot
            | LightKind::Area
            | LightKind::Projection
            | LightKind::Goniometric
            | LightKind::UniformInfinite
            | LightKind::ImageInfinite
            | LightKind::SunSky) => kind.flags(),
        }
    }

    /// Radiant power of light `id`, W.
    pub fn phi(&self, id: LightId) -> f32 {
        let i = id.row as usize;
        match id.kind {
            LightKind::Point => self.points.phi(i),
            LightKind::Spot => self.spots.phi(i),
            LightKind::Distant => self.distant.items[i].phi(),
            LightKind::UniformInfinite => self.uniform_infinite.items[i].phi(),
            LightKind::ImageInfinite => self.image_infinite.items[i].phi(),
            LightKind::SunSky => self.sun_sky.items[i].phi(),
            LightKind::Projection => self.projection.items[i].phi(),
            LightKind::Goniometric => self.goniometric.items[i].phi(),
            LightKind::Area => self.area.items[i].light.phi(),
        }
    }

    /// Luminous power of light `id`, lm: its radiant power times its spectrum's efficacy.
    pub fn luminous_power(&self, id: LightId) -> f32 {
        let i = id.row as usize;
        let (rgb_y, radiometric) = match id.kind {
            LightKind::Point => (self.points.rgb[i].y, self.points.radiometric[i]),
            LightKind::Spot => (self.spots.rgb[i].y, self.spots.radiometric[i]),
            LightKind::Area => {
                let e = &self.area.items[i].light.radiance;
                (e.rgb.y, e.radiometric)
            }
            LightKind::Projection => {
                let e = &self.projection.items[i].intensity;
                (e.rgb.y, e.radiometric)
            }
            LightKind::Goniometric => {
                let e = &self.goniometric.items[i].intensity;
                (e.rgb.y, e.radiometric)
            }
            LightKind::Distant => {
                let e = &self.distant.items[i].irradiance;
                (e.rgb.y, e.radiometric)
            }
            LightKind::UniformInfinite => {
                let e = &self.uniform_infinite.items[i].radiance;
                (e.rgb.y, e.radiometric)
            }
            LightKind::ImageInfinite => return self.image_infinite.items[i].luminous_phi().max(0.0),
            LightKind::SunSky => return self.sun_sky.items[i].luminous_phi().max(0.0),
        };
        if radiometric > 0.0 { (self.phi(id) * rgb_y / radiometric).max(0.0) } else { 0.0 }
    }

    /// Bounds for light BVHs; None for lights at infinity (distant, infinite), which samplers
    /// handle outside the tree.
    pub fn bounds(&self, id: LightId) -> Option<super::LightBounds> {
        let i = id.row as usize;
        match id.kind {
            LightKind::Point => Some(self.points.get(i).bounds()),
            LightKind::Spot => Some(self.spots.get(i).bounds()),
            LightKind::Distant => None,
            LightKind::UniformInfinite | LightKind::ImageInfinite | LightKind::SunSky => None,
            LightKind::Projection => Some(self.projection.items[i].bounds()),
            LightKind::Goniometric => Some(self.goniometric.items[i].bounds()),
            LightKind::Area => Some(self.area.items[i].light.bounds()),
        }
    }

    /// Starts loading what [`Self::bounds`] and [`Self::luminous_power`] read of light `id`: a
    /// cache hint for walks over many lights in a data-dependent order (the light BVH's refit).
    pub fn prefetch_bounds(&self, id: LightId) {
        use crate::prefetch::prefetch;
        let i = id.row as usize;
        match id.kind {
            LightKind::Point => {
                let c = &self.points;
                prefetch(&c.position, i);
                prefetch(&c.rgb, i);
                prefetch(&c.radiometric, i);
                prefetch(&c.scale, i);
                prefetch(&c.spectrum, i);
            }
            LightKind::Spot => {
                let c = &self.spots;
                prefetch(&c.position, i);
                prefetch(&c.direction, i);
                prefetch(&c.cos_inner, i);
                prefetch(&c.cos_outer, i);
                prefetch(&c.rgb, i);
                prefetch(&c.radiometric, i);
                prefetch(&c.scale, i);
                prefetch(&c.spectrum, i);
            }
            LightKind::Projection => prefetch(&self.projection.items, i),
            LightKind::Goniometric => prefetch(&self.goniometric.items, i),
            LightKind::Area => prefetch(&self.area.items, i),
            LightKind::Distant | LightKind::UniformInfinite | LightKind::ImageInfinite | LightKind::SunSky => {}
        }
    }

    /// Whether shadow rays are traced for light `id`.
    pub fn casts_shadows(&self, id: LightId) -> bool {
        let i = id.row as usize;
        match id.kind {
            LightKind::Point => self.points.casts_shadows[i],
            LightKind::Spot => self.spots.casts_shadows[i],
            LightKind::Distant => self.distant.casts_shadows[i],
            LightKind::UniformInfinite => self.uniform_infinite.casts_shadows[i],
            LightKind::ImageInfinite => self.image_infinite.casts_shadows[i],
            LightKind::SunSky => self.sun_sky.casts_shadows[i],
            LightKind::Projection => self.projection.casts_shadows[i],
            LightKind::Goniometric => self.goniometric.casts_shadows[i],
            LightKind::Area => self.area.casts_shadows[i],
        }
    }
}

impl LightTable {
    /// Ids of the lights seen by rays that escape the scene (infinite lights, distant lights with
    /// an angular size).
    pub fn escape_lights(&self) -> impl Iterator<Item = LightId> + '_ {
        self.ids().filter(|&id| self.flags(id).contains(LightFlags::INFINITE))
    }

    /// [`Self::le`] and [`Self::pdf_li`] of an escaping ray along `wi`, None where `le` is
    /// black (without its density); an image light maps `wi` into its image once for both.
    pub fn le_and_pdf_li(
        &self,
        id: LightId,
        ctx: &LightSampleContext,
        wi: Vec3,
        query: ColorQuery,
    ) -> Option<(crate::spectrum::SampledSpectrum, f32)> {
        match id.kind {
            LightKind::ImageInfinite => {
                self.image_infinite.items[id.row as usize].le_and_pdf(wi, query, self.mis_compensation)
            }
            LightKind::Distant
            | LightKind::UniformInfinite
            | LightKind::SunSky
            | LightKind::Point
            | LightKind::Spot
            | LightKind::Area
            | LightKind::Projection
            | LightKind::Goniometric => {
                let le = self.le(id, wi, query);
                (!le.0.iter().all(|&v| v == 0.0)).then(|| (le, self.pdf_li(id, ctx, wi)))
            }
        }
    }

    /// Radiance arriving along an escaping ray with direction `wi` from light `id` (zero unless
    /// the light is at infinity and covers `wi`).
    pub fn le(&self, id: LightId, wi: Vec3, query: ColorQuery) -> crate::spectrum::SampledSpectrum {
        match id.kind {
            LightKind::Distant => self.distant.items[id.row as usize].le(wi, query),
            LightKind::UniformInfinite => self.uniform_infinite.items[id.row as usize].le(wi, query),
            LightKind::ImageInfinite => self.image_infinite.items[id.row as usize].le(wi, query),
            LightKind::SunSky => self.sun_sky.items[id.row as usize].le(wi, query),
            LightKind::Point | LightKind::Spot | LightKind::Area | LightKind::Projection | LightKind::Goniometric => {
                Default::default()
            }
        }
    }

    /// True when some light is not a delta light, so BSDF sampling can find it (MIS pays off).
    pub fn has_non_delta_lights(&self) -> bool {
        self.ids().any(|id| !self.flags(id).is_delta())
    }
}
