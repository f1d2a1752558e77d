//! Shading a surface point from the light system's answers: the light samples weighted by MIS,
//! and the light a BSDF ray finds (an emitter it hits, or the infinite lights when it escapes)
//! weighted against the light sampler's pmf and `pdf_li`. The direct integrator and each bounce
//! of the path tracer use the same pieces.

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::bsdf::{Bsdf, BsdfSample};
use super::camera_pass::{CameraColumns, SampleSurface};
use super::material::Material;
use super::renderer::{Strategy, to_rgb};
use crate::geometry::{Hit, SceneBvh, ShadowOffset, SurfacePoint};
use crate::lanes::{LANES, Vec3x16};
use crate::light::{ColorQuery, LightId, LightKind, LightSampleContext, LightTable};
use crate::light_sampler::LightSampler;
use crate::rng::{Pattern, SampleStream};
use crate::sampling::Frame;
use crate::shading::{DirectLighting, LightSelection, Settings, ShadingBatch};
use crate::spectrum::SampledSpectrum;
use crate::systems::GeometryIndex;

/// The material of geometry that has none.
static DEFAULT_MATERIAL: std::sync::LazyLock<Material> = std::sync::LazyLock::new(Material::default);

/// Dimension of a sample's renderer stream where the BSDF sample of its first surface starts;
/// each later surface takes the next `BSDF_DIMENSIONS` (lobe, direction, roulette).
pub(super) const BSDF_DIMENSION: u32 = 16;
pub(super) const BSDF_DIMENSIONS: u32 = 4;

/// The world's materials, in the order of the scene BVH's instances, and what is worked out
/// from them once per render.
pub(super) struct Materials {
    pub(super) materials: Vec<Material>,
    /// Each material's [`Material::uniform_rgb_bsdf`].
    pub(super) uniform_bsdfs: Vec<Option<Bsdf>>,
    /// Whether some material has a normal texture.
    pub(super) any_normal_map: bool,
}

impl Materials {
    pub(super) fn of(world: &World) -> Self {
        let entities = &world.resource::<GeometryIndex>().entities;
        let materials: Vec<Material> =
            entities.iter().map(|&e| world.get::<Material>(e).cloned().unwrap_or_default()).collect();
        let uniform_bsdfs = materials.iter().map(Material::uniform_rgb_bsdf).collect();
        let any_normal_map = materials.iter().any(|m| m.normal_texture.is_some());
        Self { materials, uniform_bsdfs, any_normal_map }
    }
}

/// Read-only state for shading one batch in parallel.
pub(super) struct ShadeContext<'a> {
    pub(super) table: &'a LightTable,
    sampler: &'a LightSampler,
    pub(super) lighting: &'a DirectLighting,
    pub(super) batch: &'a ShadingBatch,
    pub(super) bvh: &'a SceneBvh,
    /// The samples' directions and surfaces, indexed like `batch`.
    pub(super) columns: &'a CameraColumns,
    /// The light rows of each BVH instance's entity (empty for geometry that emits nothing).
    pub(super) lights_of_instance: Vec<&'a [LightId]>,
    materials: &'a [Material],
    /// Each material's [`Material::uniform_rgb_bsdf`].
    pub(super) uniform_bsdfs: &'a [Option<Bsdf>],
    /// Seed and pattern of the renderer's own streams.
    pub(super) seed: u64,
    pub(super) pattern: Pattern,
    pub(super) strategy: Strategy,
    /// How BSDF rays leave the surface (as shadow rays do).
    pub(super) offset: ShadowOffset,
    /// Every light is sampled for every point (pmf 1) rather than one chosen by the sampler.
    all_lights: bool,
    /// Light samples per point (`Settings::samples_per_point`): a BSDF sample's MIS weight is
    /// against their density together, as the entries' pdfs are.
    light_samples: f32,
    /// The infinite lights, which rays that hit nothing see.
    pub(super) escape_ids: Vec<LightId>,
}

