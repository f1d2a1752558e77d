//! The Hosek-Wilkie sky and sun: L. Hosek and A. Wilkie, "An Analytic Model for Full Spectral
//! Sky-Dome Radiance", ACM TOG 31(4) (SIGGRAPH 2012), and "Adding a Solar Radiance Function to the
//! Hosek Skylight Model", IEEE CG&A 33(3) 2013. The coefficient tables are the authors' (version
//! 1.4a, 3-clause BSD: data/README.md, data/LICENSE-hosek-wilkie.txt); this evaluation is kelvin's.
//!
//! Sky (paper eq. 9): L(theta, gamma) = F(theta, gamma) * L_M, with
//! F = (1 + A e^(B / (cos theta + 0.01))) (C + D e^(E gamma) + F cos^2 gamma + G chi(H, gamma) + I sqrt(cos theta))
//! and chi(g, a) = (1 + cos^2 a) / (1 + g^2 - 2 g cos a)^(3/2): theta is the view direction's zenith
//! angle, gamma its angle to the sun. A..I and L_M come from tables over turbidity 1..10, ground
//! albedo 0 and 1 and six control points of a quintic Bezier in (solar elevation / (pi/2))^(1/3),
//! linear in turbidity and albedo (paper section 5).
//!
//! Units: the spectral tables give W/(m^2 sr nm) at 320, 360, ..., 720 nm; kelvin holds the 720 nm
//! value up to 830 nm (the model has no data there, its luminous share is under 0.5%). The RGB
//! tables are linear sRGB with Y = integral of L ybar d(lambda) (no 683): kelvin's photometric RGB
//! (nit) is [`K_M`] times them, which the tests check against the spectral model's luminance.

use std::sync::LazyLock;

use glam::Vec3;

use crate::spectrum::photometry::K_M;

/// The spectral model's wavelengths, nm.
pub const WAVELENGTHS_NM: [f32; 11] = [320.0, 360.0, 400.0, 440.0, 480.0, 520.0, 560.0, 600.0, 640.0, 680.0, 720.0];
/// The turbidities the tables cover.
pub const TURBIDITY_RANGE: (f32, f32) = (1.0, 10.0);

const N_TURB: usize = 10;
const N_CTRL: usize = 6;
const N_PARAMS: usize = 9;
const N_WL: usize = 11;
const SUN_PIECES: usize = 45;
const SUN_ORDER: usize = 4;

/// The tables, in the order and shapes of data/README.md (C order, turbidity outermost).
struct Tables {
    sky_params_rgb: Vec<f64>,
    sky_rad_rgb: Vec<f64>,
    sky_params_spec: Vec<f64>,
    sky_rad_spec: Vec<f64>,
    sun_rad_spec: Vec<f64>,
    sun_ld_spec: Vec<f64>,
}

static TABLES: LazyLock<Tables> = LazyLock::new(|| {
    let bytes = include_bytes!("data/hosek_wilkie.bin");
    let mut values = bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64);
    let mut take = |n: usize| -> Vec<f64> { values.by_ref().take(n).collect() };
    let t = Tables {
        sky_params_rgb: take(N_TURB * 2 * N_CTRL * 3 * N_PARAMS),
        sky_rad_rgb: take(N_TURB * 2 * N_CTRL * 3),
        sky_params_spec: take(N_TURB * 2 * N_CTRL * N_WL * N_PARAMS),
        sky_rad_spec: take(N_TURB * 2 * N_CTRL * N_WL),
        sun_rad_spec: take(N_TURB * SUN_PIECES * N_WL * SUN_ORDER),
        sun_ld_spec: take(N_WL * 6),
    };
    assert_eq!(t.sun_ld_spec.len(), N_WL * 6, "hosek_wilkie.bin is truncated");
    t
});

/// One channel of the sky model at one turbidity, albedo and solar elevation: the nine
/// parameters A..I of F and the radiance scale L_M.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChannelConfig {
    /// In the tables' order A, B, C, D, E, F, G, I, H: the paper's letters, with the zenith
    /// weight I stored before the Mie term's H (as the authors' code reads them).
    pub params: [f32; 9],
    /// L_M: W/(m^2 sr nm) for spectral channels, Y-weighted W/(m^2 sr) for RGB ones.
    pub radiance: f32,
}

