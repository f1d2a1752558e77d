//! Piecewise-constant distributions in 1D and 2D (pbrt-v4 §A.4.4-A.4.5): sample a tabulated
//! function (an environment map, a goniometric profile) in proportion to its value.
//!
//! The CDF is accumulated in f64, so a table with one value of 1e9 (the sun's pixel) among
//! values of ~1 keeps the mass of the rest: in f32, 1e9 + 1 == 1e9 and every bin after the sun
//! would get probability 0. 1D CDFs are stored in f64; a 2D table's rows are stored in f32 where
//! that keeps every nonzero bin's width positive, in f64 where it does not (distribution_2d.rs).
//! A bin's density is its CDF width, so the pdf is the density sampled, whichever the storage.
//! (A sample `u` is still an f32: a bin whose probability is below its ~6e-8 spacing is hit only
//! as often as the f32 grid allows.)

use super::SamplingError;
use crate::lanes::LANES;

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
    pub(super) integral: f64,
    min: f32,
    max: f32,
}

/// One row of bins borrowed from a [`PiecewiseConstant1D`] or a row of a
/// [`PiecewiseConstant2D`](super::PiecewiseConstant2D): the sampling, density and inversion of
/// both, written once.
#[derive(Clone, Copy, Debug)]
pub struct Bins<'a> {
    pub(super) edges: Edges<'a>,
    pub(super) integral: f64,
    pub(super) min: f32,
    pub(super) max: f32,
}

/// A row's normalised CDF at its bin edges, as stored.
#[derive(Clone, Copy, Debug)]
pub(super) enum Edges<'a> {
    Wide(&'a [f64]),
    Narrow(&'a [f32]),
}

impl Edges<'_> {
    #[inline(always)]
    fn at(&self, i: usize) -> f64 {
        match self {
            Edges::Wide(c) => c[i],
            Edges::Narrow(c) => c[i] as f64,
        }
    }

    fn len(&self) -> usize {
        match self {
            Edges::Wide(c) => c.len(),
            Edges::Narrow(c) => c.len(),
        }
    }

    /// The number of edges at or below `u`.
    pub(super) fn count_up_to(&self, u: f64) -> usize {
        match self {
            Edges::Wide(c) => c.partition_point(|&x| x <= u),
            Edges::Narrow(c) => c.partition_point(|&x| x as f64 <= u),
        }
    }
}

/// A raw value as a bin holds it: |v|, NaN as 0, +inf as `f32::MAX`.
#[inline(always)]
fn sanitise(v: f64) -> f64 {
    if v.is_nan() { 0.0 } else { v.abs().min(f32::MAX as f64) }
}

