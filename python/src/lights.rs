//! `kelvin.LightSystem`: a world with the light system's schedule, lights added and moved by id,
//! occluding geometry, and batches of points whose direct light comes back as NumPy columns.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use kelvin::geometry::{Mesh, Rectangle, Transform};
use kelvin::light::{Amount, AreaLight, DistantLight, GoniometricLight, PointLight, SpotLight};
use kelvin::rng::SampleStream;
use kelvin::shading::{ColorMode, DirectLighting, LightSamplerKind, LightSelection, Settings, ShadingBatch};
use kelvin::spectrum::color::xyz_to_srgb;
use kelvin::spectrum::{SampledSpectrum, SampledWavelengths, Spectrum};
use kelvin::systems::LightingPlugin;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::{PyKeyError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Lights, geometry and the schedule that samples them (see the Python docstrings).
#[pyclass(module = "kelvin._kelvin", unsendable)]
pub struct LightSystem {
    world: World,
    schedule: Schedule,
    /// The first sample index of the next run: each run draws new samples, so the mean of runs converges.
    next_sample: u32,
}

/// Light samples per point per run.
pub(crate) const SPP: std::ops::RangeInclusive<u32> = 1..=1 << 16;

/// Salt of the wavelengths' streams, apart from the light samples' (same seed, pixel and sample).
const WAVELENGTH_SALT: u64 = 0x7a5e_1e9f_3c0d_b00c;

/// A value of the run's colour mode as photometric linear sRGB (spectral: through XYZ at its wavelengths).
fn to_rgb(v: SampledSpectrum, wavelengths: Option<&SampledWavelengths>) -> [f32; 3] {
    match wavelengths {
        None => [v.0[0], v.0[1], v.0[2]],
        Some(w) => xyz_to_srgb(w.to_xyz(v).as_dvec3()).as_vec3().to_array(),
    }
}

/// An emitter's spectrum: a blackbody temperature (K), or a linear-sRGB colour ((1, 1, 1) is D65).
fn spectrum(color: Option<[f64; 3]>, temperature: Option<f64>) -> PyResult<Spectrum> {
    match (color, temperature) {
        (Some(_), Some(_)) => Err(PyValueError::new_err("give color or temperature, not both")),
        (None, Some(t)) => Spectrum::blackbody(t).map_err(|e| PyValueError::new_err(e.to_string())),
        (Some(rgb), None) if rgb.iter().all(|c| c.is_finite() && *c >= 0.0) => Ok(Spectrum::Rgb { rgb }),
        (Some(rgb), None) => Err(PyValueError::new_err(format!("color = {rgb:?}: components must be finite and >= 0"))),
        (None, None) => Ok(Spectrum::d65()),
    }
}

/// The one photometric amount given among `options` (name, value, unit).
fn amount(options: &[(&str, Option<f32>, fn(f32) -> Amount)], default: Amount) -> PyResult<Amount> {
    let given: Vec<_> = options.iter().filter(|o| o.1.is_some()).collect();
    match given[..] {
        [] => Ok(default),
        [(name, Some(v), unit)] if v.is_finite() && *v >= 0.0 => Ok(unit(*v)),
        [(name, Some(v), _)] => Err(PyValueError::new_err(format!("{name} = {v}: must be finite and >= 0"))),
        _ => {
            let names: Vec<&str> = given.iter().map(|o| o.0).collect();
            Err(PyValueError::new_err(format!("give one amount, not {}", names.join(" and "))))
        }
    }
}

fn finite(what: &str, v: [f32; 3]) -> PyResult<Vec3> {
    let v = Vec3::from(v);
    if v.is_finite() { Ok(v) } else { Err(PyValueError::new_err(format!("{what} = {v}: not finite"))) }
}

fn direction(what: &str, v: [f32; 3]) -> PyResult<Vec3> {
    let d = finite(what, v)?;
    if d.length_squared() > 0.0 { Ok(d) } else { Err(PyValueError::new_err(format!("{what} is the zero vector"))) }
}

fn placed(position: [f32; 3], facing: Option<[f32; 3]>) -> PyResult<Transform> {
    let t = Transform::from_translation(finite("position", position)?);
    Ok(match facing {
        Some(d) => t.looking_to(direction("direction", d)?, Vec3::Y),
        None => t,
    })
}

/// Points and normals from flat float32 columns of equal length (3 per point).
fn points_and_normals(
    points: &PyReadonlyArray1<'_, f32>,
    normals: &PyReadonlyArray1<'_, f32>,
) -> PyResult<Vec<(Vec3, Vec3)>> {
    let (p, n) = (points.as_slice()?, normals.as_slice()?);
    if p.len() != n.len() || p.len() % 3 != 0 {
        return Err(PyValueError::new_err(format!(
            "points ({}) and normals ({}) must both be N x 3",
            p.len() / 3,
            n.len() / 3
        )));
    }
    let pairs: Vec<(Vec3, Vec3)> =
        p.chunks_exact(3).zip(n.chunks_exact(3)).map(|(p, n)| (Vec3::from_slice(p), Vec3::from_slice(n))).collect();
    if let Some(i) = pairs.iter().position(|(p, n)| !p.is_finite() || !n.is_finite() || n.length_squared() == 0.0) {
        let (p, n) = pairs[i];
        return Err(PyValueError::new_err(format!(
            "point {i}: position {p} and normal {n} must be finite, the normal non-zero"
        )));
    }
    Ok(pairs.into_iter().map(|(p, n)| (p, n.normalize())).collect())
}

impl LightSystem {
    fn spawn(&mut self, bundle: impl Bundle) -> u64 {
        self.world.spawn(bundle).id().to_bits()
    }

    fn entity(&self, id: u64) -> PyResult<Entity> {
        Entity::try_from_bits(id)
            .filter(|&e| self.world.get_entity(e).is_ok())
            .ok_or_else(|| PyKeyError::new_err(format!("no light or geometry with id {id}")))
    }

    /// Runs the schedule on `spp` slots per point (slot `i * spp + s` is sample `s` of point `i`),
    /// one light sample each, without the GIL on `threads` workers. Each slot is its own sample
    /// index, so that in spectral mode it has its own wavelengths; the run's indices follow the
    /// last run's, so runs draw new samples.
    fn run(&mut self, py: Python<'_>, points: &[(Vec3, Vec3)], spp: u32, threads: Option<usize>) -> PyResult<()> {
        if !SPP.contains(&spp) {
            return Err(PyValueError::new_err(format!("spp = {spp} is outside {}..={}", SPP.start(), SPP.end())));
        }
        // Entry offsets are u32.
        if points.len() as u64 * spp as u64 > u32::MAX as u64 / 2 {
            return Err(PyValueError::new_err(format!(
                "{} points x spp = {spp}: too many samples for one run",
                points.len()
            )));
        }
        let pool = super::pool(threads)?;
        // Sample indices are u32: past 2^32 samples of a point the streams would repeat.
        let first = self.next_sample;
        self.next_sample = first.checked_add(spp).ok_or_else(|| {
            PyValueError::new_err(format!(
                "spp = {spp}: this LightSystem has drawn {first} samples per point, and its sample streams end at 2^32"
            ))
        })?;
        let mut settings = self.world.resource_mut::<Settings>();
        settings.samples_per_point = 1;
        let (spectral, pattern, seed) = (settings.color_mode == ColorMode::Spectral, settings.pattern, settings.seed);
        {
            let mut batch = self.world.resource_mut::<ShadingBatch>();
            batch.clear();
            for (i, &(p, n)) in points.iter().enumerate() {
                for sample in first..first + spp {
                    batch.push(p, n, i as u32, sample);
                    if spectral {
                        let u = SampleStream::new(pattern, seed ^ WAVELENGTH_SALT, i as u32, sample).next_f32();
                        batch.wavelengths.push(SampledWavelengths::sample_visible(u));
                    }
                }
            }
        }
        let (world, schedule) = (&mut self.world, &mut self.schedule);
        super::interruptible(py, &AtomicBool::new(false), || match &pool {
            Some(pool) => pool.install(|| schedule.run(world)),
            None => schedule.run(world),
        })
    }

    /// The last run's lighting and its slots' wavelengths (empty in RGB mode).
    fn output(&self) -> (&DirectLighting, &[SampledWavelengths]) {
        (self.world.resource::<DirectLighting>(), &self.world.resource::<ShadingBatch>().wavelengths)
    }
}

#[pymethods]
impl LightSystem {
    #[new]
    #[pyo3(signature = (sampler="bvh", color="rgb", seed=0, all_lights=false))]
    fn new(sampler: &str, color: &str, seed: u64, all_lights: bool) -> PyResult<Self> {
        let light_sampler = match super::sampler(sampler)? {
            kelvin::render::job::SamplerChoice::Uniform => LightSamplerKind::Uniform,
            kelvin::render::job::SamplerChoice::Power => LightSamplerKind::Power,
            kelvin::render::job::SamplerChoice::Bvh => LightSamplerKind::Bvh,
            _ => return Err(PyValueError::new_err(format!("sampler = {sampler:?}: expected uniform, power or bvh"))),
        };
        let selection = if all_lights { LightSelection::All } else { LightSelection::OneSampled };
        let mut world = World::new();
        let mut schedule = Schedule::default();
        world.insert_resource(Settings {
            light_sampler,
            selection,
            color_mode: super::color_mode(color)?,
            seed,
            ..Default::default()
        });
        LightingPlugin::build(&mut world, &mut schedule);
        Ok(Self { world, schedule, next_sample: 0 })
    }

    #[pyo3(signature = (position, candela=None, lumens=None, watts=None, color=None, temperature=None, radius=0.0))]
    #[allow(clippy::too_many_arguments)]
    fn add_point(
        &mut self,
        position: [f32; 3],
        candela: Option<f32>,
        lumens: Option<f32>,
        watts: Option<f32>,
        color: Option<[f64; 3]>,
        temperature: Option<f64>,
        radius: f32,
    ) -> PyResult<u64> {
        let amount = amount(
            &[
                ("candela", candela, Amount::Candela),
                ("lumens", lumens, Amount::Lumens),
                ("watts", watts, Amount::Watts),
            ],
            PointLight::default().amount,
        )?;
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(PyValueError::new_err(format!("radius = {radius}: must be finite and >= 0")));
        }
        let light = PointLight { amount, spectrum: spectrum(color, temperature)?, radius, ..Default::default() };
        Ok(self.spawn((light, placed(position, None)?)))
    }

    #[pyo3(signature = (position, direction, candela=None, lumens=None, inner_angle=0.0, outer_angle=45.0, color=None, temperature=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_spot(
        &mut self,
        position: [f32; 3],
        direction: [f32; 3],
        candela: Option<f32>,
        lumens: Option<f32>,
        inner_angle: f32,
        outer_angle: f32,
        color: Option<[f64; 3]>,
        temperature: Option<f64>,
    ) -> PyResult<u64> {
        let amount = amount(
            &[("candela", candela, Amount::Candela), ("lumens", lumens, Amount::Lumens)],
            SpotLight::default().amount,
        )?;
        if !(0.0 <= inner_angle && inner_angle <= outer_angle && outer_angle <= 180.0) {
            return Err(PyValueError::new_err(format!(
                "inner_angle = {inner_angle}, outer_angle = {outer_angle}: need 0 <= inner_angle <= outer_angle <= 180 degrees"
            )));
        }
        let light = SpotLight {
            amount,
            spectrum: spectrum(color, temperature)?,
            inner_angle: inner_angle.to_radians(),
            outer_angle: outer_angle.to_radians(),
            ..Default::default()
        };
        Ok(self.spawn((light, placed(position, Some(direction))?)))
    }

    #[pyo3(signature = (direction, lux=None, color=None, temperature=None, angular_diameter=0.0))]
    fn add_distant(
        &mut self,
        direction: [f32; 3],
        lux: Option<f32>,
        color: Option<[f64; 3]>,
        temperature: Option<f64>,
        angular_diameter: f32,
    ) -> PyResult<u64> {
        let amount = amount(&[("lux", lux, Amount::Lux)], DistantLight::default().amount)?;
        if !(0.0..180.0).contains(&angular_diameter) {
            return Err(PyValueError::new_err(format!(
                "angular_diameter = {angular_diameter}: expected [0, 180) degrees"
            )));
        }
        let light = DistantLight {
            amount,
            spectrum: spectrum(color, temperature)?,
            angular_diameter: angular_diameter.to_radians(),
            ..Default::default()
        };
        Ok(self.spawn((light, placed([0.0; 3], Some(direction))?)))
    }

    #[pyo3(signature = (center, normal, size, nits=None, lumens=None, color=None, temperature=None, two_sided=false))]
    #[allow(clippy::too_many_arguments)]
    fn add_area(
        &mut self,
        center: [f32; 3],
        normal: [f32; 3],
        size: (f32, f32),
        nits: Option<f32>,
        lumens: Option<f32>,
        color: Option<[f64; 3]>,
        temperature: Option<f64>,
        two_sided: bool,
    ) -> PyResult<u64> {
        let amount =
            amount(&[("nits", nits, Amount::Nits), ("lumens", lumens, Amount::Lumens)], AreaLight::default().amount)?;
        if !(size.0.is_finite() && size.1.is_finite() && size.0 > 0.0 && size.1 > 0.0) {
            return Err(PyValueError::new_err(format!("size = {size:?}: both sides must be finite and > 0")));
        }
        let light = AreaLight { amount, spectrum: spectrum(color, temperature)?, two_sided, ..Default::default() };
        // The rectangle emits along its local +Z; looking_to turns local -Z.
        let n = direction("normal", normal)?;
        let shape = Rectangle { half_size: Vec2::new(size.0, size.1) / 2.0 };
        Ok(self.spawn((light, shape, placed(center, Some((-n).to_array()))?)))
    }

    #[pyo3(signature = (path, position, direction=[0.0, -1.0, 0.0], lumens=None, multiplier=1.0, color=None, temperature=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_ies(
        &mut self,
        path: PathBuf,
        position: [f32; 3],
        direction: [f32; 3],
        lumens: Option<f32>,
        multiplier: f32,
        color: Option<[f64; 3]>,
        temperature: Option<f64>,
    ) -> PyResult<u64> {
        let profile =
            kelvin::scene::ies::IesProfile::from_file(&path).map_err(|e| PyOSError::new_err(e.to_string()))?;
        if !(multiplier.is_finite() && multiplier >= 0.0) {
            return Err(PyValueError::new_err(format!("multiplier = {multiplier}: must be finite and >= 0")));
        }
        let mut light = GoniometricLight::from_ies(Arc::new(profile));
        light.amount = amount(&[("lumens", lumens, Amount::Lumens)], Amount::Candela(multiplier))?;
        light.spectrum = spectrum(color, temperature)?;
        // The profile's nadir is local -Z: `direction` is where the fixture points.
        Ok(self.spawn((light, placed(position, Some(direction))?)))
    }

    /// Occluding triangles (world space): flat float32 vertices (3 per vertex) and uint32 indices (3 per triangle).
    fn add_mesh(&mut self, vertices: PyReadonlyArray1<'_, f32>, indices: PyReadonlyArray1<'_, u32>) -> PyResult<u64> {
        let positions: Vec<Vec3> = vertices.as_slice()?.chunks_exact(3).map(Vec3::from_slice).collect();
        let mesh =
            Mesh::new(positions, indices.as_slice()?.to_vec()).map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(self.spawn((mesh, Transform::IDENTITY)))
    }

    /// Spawns a glTF file's meshes, lights and cameras; returns the loader's warnings.
    fn load_gltf(&mut self, path: PathBuf) -> PyResult<Vec<String>> {
        let report = kelvin::render::scene_file::spawn_gltf_file(&mut self.world, &path)
            .map_err(|e| PyOSError::new_err(e.to_string()))?;
        Ok(report.warnings)
    }

    #[pyo3(signature = (id, position, direction=None))]
    fn move_to(&mut self, id: u64, position: [f32; 3], direction: Option<[f32; 3]>) -> PyResult<()> {
        let entity = self.entity(id)?;
        let mut t = placed(position, direction)?;
        let mut current = self
            .world
            .get_mut::<Transform>(entity)
            .ok_or_else(|| PyKeyError::new_err(format!("id {id} has no transform")))?;
        if direction.is_none() {
            t.rotation = current.rotation;
        }
        *current = t;
        Ok(())
    }

    fn remove(&mut self, id: u64) -> PyResult<()> {
        let entity = self.entity(id)?;
        self.world.despawn(entity);
        Ok(())
    }

    /// Irradiance (flat, 3 per point): the sum over each point's entries of Li cos / pdf.
    #[pyo3(signature = (points, normals, spp=64, threads=None))]
    fn irradiance<'py>(
        &mut self,
        py: Python<'py>,
        points: PyReadonlyArray1<'_, f32>,
        normals: PyReadonlyArray1<'_, f32>,
        spp: u32,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let pn = points_and_normals(&points, &normals)?;
        self.run(py, &pn, spp, threads)?;
        let (lighting, wavelengths) = self.output();
        let k = spp as usize;
        // A point's estimate is the mean of its slots' (each an estimate from one sample).
        let mut flat = vec![0.0f32; 3 * pn.len()];
        for (j, (_, n)) in pn.iter().flat_map(|pn| std::iter::repeat_n(pn, k)).enumerate() {
            let e = to_rgb(lighting.irradiance(j, *n), wavelengths.get(j));
            for (sum, c) in flat[3 * (j / k)..][..3].iter_mut().zip(e) {
                *sum += c;
            }
        }
        flat.iter_mut().for_each(|e| *e /= k as f32);
        Ok(PyArray1::from_vec(py, flat))
    }

    /// Every entry of the points' light samples as columns: point, radiance (3), wi (3), pdf, occluded, delta.
    #[pyo3(signature = (points, normals, spp=1, threads=None))]
    fn sample_li<'py>(
        &mut self,
        py: Python<'py>,
        points: PyReadonlyArray1<'_, f32>,
        normals: PyReadonlyArray1<'_, f32>,
        spp: u32,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let pn = points_and_normals(&points, &normals)?;
        self.run(py, &pn, spp, threads)?;
        let (lighting, wavelengths) = self.output();
        let k = spp as usize;
        let slots = 0..pn.len() * k;
        let point: Vec<u32> = slots.clone().flat_map(|j| lighting.entries(j).map(move |_| (j / k) as u32)).collect();
        let radiance: Vec<f32> = slots
            .flat_map(|j| lighting.entries(j).flat_map(move |e| to_rgb(lighting.radiance[e], wavelengths.get(j))))
            .collect();
        let wi: Vec<f32> = lighting.wi.iter().flat_map(|w| w.to_array()).collect();
        // A slot's pdf is one sample's: the point's k samples together have k times its density.
        let pdf: Vec<f32> = lighting.pdf.iter().map(|p| p * k as f32).collect();
        let columns = PyDict::new(py);
        columns.set_item("point", PyArray1::from_vec(py, point))?;
        columns.set_item("radiance", PyArray1::from_vec(py, radiance))?;
        columns.set_item("wi", PyArray1::from_vec(py, wi))?;
        columns.set_item("pdf", PyArray1::from_vec(py, pdf))?;
        columns.set_item("occluded", lighting.occluded.clone())?;
        columns.set_item("delta", lighting.delta.clone())?;
        Ok(columns)
    }

    /// The warnings of the light system's last run (lights it skipped and why).
    fn warnings(&self) -> Vec<String> {
        self.world.resource::<kelvin::shading::RunReport>().warnings.clone()
    }
}
