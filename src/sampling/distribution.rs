//! Piecewise-constant distributions in 1D and 2D (pbrt-v4 §A.4.4-A.4.5): sample a tabulated
//! function (an environment map, a goniometric profile) in proportion to its value.
//!
//! The CDF is accumulated and stored in f64, so a table with one value of 1e9 (the sun's pixel)
//! among values of ~1 keeps the mass of the rest: in f32, 1e9 + 1 == 1e9 and every bin after the
//! sun would get probability 0 while its pdf says otherwise. (A sample `u` is still an f32: a bin
//! whose probability is below its ~6e-8 spacing is hit only as often as the f32 grid allows.)

use glam::Vec2;
use rayon::prelude::*;

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

/// One row of bins borrowed from a [`PiecewiseConstant1D`] or a row of a [`PiecewiseConstant2D`]:
/// the sampling, density and inversion of both, written once.
#[derive(Clone, Copy, Debug)]
pub struct Bins<'a> {
    func: &'a [f32],
    cdf: &'a [f64],
    integral: f64,
    min: f32,
    max: f32,
}

/// Turns a row's raw values, held in `cdf[1..]` on entry, into its sanitised `func` and normalised
/// `cdf`; returns the sum of the values. Values in the cdf slot keep the row in one cache-resident
/// buffer and let 2D rows and the f64 marginal share this code. `func.len() + 1 == cdf.len()`.
fn finish_bins(func: &mut [f32], cdf: &mut [f64]) -> f64 {
    let n = func.len();
    cdf[0] = 0.0;
    let mut sum = 0.0f64;
    for i in 0..n {
        let v = cdf[i + 1];
        let v = if v.is_nan() { 0.0 } else { v.abs().min(f32::MAX as f64) };
        func[i] = v as f32;
        sum += v;
        cdf[i + 1] = sum;
    }
    if sum > 0.0 {
        cdf.iter_mut().for_each(|c| *c /= sum);
        // Trailing zero bins already end at sum / sum == 1 exactly; make sure the last does.
        cdf[n] = 1.0;
    } else {
        cdf.iter_mut().enumerate().for_each(|(i, c)| *c = i as f64 / n as f64);
    }
    sum
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
        let mut d = Self { func: Vec::new(), cdf: Vec::new(), integral: 0.0, min, max };
        d.rebuild(values, len);
        d
    }

    /// [`Self::build`] into the existing buffers.
    fn rebuild(&mut self, values: impl Iterator<Item = f64>, len: usize) {
        let n = len.max(1);
        self.cdf.clear();
        self.cdf.push(0.0);
        self.cdf.extend(values.take(n));
        self.cdf.resize(n + 1, 0.0);
        self.func.resize(n, 0.0);
        let sum = finish_bins(&mut self.func, &mut self.cdf);
        self.integral = sum * (self.max as f64 - self.min as f64) / n as f64;
    }

    fn bins(&self) -> Bins<'_> {
        Bins { func: &self.func, cdf: &self.cdf, integral: self.integral, min: self.min, max: self.max }
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

    /// Samples x with density f(x) / integral; returns (x, pdf, bin offset). Only bins with
    /// f > 0 are ever returned (unless all are 0, when sampling is uniform).
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        self.bins().sample(u)
    }

    /// Density at x; 0 outside the domain.
    pub fn pdf(&self, x: f32) -> f32 {
        self.bins().pdf(x)
    }

    /// The u that [`Self::sample`] maps to x; None outside the domain or where the density is 0
    /// (no u maps there).
    pub fn invert(&self, x: f32) -> Option<f32> {
        self.bins().invert(x)
    }
}

