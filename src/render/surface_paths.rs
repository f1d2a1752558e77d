//! Paths that start at given surface points instead of camera hits: the texels of a lightmap
//! (`kelvin::bake`). Each point is shaded as a white Lambertian surface seen along its normal, so
//! its path's radiance is the irradiance there over pi. Light choice, MIS and every later bounce are
//! the path tracer's own (`path.rs`); only the first surface and what counts at it differ
//! (`path::Start::Surfaces`).

use std::collections::HashMap;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use super::camera_pass::CameraColumns;
use super::material::Material;
use super::path::{PathDepth, PathJob, Paths, Start};
use super::renderer::{BATCH_SAMPLES, RENDER_SALT, RenderStats, Strategy};
use super::shade::Materials;
use crate::geometry::{ClosedSurfaces, GeometryId, SceneBvh};
use crate::scene::animate::GltfNode;
use crate::shading::{RunReport, SceneBounds, Settings, ShadingBatch};
use crate::systems::GeometryIndex;

/// A point to start a path from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StartPoint {
    /// World position, m, and its error bound (for ray offsets).
    pub(crate) p: Vec3,
    pub(crate) p_error: Vec3,
    /// Unit geometric normal of the side the point is shaded on.
    pub(crate) ng: Vec3,
    /// Unit shading normal, on `ng`'s side.
    pub(crate) ns: Vec3,
    /// The primitive the point lies on (its shadow and BSDF rays pass through it).
    pub(crate) geometry: GeometryId,
    /// Keys of the point's random streams.
    pub(crate) pixel: u32,
    pub(crate) sample: u32,
}

/// Traces batches of [`StartPoint`]s through a world, reusing its buffers from batch to batch.
pub(crate) struct SurfaceTracer {
    /// The world's materials, then the white Lambertian every first surface wears.
    materials: Materials,
    white: u32,
    /// BVH instance of each mesh entity, by `Entity::index_u32`.
    instance_of: HashMap<u32, u32>,
    columns: CameraColumns,
    paths: Paths,
    rgb: Vec<Vec3>,
    job: (PathDepth, Start),
    /// The primitives that bound solids: their back faces are leaks, double-sided or not.
    closed: ClosedSurfaces,
    seed: u64,
    pattern: crate::rng::Pattern,
    /// Counts and times, summed over the batches (with the first update's).
    pub(crate) stats: RenderStats,
}

impl SurfaceTracer {
    /// Points per batch handed to the light system (as the renderer's camera batches).
    pub(crate) const BATCH: usize = BATCH_SAMPLES;

    /// Brings the world's BVH and light tables up to date (one run of `schedule`) and prepares
    /// paths of `depth` that count direct light at their first surface or not (`direct`), and
    /// call a first ray that meets a back face nearer than `leak_distance` (m; None: any back
    /// face in the scene) leaked: of a one-sided material, or of a closed surface (the primitives
    /// of a glTF mesh placement are welded together; [`ClosedSurfaces`]).
    pub(crate) fn new(
        world: &mut World,
        schedule: &mut Schedule,
        depth: PathDepth,
        direct: bool,
        leak_distance: Option<f32>,
    ) -> Self {
        let start = std::time::Instant::now();
        let mut stats = RenderStats::default();
        // Light samples are weighed against BSDF samples (image lights may use compensated tables).
        world.resource_mut::<Settings>().mis = true;
        world.resource_mut::<ShadingBatch>().clear();
        schedule.run(world);
        stats.update_seconds = start.elapsed().as_secs_f64();
        stats.report.add(world.resource::<RunReport>());
        let mut materials = Materials::of(world);
        let white = Material::lambertian(Vec3::ONE);
        materials.uniform_bsdfs.push(white.uniform_rgb_bsdf());
        materials.materials.push(white);
        // Any back face in the scene: no two of its points are farther apart than its diameter.
        let leak_distance = leak_distance.unwrap_or_else(|| 2.0 * world.resource::<SceneBounds>().sphere.radius);
        let entities = &world.resource::<GeometryIndex>().entities;
        let instance_of = entities.iter().enumerate().map(|(i, e)| (e.index_u32(), i as u32)).collect();
        // A glTF node's primitives (an entity each) together; any other entity alone.
        let group = |i: u32| match entities.get(i as usize).and_then(|&e| world.get::<GltfNode>(e)) {
            Some(n) => (n.file as u64) << 32 | n.node as u64,
            None => 1 << 63 | i as u64,
        };
        let closed = ClosedSurfaces::of(world.resource::<SceneBvh>(), group);
        Self {
            white: materials.materials.len() as u32 - 1,
            materials,
            instance_of,
            columns: CameraColumns::default(),
            paths: Paths::default(),
            rgb: Vec::new(),
            job: (depth, Start::Surfaces { direct, leak_distance }),
            closed,
            seed: world.resource::<Settings>().seed ^ RENDER_SALT,
            pattern: world.resource::<Settings>().pattern,
            stats,
        }
    }

    /// Seed of the tracer's own random streams; dimensions 0 to 15 of each point's stream are
    /// free for the caller (placing the point), as the camera's are.
    pub(crate) fn seed(&self) -> u64 {
        self.seed
    }

    /// Pattern of the tracer's random streams (the settings').
    pub(crate) fn pattern(&self) -> crate::rng::Pattern {
        self.pattern
    }

    /// Traces one path from each of `points` (at most [`Self::BATCH`] of them, or the light
    /// system takes them in larger batches): each path's radiance (linear sRGB, nit) and whether
    /// its first ray leaked, indexed like `points`.
    pub(crate) fn trace(
        &mut self,
        world: &mut World,
        schedule: &mut Schedule,
        points: &[StartPoint],
    ) -> (&[Vec3], &[bool]) {
        let start = std::time::Instant::now();
        self.write_batch(&mut world.resource_mut::<ShadingBatch>(), points);
        self.stats.passes.camera += start.elapsed().as_secs_f64();
        let (depth, start) = self.job;
        let (materials, closed) = (&self.materials, Some(&self.closed));
        let job = PathJob { depth, materials, seed: self.seed, strategy: Strategy::Mis, start, closed };
        self.paths.trace(world, schedule, &mut self.columns, &job, &mut self.rgb, &mut self.stats);
        self.stats.camera_samples += points.len() as u64;
        (&self.rgb, self.paths.leaked())
    }

    /// Writes `points` into the batch and the columns as the camera pass writes hits: seen
    /// straight along the shading normal, on the white material.
    fn write_batch(&mut self, batch: &mut ShadingBatch, points: &[StartPoint]) {
        batch.set_len(points.len());
        batch.layout = None;
        self.columns.resize(points.len());
        let c = &mut self.columns;
        for (i, s) in points.iter().enumerate() {
            (batch.position[i], batch.position_error[i]) = (s.p, s.p_error);
            (batch.normal[i], batch.shading_normal[i]) = (s.ng, s.ns);
            (batch.pixel[i], batch.sample[i], batch.geometry[i]) = (s.pixel, s.sample, s.geometry);
            for a in 0..3 {
                c.dir[a][i] = -s.ns[a];
            }
            (c.uv[0][i], c.uv[1][i]) = Vec2::ZERO.into();
            c.material[i] = self.white;
            // Only the point's own emission reads the instance, and a texel shows none.
            c.instance[i] = self.instance_of.get(&s.geometry.entity_index).copied().unwrap_or(0);
            c.flipped[i] = false;
        }
    }
}