/// Turns raw values (`cdf[1..]` on entry) into the normalised CDF from exactly 0 to exactly 1 in
/// place; returns their sum. Values are taken as |v| with NaN as 0 and +inf as `f32::MAX`.
#[inline(always)]
pub(super) fn normalise(cdf: &mut [f64]) -> f64 {
    let n = cdf.len() - 1;
    cdf[0] = 0.0;
    // Three loops rather than one: the first and last vectorise; only the running sum is serial.
    for c in &mut cdf[1..] {
        *c = sanitise(*c);
    }
    let last = cdf[1..].iter().rposition(|&v| v > 0.0).unwrap_or(n - 1);
    let sum = prefix_sum(&mut cdf[1..]);
    if sum > 0.0 {
        // Multiplying is monotone, so the CDF still rises; min(1) keeps it within [0, 1].
        let inv = 1.0 / sum;
        cdf.iter_mut().for_each(|c| *c = (*c * inv).min(1.0));
        // From the end of the last nonzero bin on, exactly 1: trailing zero bins are never hit.
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
    pub(super) fn build(values: impl Iterator<Item = f64>, len: usize, min: f32, max: f32) -> Self {
        let mut d = Self { func: Vec::new(), cdf: Vec::new(), integral: 0.0, min, max };
        d.rebuild(values, len);
        d
    }

    /// [`Self::build`] into the existing buffers.
    pub(super) fn rebuild(&mut self, values: impl Iterator<Item = f64>, len: usize) {
        let n = len.max(1);
        self.cdf.clear();
        self.cdf.push(0.0);
        self.cdf.extend(values.take(n));
        self.cdf.resize(n + 1, 0.0);
        self.func.clear();
        self.func.extend(self.cdf[1..].iter().map(|&c| sanitise(c) as f32));
        let sum = normalise(&mut self.cdf);
        self.integral = sum * (self.max as f64 - self.min as f64) / n as f64;
    }

    pub(super) fn bins(&self) -> Bins<'_> {
        Bins { edges: Edges::Wide(&self.cdf), integral: self.integral, min: self.min, max: self.max }
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

impl Bins<'_> {
    /// Integral of |f| over the domain (0 for an all-zero row).
    pub fn integral(&self) -> f32 {
        self.integral as f32
    }

    /// Number of bins (at least 1).
    pub fn len(&self) -> usize {
        self.edges.len() - 1
    }

    /// Always false: there is at least one bin.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn width(&self) -> f64 {
        self.max as f64 - self.min as f64
    }

    /// The density of bin `offset`: its probability (CDF width) over its width, so that it is
    /// the density [`Self::sample`] draws from, bit for bit.
    pub(super) fn density(&self, offset: usize) -> f32 {
        if self.integral > 0.0 {
            let p = self.edges.at(offset + 1) - self.edges.at(offset);
            (p * self.len() as f64 / self.width()) as f32
        } else {
            (1.0 / self.width()) as f32
        }
    }

    /// As [`PiecewiseConstant1D::sample`].
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        let u = search_key(u);
        self.sample_in(self.edges.count_up_to(u), u)
    }

    /// [`Self::sample`] of key `u` ([`search_key`]) given the number of edges at or below it.
    #[inline(always)]
    pub(super) fn sample_in(&self, count: usize, u: f64) -> (f32, f32, usize) {
        let n = self.len();
        let offset = (count - 1).min(n - 1);
        let (c0, c1) = (self.edges.at(offset), self.edges.at(offset + 1));
        let du = if c1 > c0 { ((u - c0) / (c1 - c0)).clamp(0.0, 1.0) } else { 0.0 };
        let x = self.min as f64 + (offset as f64 + du) / n as f64 * self.width();
        ((x as f32).clamp(self.min, self.max), self.density(offset), offset)
    }

    pub(super) fn offset_of(&self, x: f32) -> Option<(usize, f64)> {
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
        let (c0, c1) = (self.edges.at(o), self.edges.at(o + 1));
        Some((c0 + delta * (c1 - c0)) as f32)
    }
}

/// The key a sample `u` is searched for among a CDF's edges: u < 1 keeps it inside a bin of
/// positive width (cdf[o] <= u < cdf[o + 1]).
#[inline(always)]
pub(super) fn search_key(u: f32) -> f64 {
    (u as f64).clamp(0.0, 1.0 - f64::EPSILON / 2.0)
}

/// The number of `edges[start[l]..start[l] + len]` at or below `key[l]`, per lane (sorted edges),
/// as `partition_point` counts them: the lanes' binary searches in lock step, so that their
/// loads are in flight together rather than one dependent chain after another.
#[inline(always)]
pub(super) fn count_up_to_lanes<T: Copy + Into<f64>>(
    edges: &[T],
    start: &[usize; LANES],
    len: usize,
    key: &[f64; LANES],
) -> [usize; LANES] {
    let mut base = *start;
    let mut size = len;
    while size > 1 {
        let half = size / 2;
        for l in 0..LANES {
            let mid = base[l] + half;
            base[l] = if edges[mid].into() <= key[l] { mid } else { base[l] };
        }
        size -= half;
    }
    std::array::from_fn(|l| base[l] - start[l] + usize::from(len > 0 && edges[base[l]].into() <= key[l]))
}

pub(super) fn valid_domain(min: f32, max: f32) -> bool {
    min.is_finite() && max.is_finite() && min < max
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::PiecewiseConstant2D;
    use glam::Vec2;

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
