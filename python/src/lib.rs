//! `kelvin._kelvin`: the native half of the Python package. Python (`pysrc/kelvin/__init__.py`)
//! checks shapes and dtypes, turns warnings into Python warnings and documents the API; this side
//! maps keyword arguments onto kelvin's own types and runs the work without the GIL.

mod lights;

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use glam::Vec3;
use kelvin::render::job::{IntegratorChoice, JobError, RenderJob, SamplerChoice};
use kelvin::render::tiles::Crop;
use kelvin::shading::ColorMode;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A job error as the Python exception a caller expects: bad options are `ValueError`, files that
/// do not load `OSError` (the message names the file, and for glTF the JSON pointer).
fn job_error(e: JobError) -> PyErr {
    match e {
        JobError::Invalid(msg) => PyValueError::new_err(msg),
        other => PyOSError::new_err(other.to_string()),
    }
}

/// One of `accepted` (by name), for a keyword argument `what`.
fn choice<T: Copy>(what: &str, given: &str, accepted: &[(&str, T)]) -> PyResult<T> {
    accepted.iter().find(|(name, _)| *name == given).map(|(_, v)| *v).ok_or_else(|| {
        let names: Vec<&str> = accepted.iter().map(|(n, _)| *n).collect();
        PyValueError::new_err(format!("{what} = {given:?}: expected one of {}", names.join(", ")))
    })
}

pub(crate) fn color_mode(color: &str) -> PyResult<ColorMode> {
    choice("color", color, &[("rgb", ColorMode::Rgb), ("spectral", ColorMode::Spectral)])
}

pub(crate) fn sampler(name: &str) -> PyResult<SamplerChoice> {
    choice(
        "light_sampler",
        name,
        &[
            ("uniform", SamplerChoice::Uniform),
            ("power", SamplerChoice::Power),
            ("bvh", SamplerChoice::Bvh),
            ("ris", SamplerChoice::Ris),
            ("restir", SamplerChoice::Restir),
        ],
    )
}

/// A rayon pool of `threads` workers, or None for the global pool.
pub(crate) fn pool(threads: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    match threads {
        None => Ok(None),
        Some(0) | Some(1025..) => Err(PyValueError::new_err(format!("threads = {threads:?} is outside 1..=1024"))),
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .map(Some)
            .map_err(|e| PyOSError::new_err(format!("threads = {t}: {e}"))),
    }
}

/// Runs `work` on another thread without the GIL while this one watches for Ctrl-C: a signal sets
/// `stop` (which `work` polls) and its exception is raised once `work` has returned.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    stop: &AtomicBool,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    std::thread::scope(|scope| {
        let handle = scope.spawn(work);
        let mut interrupted = None;
        while !handle.is_finished() {
            py.detach(|| std::thread::sleep(Duration::from_millis(10)));
            if interrupted.is_none()
                && let Err(e) = py.check_signals()
            {
                stop.store(true, Ordering::Relaxed);
                interrupted = Some(e);
            }
        }
        let value = handle.join().map_err(|_| PyOSError::new_err("kelvin: the render thread panicked"))?;
        interrupted.map_or(Ok(value), Err)
    })
}

fn vec3(what: &str, v: Option<[f32; 3]>) -> PyResult<Option<Vec3>> {
    match v.map(Vec3::from) {
        Some(p) if !p.is_finite() => Err(PyValueError::new_err(format!("{what} = {p}: not finite"))),
        p => Ok(p),
    }
}

