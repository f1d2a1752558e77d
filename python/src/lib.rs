//! `kelvin._kelvin`: the native half of the Python package. Python (`pysrc/kelvin/__init__.py`)
//! checks shapes and dtypes, turns warnings into Python warnings and documents the API; this side
//! maps keyword arguments onto kelvin's own types and runs the work without the GIL.

mod lights;
mod scene;

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use glam::Vec3;
use kelvin::render::job::SamplerChoice;
use kelvin::shading::ColorMode;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;

/// One of `accepted` (by name), for a keyword argument `what`.
pub(crate) fn choice<T: Copy>(what: &str, given: &str, accepted: &[(&str, T)]) -> PyResult<T> {
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

/// Worker threads of a run.
const THREADS: std::ops::RangeInclusive<u32> = 1..=1024;

/// A rayon pool of `threads` workers, or None for the global pool.
pub(crate) fn pool(threads: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    match threads {
        None => Ok(None),
        Some(t) if !u32::try_from(t).is_ok_and(|t| THREADS.contains(&t)) => {
            Err(PyValueError::new_err(format!("threads = {t} is outside {}..={}", THREADS.start(), THREADS.end())))
        }
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

pub(crate) fn vec3(what: &str, v: Option<[f32; 3]>) -> PyResult<Option<Vec3>> {
    match v.map(Vec3::from) {
        Some(p) if !p.is_finite() => Err(PyValueError::new_err(format!("{what} = {p}: not finite"))),
        p => Ok(p),
    }
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

/// The ranges of the integer and float options, name to (lowest, highest): what Python checks
/// before PyO3's conversions, which would raise errors without the option's name.
fn limits(py: Python<'_>) -> PyResult<Bound<'_, pyo3::types::PyDict>> {
    use kelvin::render::job::{CANDIDATES, DEPTH, INTENSITY, MAX_SIDE, NEIGHBOURS, RADIUS, SECONDS, SPP};
    let d = pyo3::types::PyDict::new(py);
    let ranges = [
        ("size", 1..=MAX_SIDE),
        ("crop", 0..=MAX_SIDE),
        ("spp", SPP),
        ("max_depth", DEPTH),
        ("roulette_depth", DEPTH),
        ("candidates", CANDIDATES),
        ("neighbours", NEIGHBOURS),
        ("radius", RADIUS),
        ("light_spp", lights::SPP),
        ("threads", THREADS),
    ];
    for (name, r) in ranges {
        d.set_item(name, (*r.start(), *r.end()))?;
    }
    d.set_item("seed", (0u64, u64::MAX))?;
    d.set_item("intensity", (*INTENSITY.start(), *INTENSITY.end()))?;
    d.set_item("time", (SECONDS.start, SECONDS.end))?;
    Ok(d)
}

#[pymodule]
fn _kelvin(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("LIMITS", limits(m.py())?)?;
    m.add("LUMINANCE_WEIGHTS", kelvin::scene::image::LUMINANCE_WEIGHTS.to_array())?;
    m.add_function(wrap_pyfunction!(write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(write_png, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(spectrum_json, m)?)?;
    m.add_function(wrap_pyfunction!(ies_json, m)?)?;
    m.add_class::<lights::LightSystem>()?;
    m.add_class::<scene::Scene>()?;
    Ok(())
}
