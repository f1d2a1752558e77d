//! Piecewise-constant distributions in 1D and 2D (pbrt-v4 §A.4.4-A.4.5): sample a tabulated
//! function (an environment map, a goniometric profile) in proportion to its value.
//!
//! The CDF is accumulated and stored in f64, so a table with one value of 1e9 (the sun's pixel)
//! among values of ~1 keeps the mass of the rest: in f32, 1e9 + 1 == 1e9 and every bin after the
//! sun would get probability 0 while its pdf says otherwise. (A sample `u` is still an f32: a bin
//! whose probability is below its ~6e-8 spacing is hit only as often as the f32 grid allows.)

use glam::Vec2;

use super::SamplingError;

/// A piecewise-constant density over [min, max] proportional to |f| on equal-width bins.
///
/// Invariants: at least one bin; `func` holds |f| with NaN replaced by 0 and +inf by `f32::MAX`;
/// `cdf` has `len() + 1` entries rising from exactly 0 to exactly 1. An all-zero function samples
/// uniformly (pdf 1 / (max - min)) so that sampling never divides by zero; its `integral()` is 0.
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseConstant1D {
    func: Vec<f32>,
    cdf: Vec<f64>,
    /// Integral of |f| over [min, max].
    integral: f64,
    min: f32,
    max: f32,
}

impl PiecewiseConstant1D {
    /// The distribution of |`func`| over [`min`, `max`]. For tables from data prefer [`Self::try_new`]:
    /// here an empty `func` counts as one zero bin, and a domain that is not finite with
    /// `min < max` is replaced by [0, 1].
    pub fn new(func: &[f32], min: f32, max: f32) -> Self {
        let (min, max) = if valid_domain(min, max) { (min, max) } else { (0.0, 1.0) };
        Self::build(func.iter().map(|&v| v as f64), func.len(), min, max)
    }

    /// As [`Self::new`], but an empty `func` or a bad domain is an error.
    pub fn try_new(func: &[f32], min: f32, max: f32) -> Result<Self, SamplingError> {
        if func.is_empty() {
            return Err(SamplingError::Empty { what: "PiecewiseConstant1D function" });
        }
        if !valid_domain(min, max) {
            return Err(SamplingError::BadDomain { what: "PiecewiseConstant1D", min, max });
        }
        Ok(Self::new(func, min, max))
    }

    /// Builds from f64 values (the 2D marginal passes its row integrals unrounded).
    fn build(values: impl Iterator<Item = f64>, len: usize, min: f32, max: f32) -> Self {
        let n = len.max(1);
        let mut func = Vec::with_capacity(n);
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0);
        let mut sum = 0.0f64;
        for v in values {
            let v = if v.is_nan() { 0.0 } else { v.abs().min(f32::MAX as f64) };
            func.push(v as f32);
            sum += v;
            cdf.push(sum);
        }
        if func.is_empty() {
            func.push(0.0);
            cdf.push(0.0);
        }
        if sum > 0.0 {
            cdf.iter_mut().for_each(|c| *c /= sum);
            // Trailing zero bins already end at sum / sum == 1 exactly; make sure the last does.
            cdf[n] = 1.0;
        } else {
            cdf.iter_mut().enumerate().for_each(|(i, c)| *c = i as f64 / n as f64);
        }
        let integral = sum * (max as f64 - min as f64) / n as f64;
        Self { func, cdf, integral, min, max }
    }

    /// Integral of |f| over the domain (0 for an all-zero function).
    pub fn integral(&self) -> f32 {
        self.integral as f32
    }

    /// Number of bins (at least 1).
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Always false: there is at least one bin.
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// The stored |f| per bin.
    pub fn func(&self) -> &[f32] {
        &self.func
    }

    /// The normalised CDF at the `len() + 1` bin edges, from 0 to 1.
    pub fn cdf(&self) -> &[f64] {
        &self.cdf
    }

    /// The domain (min, max).
    pub fn domain(&self) -> (f32, f32) {
        (self.min, self.max)
    }

    fn width(&self) -> f64 {
        self.max as f64 - self.min as f64
    }

    fn density(&self, offset: usize) -> f32 {
        if self.integral > 0.0 {
            (self.func[offset] as f64 / self.integral) as f32
        } else {
            (1.0 / self.width()) as f32
        }
    }

    /// Samples x with density f(x) / integral; returns (x, pdf, bin offset). Only bins with
    /// f > 0 are ever returned (unless all are 0, when sampling is uniform).
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        // u < 1 keeps us inside a bin of positive width: cdf[o] <= u < cdf[o + 1].
        let u = (u as f64).clamp(0.0, 1.0 - f64::EPSILON / 2.0);
        let n = self.len();
        let offset = (self.cdf.partition_point(|&c| c <= u) - 1).min(n - 1);
        let (c0, c1) = (self.cdf[offset], self.cdf[offset + 1]);
        let du = if c1 > c0 { ((u - c0) / (c1 - c0)).clamp(0.0, 1.0) } else { 0.0 };
        let x = self.min as f64 + (offset as f64 + du) / n as f64 * self.width();
        ((x as f32).clamp(self.min, self.max), self.density(offset), offset)
    }

    fn offset_of(&self, x: f32) -> Option<(usize, f64)> {
        if !(self.min..=self.max).contains(&x) {
            return None;
        }
        let n = self.len();
        let c = (x as f64 - self.min as f64) / self.width() * n as f64;
        let offset = (c as usize).min(n - 1);
        Some((offset, (c - offset as f64).clamp(0.0, 1.0)))
    }

    /// Density at x; 0 outside the domain.
    pub fn pdf(&self, x: f32) -> f32 {
        self.offset_of(x).map_or(0.0, |(o, _)| self.density(o))
    }

    /// The u that [`Self::sample`] maps to x; None outside the domain or where the density is 0
    /// (no u maps there).
    pub fn invert(&self, x: f32) -> Option<f32> {
        let (o, delta) = self.offset_of(x)?;
        if self.pdf(x) <= 0.0 {
            return None;
        }
        let u = self.cdf[o] + delta * (self.cdf[o + 1] - self.cdf[o]);
        Some(u as f32)
    }
}

