//! Planck's law, Wien's displacement and the Stefan-Boltzmann law, plus Kirchhoff's law for
//! non-black emitters. All in f64 and SI, with wavelengths in nanometres.

/// Planck constant, J s (SI 2019, exact).
pub const PLANCK_H: f64 = 6.626_070_15e-34;
/// Speed of light in vacuum, m/s (exact).
pub const LIGHT_SPEED_C: f64 = 299_792_458.0;
/// Boltzmann constant, J/K (SI 2019, exact).
pub const BOLTZMANN_K: f64 = 1.380_649e-23;
/// Wien's displacement constant b, m K (CODATA 2018).
pub const WIEN_B: f64 = 2.897_771_955e-3;
/// Stefan-Boltzmann constant, W/(m^2 K^4) (CODATA 2018).
pub const STEFAN_BOLTZMANN: f64 = 5.670_374_419e-8;

/// Spectral radiance of a blackbody at `lambda_nm` and temperature `t_k`, in W/(m^2 sr nm).
///
/// Finite for every input: 0 for T <= 0, for non-finite or non-positive wavelengths, and where
/// the exponent hc/(lambda k T) overflows (the true value underflows f64 there anyway).
pub fn planck(lambda_nm: f64, t_k: f64) -> f64 {
    if !(t_k > 0.0 && lambda_nm > 0.0 && t_k.is_finite() && lambda_nm.is_finite()) {
        return 0.0;
    }
    let lambda = lambda_nm * 1e-9;
    let x = PLANCK_H * LIGHT_SPEED_C / (lambda * BOLTZMANN_K * t_k);
    if x > 700.0 {
        return 0.0; // exp(x) overflows past ~709.78
    }
    // 2hc^2 / lambda^5 split so the intermediate stays in range for lambda down to 1e-12 m.
    let l2 = lambda * lambda;
    let radiance_per_m = 2.0 * PLANCK_H * LIGHT_SPEED_C * LIGHT_SPEED_C / (l2 * l2 * lambda) / x.exp_m1();
    radiance_per_m * 1e-9
}

/// Wavelength of peak spectral radiance, nm (Wien: lambda_max = b / T). 0 for T <= 0.
pub fn wien_peak_nm(t_k: f64) -> f64 {
    if t_k > 0.0 && t_k.is_finite() { WIEN_B / t_k * 1e9 } else { 0.0 }
}

/// Planck's law divided by its value at Wien's peak, so the curve peaks at exactly 1 (pbrt's
/// normalised `BlackbodySpectrum`). 0 wherever `planck` is 0.
///
/// At the peak, x = hc / (lambda_max k T) = hc / (b k) is the same for every T, so the ratio is
/// (lambda_max / lambda)^5 (e^x_max - 1) / (e^x - 1): one exponential per call.
pub fn planck_normalized(lambda_nm: f64, t_k: f64) -> f64 {
    if !(t_k > 0.0 && lambda_nm > 0.0 && t_k.is_finite() && lambda_nm.is_finite()) {
        return 0.0;
    }
    const X_MAX: f64 = PLANCK_H * LIGHT_SPEED_C / (WIEN_B * BOLTZMANN_K);
    let x = PLANCK_H * LIGHT_SPEED_C / (lambda_nm * 1e-9 * BOLTZMANN_K * t_k);
    if x > 700.0 {
        return 0.0;
    }
    let r = wien_peak_nm(t_k) / lambda_nm;
    let r5 = r * r * r * r * r;
    if !r5.is_finite() {
        return 0.0; // lambda far below the peak of a very cold body: the true value underflows
    }
    r5 * X_MAX.exp_m1() / x.exp_m1()
}

/// Radiant exitance of a blackbody, W/m^2: M = sigma T^4 (pi times the integral of `planck`).
pub fn blackbody_exitance(t_k: f64) -> f64 {
    if t_k > 0.0 && t_k.is_finite() { STEFAN_BOLTZMANN * t_k.powi(4) } else { 0.0 }
}

/// Radiance integrated over all wavelengths, W/(m^2 sr): sigma T^4 / pi.
pub fn blackbody_radiance_total(t_k: f64) -> f64 {
    blackbody_exitance(t_k) / std::f64::consts::PI
}

/// Kirchhoff's law: a body in thermal equilibrium emits eps(lambda) B(lambda, T), where the
/// emissivity eps equals its absorptivity. `emissivity` is clamped to [0, 1].
pub fn kirchhoff(lambda_nm: f64, t_k: f64, emissivity: f64) -> f64 {
    let eps = if emissivity.is_nan() { 0.0 } else { emissivity.clamp(0.0, 1.0) };
    eps * planck(lambda_nm, t_k)
}