impl ChannelConfig {
    /// L = F(theta, gamma) L_M for `cos_theta` >= 0 (the view's zenith cosine) and `gamma` the
    /// angle to the sun, radians.
    #[inline]
    pub fn eval(&self, cos_theta: f32, gamma: f32, cos_gamma: f32) -> f32 {
        self.dome(cos_theta) * self.circumsolar(cos_theta.sqrt(), gamma, cos_gamma)
    }

    /// The factor of F that depends on theta alone, times L_M: (1 + A e^(B / (cos theta + 0.01))) L_M,
    /// once per row of a lat-long image.
    #[inline]
    pub fn dome(&self, cos_theta: f32) -> f32 {
        let [a, b, ..] = self.params;
        (1.0 + a * (b / (cos_theta + 0.01)).exp()) * self.radiance
    }

    /// The other factor: C + D e^(E gamma) + F cos^2 gamma + G chi(H, gamma) + I sqrt(cos theta).
    #[inline]
    pub fn circumsolar(&self, sqrt_cos_theta: f32, gamma: f32, cos_gamma: f32) -> f32 {
        let [_, _, c, d, e, f, g, i, h] = self.params;
        let x = 1.0 + h * h - 2.0 * h * cos_gamma;
        // x^(3/2) as x sqrt(x): the sky table evaluates this per texel.
        let mie = (1.0 + cos_gamma * cos_gamma) / (x * x.sqrt());
        c + d * (e * gamma).exp() + f * cos_gamma * cos_gamma + g * mie + i * sqrt_cos_theta
    }
}

/// Quintic Bezier through six control points `ctrl(k)` at `x` in [0, 1].
fn bezier5(x: f64, ctrl: impl Fn(usize) -> f64) -> f64 {
    const BINOM: [f64; 6] = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
    (0..N_CTRL).map(|k| BINOM[k] * (1.0 - x).powi(5 - k as i32) * x.powi(k as i32) * ctrl(k)).sum()
}

/// The (turbidity index, weight) pairs of linear interpolation at `turbidity` in [1, 10].
fn turbidity_weights(turbidity: f64) -> [(usize, f64); 2] {
    let lo = (turbidity.floor() as usize).clamp(1, N_TURB);
    let frac = turbidity - lo as f64;
    [(lo - 1, 1.0 - frac), ((lo).min(N_TURB - 1), if lo < N_TURB { frac } else { 0.0 })]
}

/// Cooks channel `ch` of `n_ch` from tables laid out [turbidity][albedo][ctrl][channel](params).
fn cook(params: &[f64], rad: &[f64], n_ch: usize, ch: usize, t: f64, albedo: f64, x: f64) -> ChannelConfig {
    let mut out = [0.0f64; 9];
    let mut radiance = 0.0;
    for (ti, wt) in turbidity_weights(t) {
        for (ai, wa) in [(0usize, 1.0 - albedo), (1, albedo)] {
            let w = wt * wa;
            if w == 0.0 {
                continue;
            }
            let block = (ti * 2 + ai) * N_CTRL;
            for (p, o) in out.iter_mut().enumerate() {
                *o += w * bezier5(x, |k| params[((block + k) * n_ch + ch) * N_PARAMS + p]);
            }
            radiance += w * bezier5(x, |k| rad[(block + k) * n_ch + ch]);
        }
    }
    ChannelConfig { params: out.map(|v| v as f32), radiance: radiance as f32 }
}

/// The sky dome for one sun elevation, turbidity and albedo, every channel cooked.
#[derive(Clone, Debug, PartialEq)]
pub struct SkyModel {
    /// Linear sRGB channels (Y-weighted W/(m^2 sr); times [`K_M`] for nit).
    pub rgb: [ChannelConfig; 3],
    /// The spectral channels at [`WAVELENGTHS_NM`].
    pub spectral: [ChannelConfig; 11],
}

