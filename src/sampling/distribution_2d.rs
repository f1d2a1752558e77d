//! [`PiecewiseConstant2D`]: a marginal over rows and one conditional per row, the rows stored
//! in f32 (4 bytes a cell: the tables of an 8k environment map are bound by memory traffic).
//!
//! A row's CDF is accumulated in f64 and rounded to f32 per edge, each nonzero bin kept at least
//! one f32 step wide (`finish_row`); a bin's density is its f32 width, so sampling and pdf agree
//! exactly and no direction with light gets density 0. A row that f32 cannot hold that way (a
//! sun 1e9 times the rest of its row, with sky after it) keeps its f64 CDF.

use glam::Vec2;
use rayon::prelude::*;

use super::SamplingError;
use super::distribution::{Bins, Edges, PiecewiseConstant1D, count_up_to_lanes, normalise, search_key, valid_domain};
use crate::lanes::LANES;

/// A piecewise-constant density over a rectangle (by default [0, 1]^2) proportional to |f| on an
/// `nu` x `nv` grid: a marginal over v of row integrals, and one conditional over u per row.
///
/// The rows live in one flat buffer (`cdf`: nu + 1 edges per row) so that they can be built in
/// parallel, rebuilt in part ([`Self::fill_rows`]) and reused across rebuilds.
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseConstant2D {
    nu: usize,
    nv: usize,
    cdf: Vec<f32>,
    /// Per row, its f64 CDF where f32 cannot hold it (see `finish_row`).
    wide: Vec<Option<Box<[f64]>>>,
    /// Per row, the integral of |f| over [min.x, max.x].
    row_integral: Vec<f64>,
    marginal: PiecewiseConstant1D,
    min: Vec2,
    max: Vec2,
}

/// Rows per parallel task: enough to amortise a task (and a filter's halo rows), few enough to
/// split 1024 rows evenly over the cores.
const ROWS_PER_TASK: usize = 32;

/// Normalises the raw values in `scratch[1..]` and stores the row as f32 edges in `cdf`, or as
/// f64 in `wide` where f32 cannot hold it; returns the values' sum.
///
/// A nonzero bin narrower than an f32 step where its edge falls is widened to one step (its
/// density, the width, says so: sampling stays exact, and a dim bin is drawn slightly more often
/// than its share); zero bins keep zero width. Only a row whose widened edges would pass 1 (many
/// nonzero bins after a sun that holds nearly all of it) keeps its f64 CDF.
#[inline(always)]
fn finish_row(scratch: &mut [f64], cdf: &mut [f32], wide: &mut Option<Box<[f64]>>) -> f64 {
    let sum = normalise(scratch);
    // Rounding and the check in one loop that vectorises; the serial widening only for a row
    // that needs it.
    let n = cdf.len() - 1;
    cdf[0] = 0.0;
    let mut closed = false;
    for i in 0..n {
        let edge = scratch[i + 1] as f32;
        closed |= (scratch[i + 1] > scratch[i]) & (edge <= scratch[i] as f32);
        cdf[i + 1] = edge;
    }
    if closed {
        let mut prev = 0.0f32;
        for i in 0..n {
            let edge = if scratch[i + 1] > scratch[i] { cdf[i + 1].max(prev.next_up()) } else { prev };
            cdf[i + 1] = edge;
            prev = edge;
        }
    }
    *wide = (cdf[n] != 1.0).then(|| scratch.into());
    sum
}