impl<'a> ShadeContext<'a> {
    /// The context of the world's last schedule run, for the samples of `columns`.
    pub(super) fn new(
        world: &'a World,
        columns: &'a CameraColumns,
        materials: &'a Materials,
        seed: u64,
        strategy: Strategy,
    ) -> Self {
        let table = world.resource::<LightTable>();
        let settings = world.resource::<Settings>();
        Self {
            table,
            sampler: world.resource::<LightSampler>(),
            lighting: world.resource::<DirectLighting>(),
            batch: world.resource::<ShadingBatch>(),
            bvh: world.resource::<SceneBvh>(),
            columns,
            lights_of_instance: world.resource::<GeometryIndex>().entities.iter().map(|&e| table.rows_of(e)).collect(),
            materials: &materials.materials,
            uniform_bsdfs: &materials.uniform_bsdfs,
            seed,
            pattern: settings.pattern,
            // A resampled light sample's density is not `pmf * pdf_li` (see `LightSelection`).
            strategy: if settings.selection.is_resampled() { Strategy::LightOnly } else { strategy },
            offset: settings.shadow_offset,
            all_lights: settings.selection == LightSelection::All,
            light_samples: settings.samples_per_point.max(1) as f32,
            escape_ids: table.escape_lights().collect(),
        }
    }

    /// Whether BSDF samples can find light the light samples miss (some light is not delta).
    pub(super) fn bsdf_sampling(&self) -> bool {
        self.strategy != Strategy::LightOnly && self.table.has_non_delta_lights()
    }

    /// The area light `hit` landed on and its radiance toward `w` (unit, away from the surface).
    fn emitted(&self, hit: &Hit, w: Vec3, query: ColorQuery) -> Option<(LightId, SampledSpectrum)> {
        let surface = SampleSurface {
            uv: hit.uv,
            material: hit.material,
            instance: hit.instance,
            primitive: hit.id.primitive,
            flipped: false,
        };
        self.emitted_at(&surface, hit.p, hit.ng, w, query)
    }

    /// Whether a surface of instance `instance` may emit: whether it carries area lights.
    #[inline(always)]
    pub(super) fn may_emit(&self, instance: u32) -> bool {
        self.lights_of_instance.get(instance as usize).is_some_and(|rows| !rows.is_empty())
    }

    /// [`Self::emitted`] at point `p` of `surface`, whose geometric normal is `ng`.
    fn emitted_at(
        &self,
        surface: &SampleSurface,
        p: Vec3,
        ng: Vec3,
        w: Vec3,
        query: ColorQuery,
    ) -> Option<(LightId, SampledSpectrum)> {
        let rows = self.lights_of_instance.get(surface.instance as usize)?;
        if rows.is_empty() {
            return None;
        }
        let id = self.table.area_light_among(rows, surface.primitive)?;
        let light = &self.table.area.items[id.row as usize].light;
        Some((id, light.radiance(p, ng, surface.uv, w, query)))
    }