impl SkyModel {
    /// The model at solar elevation `elevation` (radians), `turbidity` and ground `albedo`; each
    /// is clamped to the tables' range ([0, pi/2], [1, 10], [0, 1]), NaN counting as the low end.
    pub fn new(elevation: f32, turbidity: f32, albedo: f32) -> Self {
        let clamp = |v: f32, lo: f32, hi: f32| if v.is_nan() { lo } else { v.clamp(lo, hi) } as f64;
        let e = clamp(elevation, 0.0, std::f32::consts::FRAC_PI_2);
        let t = clamp(turbidity, TURBIDITY_RANGE.0, TURBIDITY_RANGE.1);
        let a = clamp(albedo, 0.0, 1.0);
        let x = (e / std::f64::consts::FRAC_PI_2).cbrt();
        let tb = &*TABLES;
        Self {
            rgb: std::array::from_fn(|c| cook(&tb.sky_params_rgb, &tb.sky_rad_rgb, 3, c, t, a, x)),
            spectral: std::array::from_fn(|c| cook(&tb.sky_params_spec, &tb.sky_rad_spec, N_WL, c, t, a, x)),
        }
    }

    /// The same sky with every channel's radiance times `factor` (L_M scales L linearly): the
    /// twilight fade.
    pub fn scaled(mut self, factor: f32) -> Self {
        for ch in self.rgb.iter_mut().chain(self.spectral.iter_mut()) {
            ch.radiance *= factor;
        }
        self
    }

    /// Photometric linear sRGB radiance, nit, toward unit `w` for a sun toward unit `sun`; zero
    /// below the horizon (w.y <= 0), where the model is not defined.
    pub fn rgb_nits(&self, w: Vec3, sun: Vec3) -> Vec3 {
        self.rgb_nits_in_row(&self.rgb_row(w.y), w, sun)
    }

    /// What [`Self::rgb_nits`] computes from the zenith angle alone, for directions of zenith
    /// cosine `cos_theta`: a lat-long row's share, computed once for the row.
    pub fn rgb_row(&self, cos_theta: f32) -> RgbRow {
        let c = cos_theta.clamp(0.0, 1.0);
        RgbRow { dome: Vec3::from_array(self.rgb.map(|ch| ch.dome(c))) * K_M as f32, sqrt_cos_theta: c.sqrt() }
    }

    /// [`Self::rgb_nits`] toward `w`, whose zenith cosine `row` was made for.
    #[inline]
    pub fn rgb_nits_in_row(&self, row: &RgbRow, w: Vec3, sun: Vec3) -> Vec3 {
        let Some((_, gamma, cos_gamma)) = angles(w, sun) else { return Vec3::ZERO };
        let circ = Vec3::from_array(self.rgb.map(|ch| ch.circumsolar(row.sqrt_cos_theta, gamma, cos_gamma)));
        (row.dome * circ).max(Vec3::ZERO)
    }

    /// Spectral radiance, W/(m^2 sr nm), at `lambda` nm toward `w`: linear between the model's
    /// wavelengths, held beyond them; zero below the horizon.
    pub fn spectral(&self, lambda: f32, w: Vec3, sun: Vec3) -> f32 {
        let Some((cos_theta, gamma, cos_gamma)) = angles(w, sun) else { return 0.0 };
        let (i, f) = wavelength_cell(lambda);
        let lo = self.spectral[i].eval(cos_theta, gamma, cos_gamma);
        let v = if f > 0.0 { lo + f * (self.spectral[i + 1].eval(cos_theta, gamma, cos_gamma) - lo) } else { lo };
        v.max(0.0)
    }
}

/// The zenith-angle factors of the RGB sky for one zenith cosine (see [`SkyModel::rgb_row`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbRow {
    /// (1 + A e^(B / (cos theta + 0.01))) L_M per channel, times 683 (nit).
    pub dome: Vec3,
    /// Square root of the zenith cosine (clamped to [0, 1]), for the circumsolar factor.
    pub sqrt_cos_theta: f32,
}

