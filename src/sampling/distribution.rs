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
#[inline(always)]
fn finish_bins(func: &mut [f32], cdf: &mut [f64]) -> f64 {
    let n = func.len();
    cdf[0] = 0.0;
    // Three loops rather than one: the first and last vectorise; only the running sum is serial.
    for (f, c) in func.iter_mut().zip(&mut cdf[1..]) {
        let v = if c.is_nan() { 0.0 } else { c.abs().min(f32::MAX as f64) };
        *f = v as f32;
        *c = v;
    }
    let sum = prefix_sum(&mut cdf[1..]);
    if sum > 0.0 {
        // Multiplying is monotone, so the CDF still rises; min(1) keeps it within [0, 1].
        let inv = 1.0 / sum;
        cdf.iter_mut().for_each(|c| *c = (*c * inv).min(1.0));
        // From the end of the last nonzero bin on, exactly 1: trailing zero bins are never hit.
        let last = func.iter().rposition(|&f| f > 0.0).unwrap_or(n - 1);
        cdf[last + 1..].fill(1.0);
    } else {
        cdf.iter_mut().enumerate().for_each(|(i, c)| *c = i as f64 / n as f64);
    }
    sum
}

/// In-place inclusive prefix sum in f64; returns the total. Four interleaved segments, each a
/// serial running sum, then each segment offset by the totals before it: four add chains in
/// flight instead of one (the serial sum is bound by the add latency), with the same error bound.
#[inline(always)]
fn prefix_sum(v: &mut [f64]) -> f64 {
    const K: usize = 4;
    let seg = v.len() / K;
    if seg < 16 {
        let mut sum = 0.0;
        v.iter_mut().for_each(|x| {
            sum += *x;
            *x = sum;
        });
        return sum;
    }
    let (head, tail) = v.split_at_mut(seg * K);
    let mut acc = [0.0f64; K];
    for i in 0..seg {
        for (k, a) in acc.iter_mut().enumerate() {
            *a += head[k * seg + i];
            head[k * seg + i] = *a;
        }
    }
    let mut offset = 0.0;
    for (k, chunk) in head.chunks_mut(seg).enumerate() {
        if k > 0 {
            chunk.iter_mut().for_each(|x| *x += offset);
        }
        offset += acc[k];
    }
    for x in tail {
        offset += *x;
        *x = offset;
    }
    offset
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

/// Rows per parallel task: enough to amortise a task (and a filter's halo rows), few enough to
/// split 1024 rows evenly over the cores.
const ROWS_PER_TASK: usize = 32;

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
        Self::fill_rows(
            &mut [&mut d],
            0..nv,
            |_| (),
            |_, v, rows| {
                for (x, out) in rows[0].iter_mut().enumerate() {
                    *out = *func.get(v * nu + x).unwrap_or(&0.0) as f64;
                }
            },
        );
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

    /// Refills `rows` (clamped to the grid) of every distribution in `dists` in parallel, in
    /// tasks of consecutive rows: `init(rows)` makes a task's state, then `fill(state, row,
    /// values)` writes each row's raw values (|f| is taken after), one slice of `nu` per
    /// distribution, so that one pass over a source serves them all; each row's CDF is built
    /// while the row is in cache, and the marginals at the end. Rows outside `rows` are kept.
    /// Every distribution must have the grid of the first; one that does not is left unchanged.
    pub fn fill_rows<S>(
        dists: &mut [&mut Self],
        rows: std::ops::Range<usize>,
        init: impl Fn(std::ops::Range<usize>) -> S + Sync,
        fill: impl Fn(&mut S, usize, &mut [&mut [f64]]) + Sync,
    ) {
        let Some((nu, nv)) = dists.first().map(|d| (d.nu, d.nv)) else { return };
        let (lo, hi) = (rows.start.min(nv), rows.end.min(nv));
        // Per distribution, its tasks' rows; then regrouped task by task.
        let k = ROWS_PER_TASK;
        let mut per_dist: Vec<_> = dists
            .iter_mut()
            .filter(|d| (d.nu, d.nv) == (nu, nv))
            .map(|d| {
                let d = &mut **d;
                let span = d.max.x as f64 - d.min.x as f64;
                let f = d.func[lo * nu..hi * nu].chunks_mut(k * nu);
                let c = d.cdf[lo * (nu + 1)..hi * (nu + 1)].chunks_mut(k * (nu + 1));
                let r = d.row_integral[lo..hi].chunks_mut(k);
                f.zip(c).zip(r).map(move |((f, c), r)| (span, f, c, r)).collect::<Vec<_>>().into_iter()
            })
            .collect();
        let mut tasks = Vec::new();
        while let Some(task) = per_dist.iter_mut().map(|it| it.next()).collect::<Option<Vec<_>>>() {
            if task.is_empty() {
                break;
            }
            tasks.push(task);
        }
        // Each task's rows compiled for the widest instruction set: `fill` and the row finish
        // are inlined into it (see `lanes::widest`).
        tasks.into_par_iter().enumerate().for_each(|(t, mut task)| {
            crate::lanes::widest(
                #[inline(always)]
                || {
                    let first = lo + t * k;
                    let n = task[0].3.len();
                    let mut state = init(first..first + n);
                    for i in 0..n {
                        let mut values: Vec<&mut [f64]> =
                            task.iter_mut().map(|(_, _, c, _)| &mut c[i * (nu + 1) + 1..(i + 1) * (nu + 1)]).collect();
                        fill(&mut state, first + i, &mut values);
                        drop(values);
                        for (span, f, c, r) in task.iter_mut() {
                            let row = i * (nu + 1)..(i + 1) * (nu + 1);
                            let sum = finish_bins(&mut f[i * nu..(i + 1) * nu], &mut c[row]);
                            r[i] = sum * *span / nu as f64;
                        }
                    }
                },
            )
        });
        drop(per_dist);
        for d in dists.iter_mut().filter(|d| (d.nu, d.nv) == (nu, nv)) {
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