    /// The query of sample `j`'s colour mode.
    fn query(&self, j: usize) -> ColorQuery<'a> {
        self.batch.wavelengths.get(j).map_or(ColorQuery::Rgb, ColorQuery::Spectral)
    }

    /// The surface sample `j` lies on, and its BSDF.
    fn surface_and_bsdf(&self, j: usize) -> (SampleSurface, Bsdf) {
        let surface = self.columns.surface(j, self.batch.geometry[j].primitive);
        let ns = self.batch.shading_normal[j];
        let material = self.materials.get(surface.material as usize).unwrap_or(&DEFAULT_MATERIAL);
        let bsdf = match (self.query(j), self.uniform_bsdfs.get(surface.material as usize)) {
            (ColorQuery::Rgb, Some(Some(b))) => Bsdf { frame: Frame::from_z(ns), ..*b },
            (query, _) => material.bsdf(surface.uv, ns, query),
        };
        (surface, bsdf)
    }

    /// The light the camera sees on sample `j`'s surface when it emits, unweighted (its
    /// sidedness needs the unflipped normal). Later surfaces' emission is weighed where the BSDF
    /// ray that found them is traced.
    fn emitted_toward_viewer(&self, j: usize, surface: &SampleSurface) -> SampledSpectrum {
        let n = self.batch.normal[j];
        let ng = if surface.flipped { -n } else { n };
        let wo = -self.columns.dir(j);
        self.emitted_at(surface, self.batch.position[j], ng, wo, self.query(j))
            .map_or(SampledSpectrum::default(), |e| e.1)
    }

    /// The light system's samples at sample `j`, each weighted by MIS against `bsdf`.
    fn light_samples(&self, j: usize, bsdf: &Bsdf) -> SampledSpectrum {
        let (wo, ns) = (-self.columns.dir(j), self.batch.shading_normal[j]);
        let mut l = SampledSpectrum::default();
        for e in self.lighting.entries(j) {
            let (li, wi, pdf) = (self.lighting.radiance[e], self.lighting.wi[e], self.lighting.pdf[e]);
            if pdf <= 0.0 {
                continue;
            }
            let f = bsdf.f(wo, wi);
            let w = if self.lighting.delta[e] { 1.0 } else { self.strategy.light_weight(pdf, bsdf.pdf(wo, wi)) };
            if w == 0.0 {
                continue;
            }
            l = l.add(f.mul(li).scale(wi.dot(ns).abs() * w / pdf));
        }
        l
    }

    /// Sample `j`'s light-sampling context: where its light samples were drawn from.
    fn context(&self, j: usize) -> LightSampleContext {
        LightSampleContext { p: self.batch.position[j], n: self.batch.normal[j], ns: self.batch.shading_normal[j] }
    }

    /// Sample `j`'s renderer stream at dimension `dim`.
    fn stream(&self, j: usize, dim: u32) -> SampleStream {
        SampleStream::new(self.pattern, self.seed, self.batch.pixel[j], self.batch.sample[j]).at_dimension(dim)
    }

    /// The BSDF sample at sample `j`'s surface drawn from `rng` (lobe, then direction), with the
    /// ray it leaves along.
    fn sample_bsdf(&self, j: usize, bsdf: &Bsdf, rng: &mut SampleStream) -> Option<(BsdfSample, crate::geometry::Ray)> {
        let bs = bsdf.sample(-self.columns.dir(j), rng.next_f32(), rng.next_2d())?;
        let from =
            SurfacePoint { p: self.batch.position[j], p_error: self.batch.position_error[j], n: self.batch.normal[j] };
        Some((bs, self.offset.spawn_ray(&from, bs.wi)))
    }

    /// The light a BSDF ray along `wi` (drawn with solid-angle pdf `bsdf_pdf` at `from`) finds,
    /// weighted by MIS against the light sampler: the emitter at `hit`, or the infinite lights
    /// when it escaped.
    pub(super) fn found_by_bsdf_ray(
        &self,
        from: &LightSampleContext,
        wi: Vec3,
        bsdf_pdf: f32,
        hit: Option<&Hit>,
        query: ColorQuery,
    ) -> SampledSpectrum {
        match hit {
            Some(h) => self.emitted(h, -wi, query).map_or(SampledSpectrum::default(), |(id, le)| {
                le.scale(self.bsdf_weight(from, id, bsdf_pdf, self.table.pdf_li(id, from, wi)))
            }),
            None => self.escape_ids.iter().fold(SampledSpectrum::default(), |acc, &id| {
                let Some((le, pdf)) = self.table.le_and_pdf_li(id, from, wi, query) else { return acc };
                acc.add(le.scale(self.bsdf_weight(from, id, bsdf_pdf, pdf)))
            }),
        }
    }

    /// The MIS weight of a BSDF sample (solid-angle pdf `bsdf_pdf`) that found light `id`, whose
    /// `pdf_li` there is `pdf_li`, against the light samples drawn from `from`.
    #[inline]
    fn bsdf_weight(&self, from: &LightSampleContext, id: LightId, bsdf_pdf: f32, pdf_li: f32) -> f32 {
        let pmf = self.light_samples * if self.all_lights { 1.0 } else { self.sampler.pmf(from, id) };
        self.strategy.bsdf_weight(bsdf_pdf, pmf * pdf_li)
    }

    /// [`Self::found_by_bsdf_ray`] of rays `ray(0..out.len())` (at most `LANES`) into `out`, the
    /// same bits: in RGB, the rays that escaped look up each image light with its lane kernel
    /// (whose gathers overlap), other lights one ray at a time.
    pub(super) fn found_by_bsdf_rays<'r>(&self, ray: impl Fn(usize) -> BsdfRay<'r>, out: &mut [SampledSpectrum]) {
        let n = out.len();
        debug_assert!((1..=LANES).contains(&n));
        // Lanes past `n` repeat the last ray; only the first `n` are read.
        let rays: [BsdfRay; LANES] = std::array::from_fn(|k| ray(k.min(n - 1)));
        let rays = &rays[..n];
        let (mut escaped, mut wi, mut rgb) = (0u32, Vec3x16::ZERO, true);
        for (l, (r, out)) in rays.iter().zip(out.iter_mut()).enumerate() {
            *out = SampledSpectrum::default();
            match r.hit {
                Some(_) => *out = self.found_by_bsdf_ray(&r.from, r.wi, r.bsdf_pdf, r.hit, r.query),
                None => {
                    (escaped, rgb) = (escaped | 1 << l, rgb && matches!(r.query, ColorQuery::Rgb));
                    wi.set_lane(l, r.wi);
                }
            }
        }
        if escaped == 0 {
            return;
        }
        let lanes = |mask: u32| (0..rays.len()).filter(move |l| mask & 1 << l != 0);
        let kernel = rgb && !escape_kernel_off();
        for &id in &self.escape_ids {
            if id.kind == LightKind::ImageInfinite && kernel {
                let image = &self.table.image_infinite().items[id.row as usize];
                let mis = self.table.mis_compensation();
                let found = crate::lanes::widest(
                    #[inline(always)]
                    || image.le_and_pdf_rgb_lanes(&wi, escaped, mis),
                );
                for l in lanes(found.lit) {
                    let (r, le) = (&rays[l], found.le.lane(l));
                    let le = SampledSpectrum([le.x, le.y, le.z, 0.0]);
                    out[l] = out[l].add(le.scale(self.bsdf_weight(&r.from, id, r.bsdf_pdf, found.pdf[l])));
                }
            } else {
                for l in lanes(escaped) {
                    let r = &rays[l];
                    if let Some((le, pdf)) = self.table.le_and_pdf_li(id, &r.from, r.wi, r.query) {
                        out[l] = out[l].add(le.scale(self.bsdf_weight(&r.from, id, r.bsdf_pdf, pdf)));
                    }
                }
            }
        }
    }

    /// What escaped sample `j` sees: the infinite lights along its direction, unweighted.
    pub(super) fn escaped(&self, j: usize) -> SampledSpectrum {
        let (dir, query) = (self.columns.dir(j), self.query(j));
        self.escape_ids.iter().fold(SampledSpectrum::default(), |acc, &id| acc.add(self.table.le(id, dir, query)))
    }

    /// Direct light at camera samples `first..first + out.len()` (at most `LANES`), in RGB:
    /// emission, the light system's samples weighted by MIS, plus one BSDF sample each toward
    /// non-delta lights, whose rays' light is found together. Returns the number of rays traced.
    pub(super) fn shade_direct_block(&self, first: usize, out: &mut [Vec3], bsdf_sampling: bool) -> usize {
        debug_assert!(out.len() <= LANES);
        let mut l = [SampledSpectrum::default(); LANES];
        let mut rays_traced = 0;
        // The BSDF samples that may find light (escaped, or hit an emitter): their lanes, samples,
        // shading normals and hits. A ray that hits a surface without area lights finds nothing,
        // so it needs no hit record.
        let mut traced = 0;
        let (mut lane, mut sampled, mut hits) = ([0usize; LANES], [None; LANES], [None; LANES]);
        for (i, l) in l.iter_mut().enumerate().take(out.len()) {
            let j = first + i;
            if self.columns.escaped(j) {
                *l = self.escaped(j);
                continue;
            }
            let (surface, bsdf) = self.surface_and_bsdf(j);
            *l = self.emitted_toward_viewer(j, &surface).add(self.light_samples(j, &bsdf));
            if bsdf_sampling && let Some((bs, ray)) = self.sample_bsdf(j, &bsdf, &mut self.stream(j, BSDF_DIMENSION)) {
                rays_traced += 1;
                let hit = self.bvh.closest_hit_ref(&ray);
                if hit.is_some_and(|h| !self.may_emit(self.bvh.hit_instance(&h))) {
                    continue;
                }
                (lane[traced], sampled[traced], hits[traced]) =
                    (i, Some((bs, bsdf.frame.z)), hit.map(|h| self.bvh.hit_record(&ray, h)));
                traced += 1;
            }
        }
        let ray = |k: usize| {
            let (j, (bs, _)) = (first + lane[k], sampled[k].expect("a traced sample"));
            BsdfRay { from: self.context(j), wi: bs.wi, bsdf_pdf: bs.pdf, hit: hits[k].as_ref(), query: self.query(j) }
        };
        let mut found = [SampledSpectrum::default(); LANES];
        if traced > 0 {
            self.found_by_bsdf_rays(ray, &mut found[..traced]);
        }
        for k in 0..traced {
            let (bs, z) = sampled[k].expect("a traced sample");
            let l = &mut l[lane[k]];
            *l = l.add(bs.f.mul(found[k]).scale(bs.wi.dot(z).abs() / bs.pdf));
        }
        for (i, out) in out.iter_mut().enumerate() {
            *out = to_rgb(l[i], self.batch.wavelengths.get(first + i));
        }
        rays_traced
    }
}