fn valid_domain(min: f32, max: f32) -> bool {
    min.is_finite() && max.is_finite() && min < max
}

/// A piecewise-constant density over a rectangle (by default [0, 1]^2) proportional to |f| on an
/// `nu` x `nv` grid: a marginal over v of row integrals, and one conditional over u per row.
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseConstant2D {
    conditional: Vec<PiecewiseConstant1D>,
    marginal: PiecewiseConstant1D,
    min: Vec2,
    max: Vec2,
}

impl PiecewiseConstant2D {
    /// The distribution of |`func`| over [0, 1]^2; `func` is row-major: `nv` rows of `nu` values,
    /// row v covering y in [v / nv, (v + 1) / nv]. For tables from data prefer [`Self::try_new`]:
    /// here `nu` or `nv` of 0 count as 1, missing values as 0, and extra values are ignored.
    pub fn new(func: &[f32], nu: usize, nv: usize) -> Self {
        Self::with_domain(func, nu, nv, Vec2::ZERO, Vec2::ONE)
    }

    /// As [`Self::new`] over the rectangle [`min`, `max`] (replaced by [0, 1]^2 unless finite with
    /// min < max on both axes).
    pub fn with_domain(func: &[f32], nu: usize, nv: usize, min: Vec2, max: Vec2) -> Self {
        let (nu, nv) = (nu.max(1), nv.max(1));
        let (min, max) =
            if valid_domain(min.x, max.x) && valid_domain(min.y, max.y) { (min, max) } else { (Vec2::ZERO, Vec2::ONE) };
        let row = |v: usize| (0..nu).map(move |i| *func.get(v * nu + i).unwrap_or(&0.0) as f64);
        let conditional: Vec<_> = (0..nv).map(|v| PiecewiseConstant1D::build(row(v), nu, min.x, max.x)).collect();
        let marginal = PiecewiseConstant1D::build(conditional.iter().map(|c| c.integral), nv, min.y, max.y);
        Self { conditional, marginal, min, max }
    }

    /// As [`Self::with_domain`], but a wrong-sized `func` or a bad domain is an error.
    pub fn try_new(func: &[f32], nu: usize, nv: usize, min: Vec2, max: Vec2) -> Result<Self, SamplingError> {
        if nu == 0 || nv == 0 || nu.checked_mul(nv) != Some(func.len()) {
            return Err(SamplingError::BadGrid { what: "PiecewiseConstant2D", len: func.len(), nu, nv });
        }
        for (lo, hi) in [(min.x, max.x), (min.y, max.y)] {
            if !valid_domain(lo, hi) {
                return Err(SamplingError::BadDomain { what: "PiecewiseConstant2D", min: lo, max: hi });
            }
        }
        Ok(Self::with_domain(func, nu, nv, min, max))
    }

    /// Integral of |f| over the domain.
    pub fn integral(&self) -> f32 {
        self.marginal.integral()
    }

    /// Grid size [nu, nv].
    pub fn resolution(&self) -> [usize; 2] {
        [self.conditional[0].len(), self.conditional.len()]
    }

