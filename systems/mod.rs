//! What happens each update: bevy_ecs systems that turn the world into flat tables and batched
//! work, and the plugin that schedules them.
//!
//! The chain, set by set (each set's doc says what holds after it):
//! update the scene BVH -> build env-map tables -> sync lights -> update the light sampler ->
//! sample lights for the shading batch -> trace shadow rays -> write direct lighting.

#[cfg(feature = "bevy")]
mod bevy_plugin;
mod env_tables;
mod geometry;
mod plan;
mod sample;
mod shadows;
mod sync_lights;

use bevy_ecs::prelude::*;

use crate::geometry::{Disk, Mesh, Placement, Rectangle, Sphere, Transform};
use crate::light::{
    AreaLight, DistantLight, GoniometricLight, ImageInfiniteLight, LightTable, PointLight, ProjectionLight, SpotLight,
};
use crate::light_sampler::LightSampler;
use crate::shading::{DirectLighting, RunReport, SceneBounds, Settings, ShadingBatch};

pub use env_tables::{EnvTables, build_env_tables, plan_env_tables};
pub use geometry::{BvhWork, GeometryIndex, plan_bvh, update_scene_bvh};
pub use plan::Work;
pub use sample::{MAX_NEIGHBOURS, Reservoirs, ShadowRays, ShadowTarget, sample_direct_lighting};
pub use sync_lights::{
    remove_lights, sync_area_lights, sync_distant_lights, sync_goniometric_lights, sync_image_infinite_lights,
    sync_point_lights, sync_projection_lights, sync_spot_lights, sync_sun_sky_lights, sync_uniform_infinite_lights,
};

/// The light system's sets, in order.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum LightingSet {
    /// After this set, the `SceneBvh` and `SceneBounds` match the geometry entities.
    UpdateBvh,
    /// After this set, every image infinite light has sampling tables for its current image.
    BuildEnvTables,
    /// After this set, every added, changed or removed light is reflected in the `LightTable`.
    SyncLights,
    /// After this set, the light sampler matches the `LightTable`.
    UpdateSampler,
    /// After this set, `DirectLighting` holds one light sample per point (or per point and light),
    /// its shadow ray traced (occluded entries zeroed), ready to read.
    SampleLights,
}

/// Adds kelvin's resources to a `World` and its systems to a `Schedule`: the one entry an app
/// needs to embed the light system. Without bevy_app, call [`LightingPlugin::build`]; with the
/// `bevy` feature it is also a `bevy_app::Plugin` (`app.add_plugins(LightingPlugin::default())`).
#[derive(Clone, Debug)]
#[cfg_attr(not(feature = "bevy"), derive(Default))]
pub struct LightingPlugin {
    /// The schedule the systems run in (with the `bevy` feature). Defaults to `PostUpdate`,
    /// where they run after Bevy's transform propagation.
    #[cfg(feature = "bevy")]
    pub schedule: bevy_ecs::schedule::InternedScheduleLabel,
}

impl LightingPlugin {
    /// Inserts the resources (keeping any the app already inserted, such as `Settings`), makes the
    /// light and geometry components require kelvin's [`Transform`], and adds the systems and
    /// their order to `schedule`. Lights and geometry are placed by their `Transform`.
    ///
    /// Call it before spawning lights: a component's requirements can only be registered before
    /// the first entity holding it exists.
    pub fn build(world: &mut World, schedule: &mut Schedule) {
        init_resources(world);
        require_placement::<Transform>(world);
        add_systems::<Transform>(schedule);
    }
}

/// The resources the systems read and write, keeping any the app inserted first.
fn init_resources(world: &mut World) {
    world.init_resource::<Settings>();
    world.init_resource::<LightTable>();
    world.init_resource::<LightSampler>();
    world.init_resource::<ShadingBatch>();
    world.init_resource::<DirectLighting>();
    world.init_resource::<ShadowRays>();
    world.init_resource::<Reservoirs>();
    world.init_resource::<RunReport>();
    world.init_resource::<Work>();
    world.init_resource::<SceneBounds>();
    world.init_resource::<crate::geometry::SceneBvh>();
    world.init_resource::<GeometryIndex>();
    world.init_resource::<EnvTables>();
}

/// Makes every light and geometry component that is placed in the world require `T`, so an
/// entity spawned without a transform sits at the origin instead of being ignored. A requirement
/// already registered (the plugin built twice) or too late (the component already spawned) is
/// left as it is.
fn require_placement<T: Component + Default>(world: &mut World) {
    fn require<C: Component, T: Component + Default>(world: &mut World) {
        let _ = world.try_register_required_components::<C, T>();
    }
    require::<PointLight, T>(world);
    require::<SpotLight, T>(world);
    require::<DistantLight, T>(world);
    require::<ProjectionLight, T>(world);
    require::<GoniometricLight, T>(world);
    require::<AreaLight, T>(world);
    require::<ImageInfiniteLight, T>(world);
    require::<Mesh, T>(world);
    require::<Sphere, T>(world);
    require::<Disk, T>(world);
    require::<Rectangle, T>(world);
}

/// The systems and their order, with lights and geometry placed by `P`.
fn add_systems<P: Placement>(schedule: &mut Schedule) {
    schedule.configure_sets(
        (
            LightingSet::UpdateBvh,
            // Independent of geometry; image lights need their tables before they are synced.
            LightingSet::BuildEnvTables,
            // Distant and infinite lights read the scene bounds the BVH step computes.
            LightingSet::SyncLights,
            // The sampler weighs lights by power, so it reads the synced table.
            LightingSet::UpdateSampler,
            // Light selection uses the updated sampler.
            LightingSet::SampleLights,
        )
            .chain(),
    );
    schedule.add_systems(
        (plan::begin_update, plan_bvh::<P>, update_scene_bvh::<P>.run_if(plan::planned(|w| w.bvh != BvhWork::None)))
            .chain()
            .in_set(LightingSet::UpdateBvh),
    );
    schedule.add_systems(
        (
            // Removals first: an entity whose light changed kind is removed, then re-added.
            remove_lights,
            (
                sync_point_lights::<P>,
                sync_spot_lights::<P>,
                sync_distant_lights::<P>,
                sync_area_lights::<P>,
                sync_projection_lights::<P>,
                sync_goniometric_lights::<P>,
                sync_uniform_infinite_lights,
                sync_image_infinite_lights::<P>,
                sync_sun_sky_lights,
            ),
        )
            .chain()
            .in_set(LightingSet::SyncLights),
    );
    schedule.add_systems(
        (plan_env_tables, build_env_tables.run_if(plan::planned(|w| w.env_tables)))
            .chain()
            .in_set(LightingSet::BuildEnvTables),
    );
    schedule.add_systems(
        (plan::plan_sampler, sample::update_light_sampler.run_if(plan::planned(|w| w.sampler)))
            .chain()
            .in_set(LightingSet::UpdateSampler),
    );
    schedule.add_systems(
        (plan::plan_sampling, sample_direct_lighting.run_if(plan::planned(|w| w.sampling)))
            .chain()
            .in_set(LightingSet::SampleLights),
    );
}