/// (cos theta, gamma, cos gamma) of view `w` and sun `sun` (both unit), None below the horizon.
#[inline]
fn angles(w: Vec3, sun: Vec3) -> Option<(f32, f32, f32)> {
    if !(w.y > 0.0) {
        return None;
    }
    let cos_gamma = w.dot(sun).clamp(-1.0, 1.0);
    // gamma from atan2 of the cross product keeps its digits near the sun, where acos does not.
    let gamma = w.cross(sun).length().atan2(cos_gamma);
    Some((w.y.min(1.0), gamma, cos_gamma))
}

/// The model-wavelength cell of `lambda`: index i in 0..10 and the fraction toward i + 1
/// (0 beyond the ends, which hold their values).
#[inline]
pub fn wavelength_cell(lambda: f32) -> (usize, f32) {
    let t = ((lambda - WAVELENGTHS_NM[0]) / 40.0).clamp(0.0, (N_WL - 1) as f32);
    let i = (t.floor() as usize).min(N_WL - 2);
    (i, t - i as f32)
}

/// The solar disc for one sun elevation and turbidity: the radiance at the disc centre per model
/// wavelength and the limb-darkening polynomials (Hosek and Wilkie 2013).
#[derive(Clone, Debug, PartialEq)]
pub struct SunModel {
    /// Spectral radiance at the centre of the disc, W/(m^2 sr nm), at [`WAVELENGTHS_NM`].
    pub radiance: [f32; 11],
    /// Limb darkening per model wavelength: L(mu) / L(1) = sum_k c_k mu^k, mu the cosine of the
    /// angle between the line of sight and the solar surface normal.
    pub limb: [[f32; 6]; 11],
}

impl SunModel {
    /// The sun at elevation `elevation` (radians, clamped to [0, pi/2]) and `turbidity` (clamped
    /// to [1, 10]). The 2013 model evaluates the elevation of each point of the disc; kelvin takes
    /// the centre's for the whole disc, so the disc's radiance is separable in (lambda, mu).
    pub fn new(elevation: f32, turbidity: f32) -> Self {
        let e = if elevation.is_nan() { 0.0 } else { elevation.clamp(0.0, std::f32::consts::FRAC_PI_2) } as f64;
        let t = if turbidity.is_nan() { 1.0 } else { turbidity.clamp(1.0, 10.0) } as f64;
        let tb = &*TABLES;
        // Piecewise cubic in elevation over 45 pieces with breaks at (k / 45)^3 pi/2.
        let pos = (((2.0 * e / std::f64::consts::PI).cbrt() * SUN_PIECES as f64) as usize).min(SUN_PIECES - 1);
        let x = e - (pos as f64 / SUN_PIECES as f64).powi(3) * std::f64::consts::FRAC_PI_2;
        let radiance = std::array::from_fn(|wl| {
            let piece = |ti: usize| -> f64 {
                let base = ((ti * SUN_PIECES + pos) * N_WL + wl) * SUN_ORDER;
                let c = &tb.sun_rad_spec[base..base + SUN_ORDER];
                c[0] + x * (c[1] + x * (c[2] + x * c[3]))
            };
            turbidity_weights(t).iter().map(|&(ti, w)| if w == 0.0 { 0.0 } else { w * piece(ti) }).sum::<f64>() as f32
        });
        let limb = std::array::from_fn(|wl| std::array::from_fn(|k| tb.sun_ld_spec[wl * 6 + k] as f32));
        Self { radiance, limb }
    }

    /// Spectral radiance, W/(m^2 sr nm), at `lambda` nm and limb cosine `mu` in [0, 1]: both the
    /// centre radiance and the limb coefficients linear between model wavelengths (as the
    /// authors' code), held beyond them.
    pub fn spectral(&self, lambda: f32, mu: f32) -> f32 {
        let (i, f) = wavelength_cell(lambda);
        let lerp = |a: f32, b: f32| a + f * (b - a);
        let centre = lerp(self.radiance[i], self.radiance[i + 1]);
        let mu = mu.clamp(0.0, 1.0);
        let mut darkening = 0.0;
        for k in (0..6).rev() {
            darkening = darkening * mu + lerp(self.limb[i][k], self.limb[i + 1][k]);
        }
        (centre * darkening).max(0.0)
    }
}
