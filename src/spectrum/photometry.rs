//! Luminous efficacy and photometric <-> radiometric conversion.
//!
//! One ratio converts every pair: lm <-> W, cd <-> W/sr, lx <-> W/m^2 and nit <-> W/(m^2 sr) all
//! differ by the luminous efficacy K (lm/W) of the light's spectrum.

/// Maximum luminous efficacy of photopic vision, lm/W (at 540 THz, about 555 nm; SI definition).
pub const K_M: f64 = 683.0;

/// K = 683 * integral(V S) / integral(S), from the two integrals. 0 when S integrates to 0.
pub fn luminous_efficacy_of(y_integral: f64, spectrum_integral: f64) -> f64 {
    if spectrum_integral > 0.0 && y_integral.is_finite() { K_M * y_integral / spectrum_integral } else { 0.0 }
}

/// Radiometric amount (W, W/sr, W/m^2, W/(m^2 sr)) of a photometric one (lm, cd, lx, nit) for a
/// spectrum of efficacy `efficacy_lm_per_w`. 0 when the efficacy is 0 (invisible light).
pub fn radiometric(photometric: f64, efficacy_lm_per_w: f64) -> f64 {
    if efficacy_lm_per_w > 0.0 { photometric / efficacy_lm_per_w } else { 0.0 }
}

/// Photometric amount (lm, cd, lx, nit) of a radiometric one (W, W/sr, W/m^2, W/(m^2 sr)).
pub fn photometric(radiometric: f64, efficacy_lm_per_w: f64) -> f64 {
    radiometric * efficacy_lm_per_w
}

/// Lumens to watts for a spectrum of the given efficacy.
pub fn watts_from_lumens(lm: f64, efficacy_lm_per_w: f64) -> f64 {
    radiometric(lm, efficacy_lm_per_w)
}

/// Candela to W/sr.
pub fn watts_per_sr_from_candela(cd: f64, efficacy_lm_per_w: f64) -> f64 {
    radiometric(cd, efficacy_lm_per_w)
}

/// Lux to W/m^2.
pub fn watts_per_m2_from_lux(lx: f64, efficacy_lm_per_w: f64) -> f64 {
    radiometric(lx, efficacy_lm_per_w)
}

/// Nits (cd/m^2) to W/(m^2 sr).
pub fn radiance_from_nits(nits: f64, efficacy_lm_per_w: f64) -> f64 {
    radiometric(nits, efficacy_lm_per_w)
}