/// Renders as `kelvin render` does with the same options; returns the linear photometric image
/// (flat, rows top to bottom), its width and height, the loader's warnings and a few statistics.
#[pyfunction]
#[pyo3(signature = (scene, size, spp, time, env, env_intensity, sky, sky_intensity, integrator, max_depth,
    roulette_depth, light_sampler, candidates, neighbours, radius, biased_reuse, color, all_lights, mis, seed,
    threads, environment_at, crop))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: Option<PathBuf>,
    size: (u32, u32),
    spp: u32,
    time: Option<f64>,
    env: Option<PathBuf>,
    env_intensity: f32,
    sky: Option<String>,
    sky_intensity: f32,
    integrator: &str,
    max_depth: u32,
    roulette_depth: u32,
    light_sampler: &str,
    candidates: u32,
    neighbours: u32,
    radius: u32,
    biased_reuse: bool,
    color: &str,
    all_lights: bool,
    mis: bool,
    seed: u64,
    threads: Option<usize>,
    environment_at: Option<[f32; 3]>,
    crop: Option<(u32, u32, u32, u32)>,
) -> PyResult<(Bound<'py, PyArray1<f32>>, u32, u32, Vec<String>, Bound<'py, PyDict>)> {
    let integrator =
        choice("integrator", integrator, &[("path", IntegratorChoice::Path), ("direct", IntegratorChoice::Direct)])?;
    let job = RenderJob {
        scene,
        width: size.0,
        height: size.1,
        spp,
        time,
        env,
        env_intensity,
        sky,
        sky_intensity,
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
        environment_at: vec3("environment_at", environment_at)?,
        crop: crop.map(|(x0, y0, x1, y1)| Crop { x0, y0, x1, y1 }),
    };
    let pool = pool(threads)?;
    let stop = AtomicBool::new(false);
    let (film, stats, warnings) = interruptible(py, &stop, || -> Result<_, JobError> {
        let run = || {
            let mut loaded = job.load()?;
            let (film, mut stats) = loaded.render(&job, |_| {}, &stop);
            let mut warnings = loaded.warnings;
            warnings.append(&mut stats.report.warnings);
            Ok((film, stats, warnings))
        };
        match &pool {
            Some(pool) => pool.install(run),
            None => run(),
        }
    })?
    .map_err(job_error)?;
    if stats.stopped {
        return Err(PyKeyboardInterrupt::new_err("kelvin.render stopped"));
    }
    let (width, height) = (film.width, film.height);
    let flat: Vec<f32> = film.pixels().iter().flat_map(|p| p.to_array()).collect();
    let info = PyDict::new(py);
    info.set_item("seconds", stats.seconds)?;
    info.set_item("spp", stats.spp)?;
    info.set_item("camera_samples", stats.camera_samples)?;
    info.set_item("shadow_rays", stats.shadow_rays)?;
    info.set_item("bsdf_rays", stats.bsdf_rays)?;
    Ok((PyArray1::from_vec(py, flat), width, height, warnings, info))
}

/// Writes a linear image (flat RGB, rows top to bottom) as a 32-bit float OpenEXR.
#[pyfunction]
fn write_exr(path: PathBuf, pixels: PyReadonlyArray1<'_, f32>, width: usize, height: usize) -> PyResult<()> {
    let rgb = rgb_of(&pixels)?;
    kelvin::render::film_io::write_exr(&path, width, height, &rgb).map_err(|e| PyOSError::new_err(e.to_string()))
}

/// Writes a tone-mapped 8-bit sRGB PNG; `exposure` in stops, automatic (as `kelvin render`'s) when None.
#[pyfunction]
#[pyo3(signature = (path, pixels, width, height, exposure=None))]
fn write_png(
    path: PathBuf,
    pixels: PyReadonlyArray1<'_, f32>,
    width: usize,
    height: usize,
    exposure: Option<f32>,
) -> PyResult<()> {
    let rgb = rgb_of(&pixels)?;
    let exposure = exposure.unwrap_or_else(|| kelvin::render::film_io::auto_exposure(&rgb));
    if !exposure.is_finite() {
        return Err(PyValueError::new_err(format!("exposure = {exposure}: not finite")));
    }
    kelvin::render::film_io::write_png(&path, width, height, &rgb, exposure)
        .map_err(|e| PyOSError::new_err(e.to_string()))
}

/// Reads an OpenEXR image: flat RGB, width and height.
#[pyfunction]
fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Bound<'py, PyArray1<f32>>, usize, usize)> {
    let (w, h, rgb) = kelvin::render::film_io::read_exr(&path).map_err(|e| PyOSError::new_err(e.to_string()))?;
    let flat: Vec<f32> = rgb.iter().flat_map(|p| p.to_array()).collect();
    Ok((PyArray1::from_vec(py, flat), w, h))
}

pub(crate) fn rgb_of(pixels: &PyReadonlyArray1<'_, f32>) -> PyResult<Vec<Vec3>> {
    let flat = pixels.as_slice()?;
    Ok(flat.chunks_exact(3).map(Vec3::from_slice).collect())
}

/// What `kelvin spectrum SPEC --json` prints, as JSON text.
#[pyfunction]
fn spectrum_json(spec: &str) -> PyResult<String> {
    let spectrum = kelvin::spectrum::Spectrum::parse(spec).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let summary = kelvin::spectrum::SpectrumSummary::of(&spectrum);
    serde_json::to_string(&summary).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// What `kelvin ies FILE --json` prints, as JSON text.
#[pyfunction]
fn ies_json(path: PathBuf) -> PyResult<String> {
    let profile = kelvin::scene::ies::IesProfile::from_file(&path).map_err(|e| PyOSError::new_err(e.to_string()))?;
    let summary = kelvin::scene::ies::IesSummary::of(&profile);
    serde_json::to_string(&summary).map_err(|e| PyValueError::new_err(e.to_string()))
}

#[pymodule]
fn _kelvin(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(write_png, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(spectrum_json, m)?)?;
    m.add_function(wrap_pyfunction!(ies_json, m)?)?;
    m.add_class::<lights::LightSystem>()?;
    Ok(())
}
