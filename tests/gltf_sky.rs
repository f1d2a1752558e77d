//! A sun and sky carried in the scene file (`KELVIN_sun_sky`), read by every loader path alike:
//! the same image as `--sky` with the same place and time, `sky_intensity` scaling it, the job's
//! sky replacing it; bad fields, skies kelvin cannot evaluate and a sun below the horizon get
//! warnings at their JSON pointers.

mod common;

use kelvin::light::SunSkyLight;
use kelvin::light::infinite::SunPosition;
use kelvin::render::job::{IntegratorChoice, RenderJob};
use kelvin::scene::gltf::load_gltf_from_bytes;
use serde_json::{Value, json};

use common::files::{TempDir, test_data};

const SPEC: &str = "48.14,11.58,2024-06-21T10:00,4";

/// tests/data/gltf/kelvin/animated_lamp.gltf (a floor, a shutter, a camera; buffers embedded)
/// without its lamp, with `sky` as its `KELVIN_sun_sky` (None: no sky).
fn lamp_file_with_sky(sky: Option<Value>) -> Value {
    let text = std::fs::read_to_string(test_data("gltf/kelvin/animated_lamp.gltf")).unwrap();
    let mut doc: Value = serde_json::from_str(&text).unwrap();
    doc["nodes"][3].as_object_mut().unwrap().remove("extensions");
    let root = doc.as_object_mut().unwrap();
    root.remove("extensions");
    root.insert("extensionsUsed".into(), json!(["KHR_materials_specular", "KELVIN_sun_sky"]));
    if let Some(sky) = sky {
        root.insert("extensions".into(), json!({ "KELVIN_sun_sky": sky }));
    }
    doc
}

fn warnings_of(doc: &Value) -> (Option<SunSkyLight>, Vec<String>) {
    let scene = load_gltf_from_bytes(doc.to_string().as_bytes(), None, "sky.gltf").unwrap();
    (scene.sky, scene.warnings)
}

/// Renders `doc` (written to a file) as `kelvin render` would, with the job's own sky options.
fn render(dir: &TempDir, doc: &Value, sky: Option<&str>, sky_intensity: f32) -> (Vec<glam::Vec3>, Vec<String>) {
    let path = dir.join("scene.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let job = RenderJob {
        scene: Some(path),
        width: 12,
        height: 8,
        spp: 4,
        sky: sky.map(str::to_string),
        sky_intensity,
        integrator: IntegratorChoice::Direct,
        ..RenderJob::default()
    };
    let mut loaded = job.load().unwrap();
    let (film, stats) = loaded.render(&job, |_| {}, &std::sync::atomic::AtomicBool::new(false));
    let mut warnings = loaded.warnings;
    warnings.extend(stats.report.warnings);
    (film.pixels(), warnings)
}

#[test]
fn the_file_sky_is_the_sky_of_the_same_place_and_time() {
    let sky = json!({ "latitude": 48.14, "longitude": 11.58, "time": "2024-06-21T10:00", "turbidity": 4 });
    let (read, warnings) = warnings_of(&lamp_file_with_sky(Some(sky.clone())));
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(read.unwrap(), SunSkyLight::parse(SPEC).unwrap());

    let dir = TempDir::new("gltf-sky", "same-place");
    let (from_file, w) = render(&dir, &lamp_file_with_sky(Some(sky)), None, 1.0);
    assert!(w.is_empty(), "{w:?}");
    let (from_job, _) = render(&dir, &lamp_file_with_sky(None), Some(SPEC), 1.0);
    assert!(from_file.iter().any(|p| p.x > 0.0), "the floor is lit by day");
    assert_eq!(from_file, from_job, "bit for bit: the file's sky is --sky's");
}

#[test]
fn sky_intensity_scales_the_file_sky_and_the_jobs_sky_replaces_it() {
    let dir = TempDir::new("gltf-sky", "scale");
    let doc = lamp_file_with_sky(Some(json!({ "direction": [0.3, 1.0, 0.2], "intensity": 0.5 })));
    let (half, _) = render(&dir, &doc, None, 1.0);
    let (whole, _) = render(&dir, &doc, None, 2.0);
    // One light: its selection probability is 1 at any power, so doubling is exact.
    assert!(half.iter().any(|p| p.x > 0.0));
    for (h, w) in half.iter().zip(&whole) {
        assert_eq!(*h * 2.0, *w);
    }
    let (replaced, warnings) = render(&dir, &doc, Some(SPEC), 1.0);
    let (job_only, _) = render(&dir, &lamp_file_with_sky(None), Some(SPEC), 1.0);
    assert_eq!(replaced, job_only);
    assert!(warnings.iter().any(|w| w.contains("KELVIN_sun_sky is replaced by the job's sky")), "{warnings:?}");
}

