//! The report's scenes: how each is built, which knobs apply to it and in which colour mode its
//! baseline renders.

use std::path::Path;
use std::sync::Arc;

use bevy_ecs::prelude::*;

use super::AccuracyError;
use super::knobs::Knob;
use crate::light::LightTable;
use crate::scenes::color_checker::{ColorChecker, spawn_color_checker};
use crate::shading::{ColorMode, Settings};
use crate::spectrum::Spectrum;
use crate::systems::LightingPlugin;

/// The environment map of the env scene, relative to the data folder, and the luminance of its
/// texel (1, 1, 1), nit.
pub const ENV_MAP: &str = "env/spiaggia_di_mondello_1k.hdr";
const ENV_NITS: f32 = 1000.0;
/// Lights in the many-lights scene.
pub const MANY_LIGHTS: usize = 256;

/// A scene of the report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneId {
    /// The embedded default scene (area, spot, blackbody point light and sky).
    Default,
    /// [`MANY_LIGHTS`] point and spot lights over a ground with occluders
    /// ([`crate::scenes::spawn_scaling_scene`]).
    ManyLights,
    /// Objects under a real sky with its sun ([`ENV_MAP`]).
    EnvSun,
    /// The colour checker under a 2700 K blackbody.
    CheckerBlackbody,
    /// The colour checker under CIE F11.
    CheckerF11,
}

impl SceneId {
    /// Every scene, in report order.
    pub const ALL: [SceneId; 5] =
        [SceneId::Default, SceneId::ManyLights, SceneId::EnvSun, SceneId::CheckerBlackbody, SceneId::CheckerF11];

    /// The name used on the command line and in file names.
    pub fn name(self) -> &'static str {
        match self {
            SceneId::Default => "default",
            SceneId::ManyLights => "many-lights",
            SceneId::EnvSun => "env-sun",
            SceneId::CheckerBlackbody => "checker-2700k",
            SceneId::CheckerF11 => "checker-f11",
        }
    }

    /// The scene called `name`.
    pub fn parse(name: &str) -> Result<Self, AccuracyError> {
        Self::ALL.into_iter().find(|s| s.name() == name).ok_or_else(|| AccuracyError::UnknownScene {
            given: name.to_string(),
            accepted: Self::ALL.map(|s| s.name()).join(", "),
        })
    }

    /// The knobs that change something in this scene (no env table without an env map, no light
    /// sampler with one light, no strategy with only delta lights, no f64 without point or spot
    /// lights).
    pub fn knobs(self) -> Vec<Knob> {
        use Knob::*;
        match self {
            SceneId::Default => {
                vec![Spp, LightSampler, Color, Strategy, Selection, ShadowOffset, Precision, Depth, Roulette]
            }
            SceneId::ManyLights => vec![Spp, LightSampler, Color, Selection, ShadowOffset, Precision],
            SceneId::EnvSun => vec![Spp, Color, EnvTable, Strategy, ShadowOffset],
            SceneId::CheckerBlackbody | SceneId::CheckerF11 => vec![Spp, Color],
        }
    }

    /// The colour mode of the baseline and of the main reference: spectral for the colour
    /// checkers (their point is colour), RGB elsewhere (kelvin's default).
    pub fn baseline_color(self) -> ColorMode {
        match self {
            SceneId::CheckerBlackbody | SceneId::CheckerF11 => ColorMode::Spectral,
            _ => ColorMode::Rgb,
        }
    }

    /// A description of everything the scene depends on, for the reference cache key.
    pub fn describe(self) -> String {
        match self {
            SceneId::ManyLights => format!("scaling-scene n={MANY_LIGHTS} seed=1 v2"),
            SceneId::EnvSun => format!("env-sun {ENV_MAP} nits={ENV_NITS} v1"),
            s => format!("{} v1", s.name()),
        }
    }
}

/// A scene ready to render.
pub struct BuiltScene {
    /// Which scene this is.
    pub id: SceneId,
    /// The scene's entities and the light system's resources, updated once.
    pub world: World,
    /// The light system's systems, as [`LightingPlugin::build`] adds them.
    pub schedule: Schedule,
    /// The patches, for the colour-checker scenes.
    pub checker: Option<ColorChecker>,
    /// Number of lights in the light table.
    pub n_lights: usize,
}

/// Builds scene `id`; None (with the reason) when its data is missing under `data_dir`.
pub fn build(id: SceneId, data_dir: &Path) -> Result<Result<BuiltScene, String>, AccuracyError> {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings::default());
    LightingPlugin::build(&mut world, &mut schedule);
    let mut checker = None;
    match id {
        SceneId::Default => crate::scenes::default_scene::spawn_default_scene(&mut world),
        SceneId::ManyLights => {
            // The many-lights benchmark scene, seen from above at an angle.
            let s = crate::scenes::spawn_scaling_scene(&mut world, MANY_LIGHTS, 1);
            let eye = glam::Vec3::new(0.0, 0.9, 1.3) * s.half_extent;
            let target = glam::Vec3::new(0.0, 0.0, -0.1 * s.half_extent);
            let camera = crate::render::camera::Camera { yfov: 50f32.to_radians() };
            world.spawn((
                camera,
                crate::geometry::Transform::from_translation(eye).looking_to(target - eye, glam::Vec3::Y),
            ));
        }
        SceneId::EnvSun => {
            let path = data_dir.join(ENV_MAP);
            if !path.exists() {
                return Ok(Err(format!("{} not found", path.display())));
            }
            let loaded = crate::scene::image::load_image(&path)?;
            crate::scenes::sunlit_objects::spawn_sunlit_objects(&mut world, Arc::new(loaded.image), ENV_NITS);
        }
        SceneId::CheckerBlackbody => {
            let s = Spectrum::blackbody(2700.0).expect("valid temperature");
            checker = Some(spawn_color_checker(&mut world, s));
        }
        SceneId::CheckerF11 => {
            let s = Spectrum::illuminant("F11").expect("F11 is compiled in");
            checker = Some(spawn_color_checker(&mut world, s));
        }
    }
    schedule.run(&mut world);
    let n_lights = world.resource::<LightTable>().len();
    Ok(Ok(BuiltScene { id, world, schedule, checker, n_lights }))
}
