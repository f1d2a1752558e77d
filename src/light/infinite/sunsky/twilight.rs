//! What the sky does as the sun sets: the elevation the model takes, and the fade through civil
//! twilight, past the model's range.
//!
//! The Hosek-Wilkie tables are parametrised by the sun's geometric elevation in [0, 90] degrees
//! (their atmosphere is simulated with straight rays), so the model is fed the unrefracted
//! elevation; the sun's disc is still drawn where it is seen (the refracted direction). Mitsuba 3's
//! `sunsky` also takes an unrefracted position, and gives no light once the sun's centre is below
//! the horizon.
//!
//! Below the horizon kelvin keeps the model's sky at elevation 0 and scales it by
//! [`sky_fade`]: an exponential fall of one e-fold per degree of solar depression, shifted to reach
//! zero at the end of civil twilight (geometric elevation -6 degrees). The rate is fitted to the
//! AMS Glossary of Meteorology ("civil twilight"): on a clear evening the horizontal illuminance
//! falls from ~585-410 lx at sunset to ~3.5-2 lx at -6 degrees, a factor of e^4.8 to e^5.4 over
//! the 5.2 degrees between (sunset is the geometric elevation -0.833: refraction plus the disc's
//! radius). Nautical and astronomical twilight (below 0.01 lx) and the night sky are not modelled.

/// Geometric solar elevation (degrees) where the sky has faded to black: the end of civil
/// twilight (AMS Glossary of Meteorology).
pub const CIVIL_TWILIGHT_END_DEG: f32 = -6.0;

/// Degrees of solar depression per e-fold of the twilight sky (fitted to the AMS figures; see the
/// module docs).
pub const TWILIGHT_E_FOLD_DEG: f32 = 1.0;

/// Factor on the sky model's radiance at geometric solar elevation `elevation` (radians): 1 with
/// the sun above the horizon, e^(h / 1 degree) below it, less its value at -6 degrees (and
/// renormalised) so that it reaches 0 there continuously; 0 below. Monotone in `elevation`; NaN
/// gives 0.
pub fn sky_fade(elevation: f32) -> f32 {
    let h = elevation.to_degrees();
    if h >= 0.0 {
        return 1.0;
    }
    if !(h > CIVIL_TWILIGHT_END_DEG) {
        return 0.0;
    }
    let end = (CIVIL_TWILIGHT_END_DEG / TWILIGHT_E_FOLD_DEG).exp();
    (((h / TWILIGHT_E_FOLD_DEG).exp() - end) / (1.0 - end)).clamp(0.0, 1.0)
}