#[test]
fn a_sun_below_the_horizon_is_a_dark_sky_and_says_so_at_load_and_at_render() {
    // Munich at 22:00 UTC on the summer solstice: the sun is about 15 degrees below the horizon.
    let night = json!({ "latitude": 48.14, "longitude": 11.58, "time": "2024-06-21T22:00" });
    let (read, warnings) = warnings_of(&lamp_file_with_sky(Some(night.clone())));
    assert!(read.is_some(), "the sky is kept: it turns on when an app moves the sun");
    assert!(
        warnings.iter().any(|w| w.starts_with("sky.gltf: /extensions/KELVIN_sun_sky: the sun is 1")
            && w.contains("degrees below the horizon at 48.14, 11.58 on 2024-06-21T22:00 UTC")
            && w.contains("the night sky is not modelled")),
        "{warnings:?}"
    );
    let dir = TempDir::new("gltf-sky", "night");
    let (image, warnings) = render(&dir, &lamp_file_with_sky(Some(night)), None, 1.0);
    assert!(image.iter().all(|p| *p == glam::Vec3::ZERO), "no light at night");
    assert!(warnings.iter().any(|w| w.starts_with("sun and sky ") && w.contains("below the horizon")), "{warnings:?}");
}

#[test]
fn bad_fields_get_warnings_at_their_pointers() {
    let p = "sky.gltf: /extensions/KELVIN_sun_sky";
    let cases: &[(Value, &str, bool)] = &[
        (json!([1, 2]), "sky.gltf: /extensions/KELVIN_sun_sky: not an object; no sky", false),
        (json!({}), "needs latitude, longitude and time, or a direction; no sky", false),
        (json!({ "latitude": 10, "time": "2024-06-21T10:00" }), "longitude missing or not a number; no sky", false),
        (json!({ "direction": [0, 1, 0], "latitude": 1 }), "not both; no sky", false),
        (json!({ "direction": [0, 1] }), "/direction: [0,1] is not three numbers; no sky", false),
        (json!({ "direction": [0, 0, 0] }), "must be finite and nonzero; no sky", false),
        (json!({ "latitude": 95, "longitude": 0, "time": "2024-06-21T10:00" }), "latitude", false),
        (json!({ "latitude": 0, "longitude": 0, "time": "noon" }), "/time: ", false),
        (json!({ "latitude": 0, "longitude": 0, "time": 12 }), "/time: 12 is not a string; no sky", false),
        (json!({ "direction": [0, 1, 0], "turbidity": 40 }), "/turbidity: ", true),
        (json!({ "direction": [0, 1, 0], "groundAlbedo": "white" }), "/groundAlbedo: \"white\" is not a number", true),
        (json!({ "direction": [0, 1, 0], "intensity": -1 }), "/intensity: ", true),
        (json!({ "direction": [0, 1, 0], "sunAngularDiameter": 2 }), "/sunAngularDiameter: ", true),
    ];
    for (sky, says, kept) in cases {
        let (read, warnings) = warnings_of(&lamp_file_with_sky(Some(sky.clone())));
        assert!(
            warnings.iter().any(|w| w.starts_with(p) && w.contains(says)),
            "{sky}: expected '{says}' in {warnings:?}"
        );
        assert_eq!(read.is_some(), *kept, "{sky}");
        if let Some(light) = read {
            // The bad field fell back to its default; the rest stands.
            let default = SunSkyLight { sun: SunPosition::Direction(glam::Vec3::Y), ..SunSkyLight::default() };
            assert_eq!(light, default, "{sky}");
        }
    }
}

#[test]
fn an_image_based_light_extension_is_named_with_what_to_do_instead() {
    let mut doc = lamp_file_with_sky(None);
    doc["extensions"] = json!({ "EXT_lights_image_based": { "lights": [] } });
    let (sky, warnings) = warnings_of(&doc);
    assert!(sky.is_none());
    assert!(
        warnings.iter().any(|w| w.starts_with("sky.gltf: /extensions/EXT_lights_image_based: ") && w.contains("--env")),
        "{warnings:?}"
    );
}