/// Test switch: image lights' escape lookups one ray at a time, to compare with the kernel.
#[cfg(test)]
static ESCAPE_KERNEL_OFF: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

#[inline(always)]
fn escape_kernel_off() -> bool {
    #[cfg(test)]
    return ESCAPE_KERNEL_OFF.load(std::sync::atomic::Ordering::Relaxed);
    #[cfg(not(test))]
    false
}

/// A traced BSDF ray, as [`ShadeContext::found_by_bsdf_rays`] reads it.
#[derive(Clone, Copy)]
pub(super) struct BsdfRay<'a> {
    /// The surface it left, as the light sampler saw it.
    pub(super) from: LightSampleContext,
    /// Unit direction.
    pub(super) wi: Vec3,
    /// Solid-angle density of the BSDF sample.
    pub(super) bsdf_pdf: f32,
    /// What it hit; None when it escaped.
    pub(super) hit: Option<&'a Hit>,
    pub(super) query: ColorQuery<'a>,
}

/// What the path tracer's shading of one surface gives: the light to add to the path's radiance
/// (already times its throughput), and the ray that continues it, if it goes on.
pub(super) struct Bounce {
    pub(super) radiance: SampledSpectrum,
    pub(super) next: Option<Continuation>,
}

/// A path leaving a surface along a BSDF sample.
#[derive(Clone, Copy)]
pub(super) struct Continuation {
    pub(super) ray: crate::geometry::Ray,
    /// Unit direction of `ray`.
    pub(super) wi: Vec3,
    /// Throughput after this surface (roulette included).
    pub(super) beta: SampledSpectrum,
    /// The surface it leaves, as the light sampler saw it (for MIS of what the ray finds).
    pub(super) from: LightSampleContext,
    pub(super) bsdf_pdf: f32,
}

