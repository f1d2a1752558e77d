//! A sun and sky carried in the file: the root extension `KELVIN_sun_sky` (kelvin's own; glTF has
//! no standard one), read into a [`SunSkyLight`]:
//!
//! ```json
//! "extensions": { "KELVIN_sun_sky": {
//!     "latitude": 48.14, "longitude": 11.58, "time": "2024-06-21T10:00",
//!     "turbidity": 3.0, "groundAlbedo": 0.3, "sunAngularDiameter": 0.0093, "intensity": 1.0 } }
//! ```
//!
//! The sun is placed by `latitude` and `longitude` (degrees north and east) and `time` (UTC,
//! `YYYY-MM-DDTHH:MM[:SS]`), or by `direction` (toward the sun, world frame, +Y up), not both.
//! `sunAngularDiameter` is in radians as glTF's angles are; `intensity` multiplies the model's
//! physical radiance. A bad optional field gets a warning at its pointer and its default; a sun that
//! cannot be placed drops the sky with a warning; a sun past the end of civil twilight keeps the
//! (dark) sky and says so. Sky extensions kelvin does not evaluate get a warning at their pointer.

use serde_json::Value;

use super::Warnings;
use crate::light::SunSkyLight;
use crate::light::infinite::SunPosition;
use crate::light::infinite::sunsky::solar::UtcDateTime;

/// The extension's name.
pub const SUN_SKY: &str = "KELVIN_sun_sky";

/// Root extensions that describe a sky or an environment kelvin does not read from files, and
/// what to do instead.
const UNREAD_SKIES: &[(&str, &str)] = &[(
    "EXT_lights_image_based",
    "image-based lights are not read from glTF files; pass the map with --env (or `env=` in Python)",
)];

/// The file's sun and sky, if it has one that kelvin can evaluate.
pub(super) fn read_sky(json: &Value, warnings: &mut Warnings) -> Option<SunSkyLight> {
    for (name, instead) in UNREAD_SKIES {
        if json.pointer(&format!("/extensions/{name}")).is_some() {
            warnings.push(&format!("/extensions/{name}"), instead);
        }
    }
    let pointer = format!("/extensions/{SUN_SKY}");
    let object = match json.pointer(&pointer)? {
        Value::Object(o) => o,
        _ => {
            warnings.push(&pointer, "not an object; no sky");
            return None;
        }
    };
    let at = |field: &str| format!("{pointer}/{field}");
    let number = |field: &str, warnings: &mut Warnings| -> Option<f64> {
        let v = object.get(field)?;
        match v.as_f64().filter(|x| x.is_finite()) {
            Some(x) => Some(x),
            None => {
                warnings.push(&at(field), format!("{v} is not a number"));
                None
            }
        }
    };
    let place = (number("latitude", warnings), number("longitude", warnings), object.get("time"));
    let direction = object.get("direction");
    let sun = match (place, direction) {
        ((None, None, None), None) => {
            warnings.push(&pointer, "needs latitude, longitude and time, or a direction; no sky");
            return None;
        }
        ((Some(_), _, _) | (_, Some(_), _) | (_, _, Some(_)), Some(_)) => {
            warnings.push(&pointer, "give latitude, longitude and time, or a direction, not both; no sky");
            return None;
        }
        ((Some(latitude_deg), Some(longitude_deg), Some(time)), None) => {
            let time = match time.as_str().map(UtcDateTime::parse) {
                Some(Ok(t)) => t,
                Some(Err(e)) => {
                    warnings.push(&at("time"), format!("{e}; no sky"));
                    return None;
                }
                None => {
                    warnings.push(&at("time"), format!("{time} is not a string; no sky"));
                    return None;
                }
            };
            SunPosition::Location { latitude_deg, longitude_deg, time }
        }
        ((_, _, _), None) => {
            let missing: Vec<&str> = [("latitude", place.0.is_none()), ("longitude", place.1.is_none())]
                .into_iter()
                .chain([("time", place.2.is_none())])
                .filter_map(|(f, gone)| gone.then_some(f))
                .collect();
            warnings.push(&pointer, format!("{} missing or not a number; no sky", missing.join(" and ")));
            return None;
        }
        (_, Some(d)) => match d.as_array().map(|a| a.iter().filter_map(Value::as_f64).collect::<Vec<_>>()) {
            Some(v) if v.len() == 3 => SunPosition::Direction(glam::Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)),
            _ => {
                warnings.push(&at("direction"), format!("{d} is not three numbers; no sky"));
                return None;
            }
        },
    };
    let mut light = SunSkyLight { sun, ..SunSkyLight::default() };
    // Optional fields: each checked alone, so one bad value falls back to its default only.
    let fields: [(&str, fn(&mut SunSkyLight) -> &mut f32); 4] = [
        ("turbidity", |l| &mut l.turbidity),
        ("groundAlbedo", |l| &mut l.ground_albedo),
        ("sunAngularDiameter", |l| &mut l.sun_angular_diameter),
        ("intensity", |l| &mut l.scale),
    ];
    for (field, slot) in fields {
        let Some(value) = number(field, warnings) else { continue };
        let mut trial = light.clone();
        *slot(&mut trial) = value as f32;
        match trial.validate() {
            Ok(()) => light = trial,
            Err(e) => warnings.push(&at(field), format!("{e}; the default is used")),
        }
    }
    match light.dark_reason() {
        Ok(None) => {}
        Ok(Some(dark)) => warnings.push(&pointer, dark),
        Err(e) => {
            warnings.push(&pointer, format!("{e}; no sky"));
            return None;
        }
    }
    Some(light)
}
