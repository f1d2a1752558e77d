//! `kelvin.Scene`: a loaded scene (glTF file or the default scene, with its environment map and sun
//! and sky) that renders many times, under many settings, and poses its animations between renders.
//! `kelvin.render` is a `Scene` loaded for one render.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

use bevy_ecs::prelude::*;
use glam::{Affine3A, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::{DistantLight, GoniometricLight, PointLight, SpotLight, SunSkyLight};
use kelvin::render::camera::Camera;
use kelvin::render::job::{IntegratorChoice, JobError, LoadedJob, RenderJob};
use kelvin::render::tiles::Crop;
use kelvin::rng::Pattern;
use kelvin::scene::animate::{GltfAnimations, GltfNode, pose_gltf};
use kelvin::scene::gltf::LightKind;
use numpy::PyArray1;
use pyo3::exceptions::{PyKeyError, PyKeyboardInterrupt, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::{choice, color_mode, interruptible, pool, sampler, vec3};

/// A job error as the Python exception a caller expects: bad options are `ValueError`, files that
/// do not load `OSError` (the message names the file, and for glTF the JSON pointer).
fn job_error(e: JobError) -> PyErr {
    match e {
        JobError::Invalid(msg) => PyValueError::new_err(msg),
        other => PyOSError::new_err(other.to_string()),
    }
}

/// A loaded scene: its world and schedule, and the job that loaded it (scene file, environment
/// map, sun and sky), whose other options each render sets.
#[pyclass(module = "kelvin._kelvin", unsendable)]
pub struct Scene {
    base: RenderJob,
    loaded: LoadedJob,
}

/// Where a node's entity of one component type is now: glTF node index to its `Transform`.
fn placed<C: Component>(world: &mut World, file: Option<usize>) -> Vec<(usize, Transform)> {
    let mut query = world.query_filtered::<(&GltfNode, &Transform), With<C>>();
    query.iter(world).filter(|(n, _)| Some(n.file) == file).map(|(n, t)| (n.node, *t)).collect()
}

/// The pose of node `node` from `placed`, or the file's rest pose.
fn pose_of(placed: &[(usize, Transform)], node: Option<usize>, rest: Affine3A) -> Transform {
    node.and_then(|n| placed.iter().find(|(m, _)| *m == n)).map_or(Transform::from_affine(rest), |(_, t)| *t)
}

fn tuple(v: Vec3) -> (f32, f32, f32) {
    (v.x, v.y, v.z)
}

#[pymethods]
impl Scene {
    /// Loads `scene` (None: the default scene) with an environment map and a sun and sky, as
    /// `kelvin render` does; returns the scene and the loaders' warnings.
    #[staticmethod]
    #[pyo3(signature = (scene, env, env_intensity, sky, sky_intensity))]
    fn load(
        py: Python<'_>,
        scene: Option<PathBuf>,
        env: Option<PathBuf>,
        env_intensity: f32,
        sky: Option<String>,
        sky_intensity: f32,
    ) -> PyResult<(Scene, Vec<String>)> {
        let base = RenderJob { scene, env, env_intensity, sky, sky_intensity, ..RenderJob::default() };
        let mut loaded = py.detach(|| base.load()).map_err(job_error)?;
        let warnings = std::mem::take(&mut loaded.warnings);
        Ok((Scene { base, loaded }, warnings))
    }

    /// Renders with every option of `kelvin render` but the scene's own; returns the linear image
    /// (flat, rows top to bottom), its width and height, the warnings and the statistics.
    #[pyo3(signature = (size, spp, time, integrator, max_depth, roulette_depth, light_sampler, candidates,
        neighbours, radius, biased_reuse, color, all_lights, mis, seed, pattern, threads, environment_at, crop))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        size: (u32, u32),
        spp: u32,
        time: Option<f64>,
        integrator: &str,
        max_depth: u32,
        roulette_depth: u32,
        light_sampler: &str,
        candidates: Option<u32>,
        neighbours: Option<u32>,
        radius: Option<u32>,
        biased_reuse: bool,
        color: &str,
        all_lights: bool,
        mis: bool,
        seed: u64,
        pattern: &str,
        threads: Option<usize>,
        environment_at: Option<[f32; 3]>,
        crop: Option<(u32, u32, u32, u32)>,
    ) -> PyResult<(Bound<'py, PyArray1<f32>>, u32, u32, Vec<String>, Bound<'py, PyDict>)> {
        let integrator = choice(
            "integrator",
            integrator,
            &[("path", IntegratorChoice::Path), ("direct", IntegratorChoice::Direct)],
        )?;
        let job = RenderJob {
            width: size.0,
            height: size.1,
            spp,
            time,
            integrator,
            depth: kelvin::render::path::PathDepth { max_depth, roulette_depth },
            light_sampler: sampler(light_sampler)?,
            candidates,
            neighbours,
            radius,
            biased_reuse,
            color: color_mode(color)?,
            all_lights,
            mis,
            seed,
            pattern: choice("pattern", pattern, &[("sobol", Pattern::Sobol), ("independent", Pattern::Independent)])?,
            environment_at: vec3("environment_at", environment_at)?,
            crop: crop.map(|(x0, y0, x1, y1)| Crop { x0, y0, x1, y1 }),
            ..self.base.clone()
        };
        job.check().map_err(job_error)?;
        let pool = pool(threads)?;
        let stop = AtomicBool::new(false);
        let loaded = &mut self.loaded;
        // The settings of this render replace the last one's; the light system rebuilds what they change.
        loaded.world.insert_resource(job.settings());
        let (film, stats) = interruptible(py, &stop, || {
            let mut run = || loaded.render(&job, |_| {}, &stop);
            match &pool {
                Some(pool) => pool.install(run),
                None => run(),
            }
        })?;
        if stats.stopped {
            return Err(PyKeyboardInterrupt::new_err("kelvin: render stopped"));
        }
        let (width, height) = (film.width, film.height);
        let flat: Vec<f32> = film.pixels().iter().flat_map(|p| p.to_array()).collect();
        let info = PyDict::new(py);
        info.set_item("seconds", stats.seconds)?;
        info.set_item("spp", stats.spp)?;
        info.set_item("camera_samples", stats.camera_samples)?;
        info.set_item("shadow_rays", stats.shadow_rays)?;
        info.set_item("bsdf_rays", stats.bsdf_rays)?;
        Ok((PyArray1::from_vec(py, flat), width, height, stats.report.warnings, info))
    }

    /// Poses animation `animation` (a name or an index) at `t` seconds: every node it moves takes
    /// its transform at `t`, and the next render shows it. Returns the counts of what moved.
    fn pose<'py>(&mut self, py: Python<'py>, animation: &Bound<'py, PyAny>, t: f32) -> PyResult<Bound<'py, PyDict>> {
        if !t.is_finite() {
            return Err(PyValueError::new_err(format!("t = {t}: not finite")));
        }
        let name: String = match animation.extract::<usize>() {
            Ok(i) => i.to_string(),
            Err(_) => animation.extract().map_err(|_| PyValueError::new_err("animation: a name or an index"))?,
        };
        let world = &mut self.loaded.world;
        let files = world.get_resource::<GltfAnimations>().map_or(&[][..], |a| &a.files);
        let Some(clips) = self.loaded.file.and_then(|f| files.get(f)).filter(|a| !a.clips.is_empty()) else {
            return Err(PyKeyError::new_err(format!("animation {name}: this scene has no animation")));
        };
        let Some(clip) = clips.find(&name) else {
            let names: Vec<String> = clips
                .clips
                .iter()
                .enumerate()
                .map(|(i, c)| format!("{i}: {}", c.name.as_deref().unwrap_or("-")))
                .collect();
            return Err(PyKeyError::new_err(format!(
                "animation {name}: not in the scene (it has {})",
                names.join(", ")
            )));
        };
        let file = self.loaded.file.unwrap_or_default();
        let posed = pose_gltf(world, file, clip, t).map_err(PyValueError::new_err)?;
        let report = PyDict::new(py);
        report.set_item("moved", posed.moved)?;
        report.set_item("unchanged", posed.unchanged)?;
        report.set_item("frozen", posed.frozen)?;
        Ok(report)
    }

    /// The scene's lights, each a dict: the file's punctual lights (name, node, kind, colour,
    /// intensity in glTF units, where they are now), then the environment map and the sun and sky
    /// (the job's, or the file's `KELVIN_sun_sky`).
    fn lights<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let file = self.loaded.file;
        let world = &mut self.loaded.world;
        let mut placed_all = placed::<PointLight>(world, file);
        placed_all.extend(placed::<SpotLight>(world, file));
        placed_all.extend(placed::<DistantLight>(world, file));
        placed_all.extend(placed::<GoniometricLight>(world, file));
        let list = PyList::empty(py);
        for light in &self.loaded.lights {
            let d = PyDict::new(py);
            let kind = match light.kind {
                LightKind::Point => "point",
                LightKind::Spot { inner_cone_angle, outer_cone_angle } => {
                    d.set_item("inner_cone_angle", inner_cone_angle.to_degrees())?;
                    d.set_item("outer_cone_angle", outer_cone_angle.to_degrees())?;
                    "spot"
                }
                LightKind::Directional => "directional",
                LightKind::Ies => "ies",
            };
            let now = pose_of(&placed_all, light.node, light.world);
            d.set_item("kind", kind)?;
            d.set_item("name", light.name.clone())?;
            d.set_item("node", light.node)?;
            d.set_item("node_name", light.node_name.clone())?;
            d.set_item("color", tuple(light.color))?;
            d.set_item("intensity", light.intensity)?;
            d.set_item("range", light.range)?;
            d.set_item("position", tuple(now.translation))?;
            d.set_item("direction", tuple(now.forward()))?;
            list.append(d)?;
        }
        if let Some(env) = &self.base.env {
            let d = PyDict::new(py);
            d.set_item("kind", "environment")?;
            d.set_item("path", env)?;
            d.set_item("intensity", self.base.env_intensity)?;
            list.append(d)?;
        }
        let mut skies = self.loaded.world.query::<&SunSkyLight>();
        for sky in skies.iter(&self.loaded.world) {
            let d = PyDict::new(py);
            d.set_item("kind", "sun_sky")?;
            d.set_item("direction", sky.sun_direction().ok().map(tuple))?;
            d.set_item("turbidity", sky.turbidity)?;
            d.set_item("intensity", sky.scale)?;
            d.set_item("below_horizon", sky.dark_reason().ok().flatten().is_some())?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// The file's cameras, each a dict (name, node, field of view in degrees, clip planes, where it
    /// is now); renders look through the first.
    fn cameras<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let placed = placed::<Camera>(&mut self.loaded.world, self.loaded.file);
        let list = PyList::empty(py);
        for camera in &self.loaded.cameras {
            let now = pose_of(&placed, camera.node, camera.world);
            let d = PyDict::new(py);
            d.set_item("name", camera.name.clone())?;
            d.set_item("node", camera.node)?;
            d.set_item("yfov", camera.yfov.to_degrees())?;
            d.set_item("aspect", camera.aspect)?;
            d.set_item("znear", camera.znear)?;
            d.set_item("zfar", camera.zfar)?;
            d.set_item("position", tuple(now.translation))?;
            d.set_item("direction", tuple(now.forward()))?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// The file's animations, each a dict: index, name, duration (s) and channel count.
    fn animations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let files = self.loaded.world.get_resource::<GltfAnimations>().map_or(&[][..], |a| &a.files);
        let list = PyList::empty(py);
        for (index, clip) in
            self.loaded.file.and_then(|f| files.get(f)).map_or(&[][..], |a| &a.clips).iter().enumerate()
        {
            let d = PyDict::new(py);
            d.set_item("index", index)?;
            d.set_item("name", clip.name.clone())?;
            d.set_item("duration", clip.duration())?;
            d.set_item("channels", clip.channels.len())?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// The one-line summary of the loaded file, as `kelvin render` prints it.
    fn summary(&self) -> Option<String> {
        self.loaded.summary.clone()
    }
}