/// The path tracer's per-surface knobs.
#[derive(Clone, Copy)]
pub(super) struct BounceRules {
    /// Whether the surface only shows its emission (depth 0 of a `max_depth` 0 render).
    pub(super) emission_only: bool,
    /// Whether this surface is the path's last: its BSDF ray only looks for emitters.
    pub(super) last: bool,
    /// Whether Russian roulette may end the path here.
    pub(super) roulette: bool,
    /// Whether the surface's own emission counts (a camera's first surface; no later one, whose
    /// emission the BSDF ray that found it weighs, and no lightmap texel).
    pub(super) emission: bool,
    /// Whether the surface's BSDF ray is traced even where it can find no light: a bake's first
    /// ray, whose hit the leak test reads (at depth 1 under delta lights alone, too).
    pub(super) leak_probe: bool,
    /// Whether light that reaches the surface straight from a light counts: its light samples and
    /// the emitters its BSDF ray finds (false only for a texel baked as bounced light alone).
    pub(super) direct: bool,
}

impl ShadeContext<'_> {
    /// Sample `j` as surface `depth` (0 = the path's first) of a path with throughput `beta`: its
    /// emission when the rules count it, its light samples, and the BSDF sample that continues
    /// the path (traced for MIS unless roulette ends it, or the path ends here and no light could
    /// be found by it).
    pub(super) fn shade_path_vertex(&self, j: usize, depth: u32, beta: SampledSpectrum, rules: BounceRules) -> Bounce {
        let (surface, bsdf) = self.surface_and_bsdf(j);
        // Emission found by later BSDF rays is added, MIS-weighted, where they are traced.
        let mut l = if rules.emission { self.emitted_toward_viewer(j, &surface) } else { SampledSpectrum::default() };
        if rules.emission_only {
            return Bounce { radiance: beta.mul(l), next: None };
        }
        if rules.direct {
            l = l.add(self.light_samples(j, &bsdf));
        }
        let radiance = beta.mul(l);
        // The last surface's BSDF ray only looks for emitters: none to find (delta lights only, or
        // light samples alone), none traced, unless the leak test reads it (it then finds nothing).
        if rules.last && !rules.leak_probe && !self.bsdf_sampling() {
            return Bounce { radiance, next: None };
        }
        let dim = BSDF_DIMENSION + depth * BSDF_DIMENSIONS;
        // Lobe, direction and roulette: one set of the stream.
        let mut rng = self.stream(j, dim);
        let Some((bs, ray)) = self.sample_bsdf(j, &bsdf, &mut rng) else { return Bounce { radiance, next: None } };
        let mut next_beta = beta.mul(bs.f).scale(bs.wi.dot(bsdf.frame.z).abs() / bs.pdf);
        if rules.roulette && !rules.last {
            // pbrt-v4's roulette: continue with probability max(beta) when that is below 1.
            let keep = next_beta.0.iter().fold(0.0f32, |m, &c| m.max(c));
            if keep < 1.0 {
                let u = rng.next_f32();
                if u >= keep {
                    return Bounce { radiance, next: None };
                }
                next_beta = next_beta.scale(1.0 / keep);
            }
        }
        let finite = next_beta.0.iter().all(|c| c.is_finite());
        let next =
            finite.then_some(Continuation { ray, wi: bs.wi, beta: next_beta, from: self.context(j), bsdf_pdf: bs.pdf });
        Bounce { radiance, next }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use bevy_ecs::prelude::*;
    use glam::{Vec2, Vec3};

    use crate::geometry::{Rectangle, Transform};
    use crate::light::{Amount, AreaLight, ImageInfiniteLight, UniformInfiniteLight};
    use crate::render::camera::Camera;
    use crate::render::material::Material;
    use crate::render::path::PathDepth;
    use crate::render::renderer::{Integrator, RenderOptions, render};
    use crate::scene::image::RgbImage;
    use crate::shading::Settings;
    use crate::systems::LightingPlugin;

    /// A floor under a turned sky map with a bright sun, a uniform sky, and an emissive panel that
    /// BSDF rays hit, seen with the horizon in view: blocks mix rays that escape with rays that hit.
    fn pixels(integrator: Integrator) -> Vec<Vec3> {
        let mut world = World::new();
        let mut schedule = Schedule::default();
        world.insert_resource(Settings::default());
        LightingPlugin::build(&mut world, &mut schedule);
        let up = Transform::default().looking_to(Vec3::NEG_Y, Vec3::Z);
        world.spawn((Rectangle { half_size: Vec2::splat(5.0) }, up, Material::lambertian(Vec3::new(0.5, 0.3, 0.8))));
        let panel =
            Transform::from_translation(Vec3::new(1.0, 1.0, -1.0)).looking_to(Vec3::new(-1.0, -1.0, 1.0), Vec3::Y);
        world.spawn((
            Rectangle { half_size: Vec2::splat(0.5) },
            panel,
            AreaLight { amount: Amount::Nits(20.0), ..Default::default() },
        ));
        let (w, h) = (32, 16);
        let mut sky: Vec<Vec3> =
            (0..w * h).map(|i| Vec3::new(0.3, 0.4 + (i % w) as f32 * 0.01, 0.9 - (i / w) as f32 * 0.04)).collect();
        sky[3 * w + 7] = Vec3::splat(2e3);
        let map = ImageInfiniteLight::new(Arc::new(RgbImage { width: w, height: h, pixels: sky }));
        let turn = Transform { rotation: glam::Quat::from_rotation_y(0.7), ..Transform::IDENTITY };
        world.spawn((map, turn));
        world.spawn((UniformInfiniteLight { amount: Amount::Nits(0.2), ..Default::default() }, Transform::IDENTITY));
        let eye = Vec3::new(0.0, 1.0, 4.0);
        world.spawn((
            Camera { yfov: 1.2 },
            Transform::from_translation(eye).looking_to(Vec3::new(0.0, -0.3, -1.0), Vec3::Y),
        ));
        let opts = RenderOptions { width: 24, height: 16, spp: 4, integrator, ..Default::default() };
        render(&mut world, &mut schedule, &opts, |_| {}).0.pixels()
    }

    #[test]
    fn escape_kernel_matches_one_ray_at_a_time_bit_for_bit_in_both_integrators() {
        use std::sync::atomic::Ordering::Relaxed;
        let path = Integrator::Path(PathDepth { max_depth: 3, roulette_depth: 1 });
        for integrator in [Integrator::Direct, path] {
            let kernel = pixels(integrator);
            super::ESCAPE_KERNEL_OFF.store(true, Relaxed);
            let one_at_a_time = pixels(integrator);
            super::ESCAPE_KERNEL_OFF.store(false, Relaxed);
            // The sky fills the top of the image; the floor is lit.
            let bright = kernel.iter().filter(|p| p.min_element() > 0.0).count();
            assert!(bright > kernel.len() * 3 / 4 && kernel.iter().all(|p| p.is_finite()), "{bright} lit pixels");
            let differs = kernel
                .iter()
                .zip(&one_at_a_time)
                .position(|(a, b)| a.to_array().map(f32::to_bits) != b.to_array().map(f32::to_bits));
            assert_eq!(differs, None, "{integrator:?}: first differing pixel");
        }
    }
}