impl<'a> Bins<'a> {
    /// Integral of |f| over the domain (0 for an all-zero row).
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
    pub fn func(&self) -> &'a [f32] {
        self.func
    }

    /// The normalised CDF at the `len() + 1` bin edges, from 0 to 1.
    pub fn cdf(&self) -> &'a [f64] {
        self.cdf
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

    /// As [`PiecewiseConstant1D::sample`].
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

    /// As [`PiecewiseConstant1D::pdf`].
    pub fn pdf(&self, x: f32) -> f32 {
        self.offset_of(x).map_or(0.0, |(o, _)| self.density(o))
    }

    /// As [`PiecewiseConstant1D::invert`].
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
///
/// The rows live in two flat buffers (`func`: nu per row, `cdf`: nu + 1 per row) so that they can
/// be built in parallel, rebuilt in part ([`Self::fill_rows`]) and reused across rebuilds.
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseConstant2D {
    nu: usize,
    nv: usize,
    func: Vec<f32>,
    cdf: Vec<f64>,
    /// Per row, the integral of |f| over [min.x, max.x].
    row_integral: Vec<f64>,
    marginal: PiecewiseConstant1D,
    min: Vec2,
    max: Vec2,
}

/// A block of consecutive rows of a [`PiecewiseConstant2D`] being filled by [`PiecewiseConstant2D::fill_rows`].
pub struct RowBlock<'a> {
    /// The index of the block's first row.
    pub first_row: usize,
    nu: usize,
    cdf: &'a mut [f64],
}

impl RowBlock<'_> {
    /// Number of rows in the block.
    pub fn rows(&self) -> usize {
        self.cdf.len() / (self.nu + 1)
    }

    /// The raw values (|f| is taken later) of the block's row `i`, `nu` of them, to be written.
    pub fn values(&mut self, i: usize) -> &mut [f64] {
        let s = i * (self.nu + 1);
        &mut self.cdf[s + 1..s + self.nu + 1]
    }
}