/// A `fill` for [`PiecewiseConstant2D::fill_rows`] that makes every row zero.
fn zero_rows(_: &mut (), _: usize, rows: &mut [&mut [f64]]) {
    rows.iter_mut().for_each(|r| r.fill(0.0));
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
        let mut d = Self::unfilled(nu, nv, min, max);
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
        let mut d = Self::unfilled(nu, nv, min, max);
        let nv = d.nv;
        Self::fill_rows(&mut [&mut d], 0..nv, |_| (), zero_rows);
        d
    }

    /// A grid whose rows are not yet valid: every row must be filled by [`Self::fill_rows`]
    /// before use. Its buffers come zeroed from the allocator, which maps fresh pages lazily: a
    /// fresh build writes each cell once.
    pub fn unfilled(nu: usize, nv: usize, min: Vec2, max: Vec2) -> Self {
        let (min, max) =
            if valid_domain(min.x, max.x) && valid_domain(min.y, max.y) { (min, max) } else { (Vec2::ZERO, Vec2::ONE) };
        let (nu, nv) = (nu.max(1), nv.max(1));
        Self {
            nu,
            nv,
            cdf: vec![0.0; (nu + 1) * nv],
            wide: vec![None; nv],
            row_integral: vec![0.0; nv],
            marginal: PiecewiseConstant1D::build(std::iter::empty(), nv, min.y, max.y),
            min,
            max,
        }
    }

    /// Resizes to `nu` x `nv` all-zero rows, keeping the buffers' memory (0 counts as 1).
    pub fn reset(&mut self, nu: usize, nv: usize) {
        let (nu, nv) = (nu.max(1), nv.max(1));
        (self.nu, self.nv) = (nu, nv);
        self.cdf.resize((nu + 1) * nv, 0.0);
        self.wide.clear();
        self.wide.resize(nv, None);
        self.row_integral.resize(nv, 0.0);
        Self::fill_rows(&mut [self], 0..nv, |_| (), zero_rows);
    }

    /// Refills `rows` (clamped to the grid) of every distribution in `dists` in parallel, in
    /// tasks of consecutive rows: `init(rows)` makes a task's state, then `fill(state, row,
    /// values)` writes each of a row's raw values (|f| is taken after), one slice of
    /// `nu` per distribution, so that one pass over a source serves them all; each row's CDF is
    /// built while the row is in cache, and the marginals at the end. Rows outside `rows` are
    /// kept. Every distribution must have the grid of the first; one that does not is left
    /// unchanged.
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
                let c = d.cdf[lo * (nu + 1)..hi * (nu + 1)].chunks_mut(k * (nu + 1));
                let w = d.wide[lo..hi].chunks_mut(k);
                let r = d.row_integral[lo..hi].chunks_mut(k);
                c.zip(w).zip(r).map(move |((c, w), r)| (span, c, w, r)).collect::<Vec<_>>().into_iter()
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
                    // One f64 row per distribution, in cache while its values become its CDF.
                    let mut scratch = vec![0.0; task.len() * (nu + 1)];
                    for i in 0..n {
                        let mut values: Vec<&mut [f64]> = scratch.chunks_mut(nu + 1).map(|s| &mut s[1..]).collect();
                        fill(&mut state, first + i, &mut values);
                        drop(values);
                        for ((span, c, w, r), s) in task.iter_mut().zip(scratch.chunks_mut(nu + 1)) {
                            let sum = finish_row(s, &mut c[i * (nu + 1)..(i + 1) * (nu + 1)], &mut w[i]);
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

    /// Rows kept in f64 because f32 cannot hold them (see the module's notes).
    pub fn wide_rows(&self) -> usize {
        self.wide.iter().filter(|w| w.is_some()).count()
    }

    /// The conditional distribution over u in row `v`, if that row exists.
    pub fn conditional(&self, v: usize) -> Option<Bins<'_>> {
        (v < self.nv).then(|| Bins {
            edges: match &self.wide[v] {
                Some(wide) => Edges::Wide(wide),
                None => Edges::Narrow(&self.cdf[v * (self.nu + 1)..(v + 1) * (self.nu + 1)]),
            },
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

    /// [`Self::sample`] at a lane each, the same results: the lanes' searches of the marginal,
    /// then of their rows, run in lock step (rows kept in f64 are searched one lane at a time).
    #[inline(always)]
    pub fn sample_lanes(&self, u: &[Vec2; LANES]) -> [(Vec2, f32, [usize; 2]); LANES] {
        let (marginal, nu) = (self.marginal.bins(), self.nu);
        let key_v: [f64; LANES] = std::array::from_fn(|l| search_key(u[l].y));
        let edges = self.marginal.cdf();
        let counts = count_up_to_lanes(edges, &[0; LANES], edges.len(), &key_v);
        let ys: [(f32, f32, usize); LANES] = std::array::from_fn(|l| marginal.sample_in(counts[l], key_v[l]));
        let key_u: [f64; LANES] = std::array::from_fn(|l| search_key(u[l].x));
        let start = std::array::from_fn(|l| ys[l].2.min(self.nv - 1) * (nu + 1));
        let counts = count_up_to_lanes(&self.cdf, &start, nu + 1, &key_u);
        std::array::from_fn(|l| {
            let (y, pdf_v, iv) = ys[l];
            let row = self.row(iv);
            let count = match row.edges {
                Edges::Wide(_) => row.edges.count_up_to(key_u[l]),
                Edges::Narrow(_) => counts[l],
            };
            let (x, pdf_u, iu) = row.sample_in(count, key_u[l]);
            (Vec2::new(x, y), pdf_u * pdf_v, [iu, iv])
        })
    }

    /// Density at `p`, the one [`Self::sample`] returns there; 0 outside the domain.
    pub fn pdf(&self, p: Vec2) -> f32 {
        let marginal = self.marginal.bins();
        let (Some((iu, _)), Some((iv, _))) = (self.row(0).offset_of(p.x), marginal.offset_of(p.y)) else {
            return 0.0;
        };
        self.row(iv).density(iu) * marginal.density(iv)
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
    use crate::rng::SplitMix64;

    /// The lanes' lock-step searches give `sample`'s results for every u: random ones, u on the
    /// CDF's edges (ties go to the bin above, as `partition_point` counts), 0 and the last f32
    /// below 1, in a table with zero bins, a zero row and a sun row kept in f64.
    #[test]
    fn sample_lanes_matches_sample_on_edges_zero_rows_and_wide_rows() {
        let (nu, nv) = (96, 40);
        let mut rng = SplitMix64::new(5);
        let mut f: Vec<f32> = (0..nu * nv).map(|i| if i % 5 == 0 { 0.0 } else { rng.f32() + 0.01 }).collect();
        f[7 * nu..8 * nu].fill(0.0);
        f[10 * nu + 40] = 1e12;
        let d = PiecewiseConstant2D::new(&f, nu, nv);
        assert_eq!(d.wide_rows(), 1);
        let mut us: Vec<Vec2> = (0..4000).map(|_| Vec2::new(rng.f32(), rng.f32())).collect();
        let edges: Vec<f32> = d.marginal().cdf().iter().map(|&c| c as f32).collect();
        let row_edges: Vec<f32> = d.cdf[..nu + 1].to_vec();
        for (i, &v) in edges.iter().enumerate() {
            us.push(Vec2::new(row_edges[i % row_edges.len()], v));
        }
        us.extend([Vec2::ZERO, Vec2::splat(1.0 - f32::EPSILON / 2.0), Vec2::new(0.5, 10.5 / nv as f32), Vec2::ONE]);
        // Every lane of the sun's row, searched in f64.
        us.extend((0..LANES).map(|l| Vec2::new(l as f32 / LANES as f32, d.marginal().cdf()[10] as f32 + 1e-7)));
        for chunk in us.chunks(LANES) {
            let u: [Vec2; LANES] = std::array::from_fn(|l| chunk[l % chunk.len()]);
            for (l, got) in d.sample_lanes(&u).iter().enumerate() {
                let want = d.sample(u[l]);
                assert_eq!(
                    (got.0.to_array().map(f32::to_bits), got.1.to_bits(), got.2),
                    (want.0.to_array().map(f32::to_bits), want.1.to_bits(), want.2),
                    "u {:?}",
                    u[l]
                );
            }
        }
    }
}