    /// The domain (min, max).
    pub fn domain(&self) -> (Vec2, Vec2) {
        (self.min, self.max)
    }

    /// The marginal distribution over v (of row integrals).
    pub fn marginal(&self) -> &PiecewiseConstant1D {
        &self.marginal
    }

    /// The conditional distribution over u in row `v`, if that row exists.
    pub fn conditional(&self, v: usize) -> Option<&PiecewiseConstant1D> {
        self.conditional.get(v)
    }

    /// Samples a point with density f / integral; returns (point, pdf, [u bin, v bin]).
    pub fn sample(&self, u: Vec2) -> (Vec2, f32, [usize; 2]) {
        let (y, pdf_v, iv) = self.marginal.sample(u.y);
        let (x, pdf_u, iu) = self.conditional[iv].sample(u.x);
        (Vec2::new(x, y), pdf_u * pdf_v, [iu, iv])
    }

    /// Density at `p`; 0 outside the domain.
    pub fn pdf(&self, p: Vec2) -> f32 {
        let (Some((iu, _)), Some((iv, _))) = (self.conditional[0].offset_of(p.x), self.marginal.offset_of(p.y)) else {
            return 0.0;
        };
        if self.marginal.integral > 0.0 {
            (self.conditional[iv].func[iu] as f64 / self.marginal.integral) as f32
        } else {
            let area = (self.max.x as f64 - self.min.x as f64) * (self.max.y as f64 - self.min.y as f64);
            (1.0 / area) as f32
        }
    }

    /// The unit-square sample that [`Self::sample`] maps to `p`; None outside the domain or where
    /// the density is 0.
    pub fn invert(&self, p: Vec2) -> Option<Vec2> {
        if self.pdf(p) <= 0.0 {
            return None;
        }
        let v = self.marginal.invert(p.y)?;
        let (iv, _) = self.marginal.offset_of(p.y)?;
        let u = self.conditional[iv].invert(p.x)?;
        Some(Vec2::new(u, v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn negative_and_nan_values_count_as_their_magnitude_and_zero() {
        let d = PiecewiseConstant1D::new(&[-2.0, f32::NAN, 2.0], 0.0, 3.0);
        assert_eq!(d.func(), &[2.0, 0.0, 2.0]);
        assert_eq!(d.integral(), 4.0);
        assert_eq!(d.pdf(1.5), 0.0);
        assert_eq!(d.pdf(0.5), 0.5);
        assert!(d.invert(1.5).is_none());
    }

    #[test]
    fn all_zero_function_samples_uniformly_with_finite_pdf() {
        let d = PiecewiseConstant1D::new(&[0.0; 4], -1.0, 1.0);
        assert_eq!(d.integral(), 0.0);
        let (x, pdf, o) = d.sample(0.6);
        assert!((x - 0.2).abs() < 1e-6 && pdf == 0.5 && o == 2, "{x} {pdf} {o}");
        let d2 = PiecewiseConstant2D::new(&[0.0; 6], 3, 2);
        let (_, pdf2, _) = d2.sample(Vec2::new(0.3, 0.9));
        assert_eq!(pdf2, 1.0);
        assert_eq!(d2.pdf(Vec2::new(0.3, 0.9)), 1.0);
    }

    #[test]
    fn zero_bins_are_never_sampled_even_at_their_cdf_edges() {
        let d = PiecewiseConstant1D::new(&[0.0, 1.0, 0.0, 0.0, 3.0, 0.0], 0.0, 1.0);
        for u in [0.0, 0.25, 0.2500001, 0.9999999, 1.0, 0.5] {
            let (_, pdf, o) = d.sample(u);
            assert!(d.func()[o] > 0.0 && pdf > 0.0, "u = {u} gave bin {o}");
        }
    }

    #[test]
    fn bad_input_is_an_error_from_try_new() {
        assert!(matches!(PiecewiseConstant1D::try_new(&[], 0.0, 1.0), Err(SamplingError::Empty { .. })));
        assert!(matches!(PiecewiseConstant1D::try_new(&[1.0], 1.0, 1.0), Err(SamplingError::BadDomain { .. })));
        let err = PiecewiseConstant2D::try_new(&[1.0; 5], 2, 3, Vec2::ZERO, Vec2::ONE).unwrap_err();
        assert!(err.to_string().contains("5 values given for a 2 x 3 grid"), "{err}");
        // new() stays usable on the same input.
        assert_eq!(PiecewiseConstant1D::new(&[], 0.0, 1.0).len(), 1);
        assert_eq!(PiecewiseConstant2D::new(&[1.0; 5], 2, 3).resolution(), [2, 3]);
    }
}