/// Rows per parallel task: enough to amortise a task, few enough to split 2 x 1024 rows evenly.
const ROWS_PER_TASK: usize = 16;

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
        let mut d = Self::zeros(nu, nv, min, max);
        let nu = d.nu;
        Self::fill_rows(&mut [&mut d], 0..nv, |blocks| {
            let [block] = blocks else { return };
            for i in 0..block.rows() {
                let v = block.first_row + i;
                for (x, out) in block.values(i).iter_mut().enumerate() {
                    *out = *func.get(v * nu + x).unwrap_or(&0.0) as f64;
                }
            }
        });
        d
    }

    /// An all-zero `nu` x `nv` distribution (samples uniformly) over [`min`, `max`], to be filled
    /// by [`Self::fill_rows`]; `nu` or `nv` of 0 count as 1, a bad domain as [0, 1]^2.
    pub fn zeros(nu: usize, nv: usize, min: Vec2, max: Vec2) -> Self {
        let (min, max) =
            if valid_domain(min.x, max.x) && valid_domain(min.y, max.y) { (min, max) } else { (Vec2::ZERO, Vec2::ONE) };
        let mut d = Self {
            nu: 0,
            nv: 0,
            func: Vec::new(),
            cdf: Vec::new(),
            row_integral: Vec::new(),
            marginal: PiecewiseConstant1D::build(std::iter::empty(), 1, min.y, max.y),
            min,
            max,
        };
        d.reset(nu, nv);
        d
    }

    /// Resizes to `nu` x `nv` all-zero rows, keeping the buffers' memory (0 counts as 1).
    pub fn reset(&mut self, nu: usize, nv: usize) {
        let (nu, nv) = (nu.max(1), nv.max(1));
        (self.nu, self.nv) = (nu, nv);
        self.func.clear();
        self.func.resize(nu * nv, 0.0);
        self.cdf.clear();
        self.cdf.resize((nu + 1) * nv, 0.0);
        self.row_integral.clear();
        self.row_integral.resize(nv, 0.0);
        self.cdf.par_chunks_mut(nu + 1).zip(self.func.par_chunks_mut(nu)).for_each(|(c, f)| {
            finish_bins(f, c);
        });
        self.finish_marginal();
    }

    /// Refills `rows` (clamped to the grid) of every distribution in `dists` in parallel: `fill`
    /// writes each row's raw values through [`RowBlock::values`] (the same blocks of every
    /// distribution at once, so one pass over the source serves them all), then each row's CDF
    /// and the marginal are rebuilt. Rows outside `rows` are kept. Every distribution must have
    /// the grid of the first; one that does not is left unchanged.
    pub fn fill_rows(dists: &mut [&mut Self], rows: std::ops::Range<usize>, fill: impl Fn(&mut [RowBlock]) + Sync) {
        let Some((nu, nv)) = dists.first().map(|d| (d.nu, d.nv)) else { return };
        let (lo, hi) = (rows.start.min(nv), rows.end.min(nv));
        let same: Vec<bool> = dists.iter().map(|d| (d.nu, d.nv) == (nu, nv)).collect();
        // Per distribution, its blocks of ROWS_PER_TASK rows; then regrouped block by block.
        let mut per_dist: Vec<_> = dists
            .iter_mut()
            .zip(&same)
            .filter(|(_, s)| **s)
            .map(|(d, _)| {
                let d = &mut **d;
                let span = d.max.x as f64 - d.min.x as f64;
                let (f, c, r) = (
                    &mut d.func[lo * nu..hi * nu],
                    &mut d.cdf[lo * (nu + 1)..hi * (nu + 1)],
                    &mut d.row_integral[lo..hi],
                );
                let k = ROWS_PER_TASK;
                let blocks = f.chunks_mut(k * nu).zip(c.chunks_mut(k * (nu + 1))).zip(r.chunks_mut(k));
                blocks.map(move |b| (span, b)).enumerate().collect::<Vec<_>>().into_iter()
            })
            .collect();
        let mut tasks = Vec::new();
        while let Some(block) = per_dist.iter_mut().map(|it| it.next()).collect::<Option<Vec<_>>>() {
            if block.is_empty() {
                break;
            }
            tasks.push(block);
        }
        tasks.into_par_iter().for_each(|mut block| {
            let first_row = lo + block[0].0 * ROWS_PER_TASK;
            let mut views: Vec<RowBlock> =
                block.iter_mut().map(|(_, (_, ((_, c), _)))| RowBlock { first_row, nu, cdf: &mut **c }).collect();
            fill(&mut views);
            drop(views);
            for (_, (span, ((f, c), r))) in block.iter_mut() {
                for ((f, c), r) in f.chunks_mut(nu).zip(c.chunks_mut(nu + 1)).zip(r.iter_mut()) {
                    *r = finish_bins(f, c) * *span / nu as f64;
                }
            }
        });
        for (d, _) in dists.iter_mut().zip(&same).filter(|(_, s)| **s) {
            d.finish_marginal();
        }
    }

    fn finish_marginal(&mut self) {
        let Self { marginal, row_integral, nv, .. } = self;
        marginal.rebuild(row_integral.iter().copied(), *nv);
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
        [self.nu, self.nv]
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
    pub fn conditional(&self, v: usize) -> Option<Bins<'_>> {
        (v < self.nv).then(|| Bins {
            func: &self.func[v * self.nu..(v + 1) * self.nu],
            cdf: &self.cdf[v * (self.nu + 1)..(v + 1) * (self.nu + 1)],
            integral: self.row_integral[v],
            min: self.min.x,
            max: self.max.x,
        })
    }

    fn row(&self, v: usize) -> Bins<'_> {
        self.conditional(v.min(self.nv - 1)).unwrap_or(self.marginal.bins())
    }

    /// Samples a point with density f / integral; returns (point, pdf, [u bin, v bin]).
    pub fn sample(&self, u: Vec2) -> (Vec2, f32, [usize; 2]) {
        let (y, pdf_v, iv) = self.marginal.sample(u.y);
        let (x, pdf_u, iu) = self.row(iv).sample(u.x);
        (Vec2::new(x, y), pdf_u * pdf_v, [iu, iv])
    }

    /// Density at `p`; 0 outside the domain.
    pub fn pdf(&self, p: Vec2) -> f32 {
        let (Some((iu, _)), Some((iv, _))) = (self.row(0).offset_of(p.x), self.marginal.bins().offset_of(p.y)) else {
            return 0.0;
        };
        if self.marginal.integral > 0.0 {
            (self.func[iv * self.nu + iu] as f64 / self.marginal.integral) as f32
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
        let (iv, _) = self.marginal.bins().offset_of(p.y)?;
        let u = self.row(iv).invert(p.x)?;
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
