//! Building [`EnvMapTables`]: the parallel full-resolution build, the rebuild of changed rows, and
//! the whole-image reference (also the path for tables downsampled below the image's size).
//!
//! Both builds evaluate each texel with the same f64 functions below (luminance, the [1, 6, 1] / 8
//! filter, the row band, the compensation excess) in the same order, and round to f32 only where
//! the table stores a cell, so the fast build's cells, CDFs and pdfs equal the reference's bit for
//! bit. f64 per texel is kept on purpose: the compensated cell max(0, L - mean) cancels, and an
//! f32 luminance (relative error 6e-8) would carry an error of 6e-8 mean / (L - mean) into it,
//! above 1e-5 for texels within 0.6% of the mean. The build is bound by memory traffic, not by
//! this arithmetic (docs/performance.md, "Environment-map tables").

use std::cell::RefCell;
use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::{EnvLookup, EnvMapTables, EnvTableOptions, clean_texel, row_band, row_divisor, table_resolution};
use crate::lanes::{self, LANES};
use crate::sampling::PiecewiseConstant2D;
use crate::scene::image::{LUMINANCE_WEIGHTS, RgbImage};

/// A partial rebuild keeps the compensation threshold (the mean) while the mean moves less than
/// this fraction of itself: any threshold gives a table whose pdf is the one sampled (unbiased
/// under MIS), and refreshing it means rewriting every compensated cell.
pub const MEAN_TOLERANCE: f64 = 0.01;

/// What the tables were built with, and the per-row buffers a partial rebuild needs.
#[derive(Clone, Debug, PartialEq, Default)]
pub(super) struct BuildState {
    compensate: bool,
    max_width: Option<usize>,
    /// The image's (width, height) at the last build.
    size: (usize, usize),
    /// The compensation threshold the compensated table was built with.
    pub(super) mean: f64,
    /// Per texel row: its solid angle scaled so rows average 1 (a constant factor leaves the
    /// density unchanged), its luminance sum, and its non-finite texels.
    band: Vec<f64>,
    row_lum_sum: Vec<f64>,
    row_bad: Vec<usize>,
}

/// Luminance (Rec. 709 Y, f64) of a texel as the light uses it.
#[inline]
fn texel_lum(t: Vec3) -> f64 {
    LUMINANCE_WEIGHTS.as_dvec3().dot(clean_texel(t).as_dvec3())
}

/// The [1, 6, 1] / 8 filter: the mean of the bilinear interpolant over a texel, in 1D (the half
/// texel toward a neighbour averages 1/4 of it and 3/4 of the centre).
#[inline(always)]
fn filter3(a: f64, c: f64, b: f64) -> f64 {
    (a + 6.0 * c + b) / 8.0
}

/// The compensated importance of luminance `l` (Karlik et al. 2019): max(0, l - mean), with
/// excesses within rounding of the mean (a constant map) counted as none.
#[inline(always)]
fn excess(l: f64, mean: f64) -> f64 {
    if l - mean > 1e-9 * mean { l - mean } else { 0.0 }
}

/// A cell value as the table stores it (f32, saturating).
#[inline(always)]
fn cell(v: f64) -> f64 {
    (v.min(f32::MAX as f64) as f32) as f64
}

/// Luminance of texel row `y` into `out` (the image's width; pixels missing from a short buffer
/// are black); returns its number of non-finite texels. Blocks of [`LANES`] texels go through
/// [`lum_lanes`], the rest through [`texel_lum`], which it equals bit for bit.
#[inline(always)]
pub fn lum_row(image: &RgbImage, y: usize, out: &mut [f64]) -> usize {
    let w = out.len();
    let px = if image.width == w { image.pixels.get(y * w..).unwrap_or(&[]) } else { &[] };
    let px = &px[..px.len().min(w)];
    let whole = px.len() / LANES * LANES;
    let mut bad = 0;
    for b in (0..whole).step_by(LANES) {
        bad += lum_lanes(lanes::block(px, b), lanes::block_mut(out, b));
    }
    for (o, &t) in out[whole..].iter_mut().zip(&px[whole..]) {
        bad += usize::from(!t.is_finite());
        *o = texel_lum(t);
    }
    out[px.len()..].fill(0.0);
    bad
}

/// [`texel_lum`] of [`LANES`] texels, branch-free so that it vectorises; returns how many are
/// not finite.
#[inline(always)]
fn lum_lanes(texels: &[Vec3; LANES], out: &mut [f64; LANES]) -> usize {
    let weights = LUMINANCE_WEIGHTS.as_dvec3();
    let mut bad = 0;
    for l in 0..LANES {
        let t = texels[l];
        let finite = t.x.is_finite() & t.y.is_finite() & t.z.is_finite();
        bad += usize::from(!finite);
        // clean_texel: a texel with a non-finite channel is black, negative channels are 0.
        let channel = |c: f32| if finite { c.max(0.0) as f64 } else { 0.0 };
        out[l] = weights.x * channel(t.x) + weights.y * channel(t.y) + weights.z * channel(t.z);
    }
    bad
}

/// Sum of a row in four interleaved chains: a serial sum waits on each add's latency.
#[inline(always)]
fn row_sum(v: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let chunks = v.chunks_exact(4);
    let rest: f64 = chunks.remainder().iter().sum();
    for c in chunks {
        acc.iter_mut().zip(c).for_each(|(a, &x)| *a += x);
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + rest
}

/// The filter across a row, wrapping in u (the seam).
#[inline(always)]
fn filter_row(lum: &[f64], out: &mut [f64]) {
    let w = lum.len();
    if w < 3 {
        for x in 0..w {
            out[x] = filter3(lum[(x + w - 1) % w], lum[x], lum[(x + 1) % w]);
        }
        return;
    }
    out[0] = filter3(lum[w - 1], lum[0], lum[1]);
    for x in 1..w - 1 {
        out[x] = filter3(lum[x - 1], lum[x], lum[x + 1]);
    }
    out[w - 1] = filter3(lum[w - 2], lum[w - 1], lum[0]);
}

/// sum L Omega / sum Omega over all texels, from each row's luminance sum: the filter keeps a
/// row's sum across u and gives 1/8 of it to each neighbouring row (clamped at the poles).
fn solid_angle_mean(row_lum_sum: &[f64], band: &[f64], w: usize, lookup: EnvLookup) -> f64 {
    let h = row_lum_sum.len();
    let r = |y: usize| match lookup {
        EnvLookup::Nearest => row_lum_sum[y],
        EnvLookup::Bilinear => {
            filter3(row_lum_sum[y.saturating_sub(1)], row_lum_sum[y], row_lum_sum[(y + 1).min(h - 1)])
        }
    };
    (0..h).map(|y| r(y) * band[y]).sum::<f64>() / (w * h).max(1) as f64
}

thread_local! {
    /// Per worker, the rows of [`Window`], kept across tasks and builds: allocating them per task
    /// costs page faults on every build.
    static SCRATCH: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

/// A task's rolling view of the texel rows it reads (its own and, for bilinear, one either
/// side): one luminance row and a ring of three filtered rows, each texel row computed once.
struct Window<'a> {
    buf: Vec<f64>,
    image: &'a RgbImage,
    lookup: EnvLookup,
    own: Range<usize>,
    next: usize,
    w: usize,
    h: usize,
}

impl<'a> Window<'a> {
    fn new(image: &'a RgbImage, lookup: EnvLookup, own: Range<usize>, w: usize, h: usize) -> Self {
        let mut buf = SCRATCH.with_borrow_mut(std::mem::take);
        buf.resize(4 * w, 0.0);
        let next = own.start.saturating_sub(usize::from(lookup == EnvLookup::Bilinear));
        Self { buf, image, lookup, own, next, w, h }
    }

    /// Advances to table row `y`; returns its filtered rows above, at and below (clamped at the
    /// poles), and stores the non-finite counts of the task's own rows in `bad`.
    #[inline(always)]
    fn rows(&mut self, y: usize, bad: &[AtomicUsize]) -> (&[f64], &[f64], &[f64]) {
        let (w, halo) = (self.w, usize::from(self.lookup == EnvLookup::Bilinear));
        let (up, down) = (y.saturating_sub(halo), (y + halo).min(self.h - 1));
        let (lum, ring) = self.buf.split_at_mut(w);
        while self.next <= down {
            let r = self.next;
            let b = lum_row(self.image, r, lum);
            if self.own.contains(&r) {
                bad[r].store(b, Ordering::Relaxed);
            }
            let slot = &mut ring[(r % 3) * w..(r % 3 + 1) * w];
            match self.lookup {
                EnvLookup::Nearest => slot.copy_from_slice(lum),
                EnvLookup::Bilinear => filter_row(lum, slot),
            }
            self.next += 1;
        }
        let row = |r: usize| &ring[(r % 3) * w..(r % 3 + 1) * w];
        (row(up), row(y), row(down))
    }
}

impl Drop for Window<'_> {
    fn drop(&mut self) {
        SCRATCH.with_borrow_mut(|s| *s = std::mem::take(&mut self.buf));
    }
}

/// Table row `y` (table = image resolution) of the plain table into `out[0]` and, with a mean,
/// the compensated one into `out[1]`. Index loops, one per case, so that each vectorises.
#[inline(always)]
fn fill_row(win: &mut Window, y: usize, band: f64, mean: Option<f64>, bad: &[AtomicUsize], out: &mut [&mut [f64]]) {
    let bilinear = win.lookup == EnvLookup::Bilinear;
    let (ru, rc, rd) = win.rows(y, bad);
    let w = rc.len();
    let (ru, rd) = (&ru[..w], &rd[..w]);
    // The vertical half of the footprint filter.
    let lum = |x: usize| if bilinear { filter3(ru[x], rc[x], rd[x]) } else { rc[x] };
    match (out, mean) {
        ([plain, comp, ..], Some(m)) => {
            let (plain, comp) = (&mut plain[..w], &mut comp[..w]);
            for x in 0..w {
                let l = lum(x);
                plain[x] = cell(l * band);
                comp[x] = cell(excess(l, m) * band);
            }
        }
        ([plain, ..], _) => {
            let plain = &mut plain[..w];
            for x in 0..w {
                plain[x] = cell(lum(x) * band);
            }
        }
        ([], _) => {}
    }
}

impl EnvMapTables {
    /// Tables for `options` with nothing built yet.
    pub(super) fn empty(options: EnvTableOptions) -> Self {
        Self {
            resolution: [1, 1],
            distribution: None,
            compensated: None,
            bad_texels: 0,
            lookup: options.lookup,
            row_divisor: Vec::new(),
            state: BuildState::default(),
        }
    }

    /// Rebuilds the tables for `image` with `options`, reusing their buffers: the parallel
    /// build at the image's resolution, the reference build for a smaller `max_width`.
    pub fn rebuild(&mut self, image: &RgbImage, options: EnvTableOptions) {
        let (w, h) = (image.width.max(1), image.height.max(1));
        let res = table_resolution(w, h, options.max_width);
        if res != [w, h] {
            *self = Self::build_reference(image, options);
            return;
        }
        self.lookup = options.lookup;
        self.resolution = res;
        self.row_divisor.clear();
        self.row_divisor.extend((0..h).map(|row| row_divisor(row, h)));
        let s = &mut self.state;
        (s.compensate, s.max_width, s.size) = (options.compensate, options.max_width, (w, h));
        s.band.clear();
        s.band.extend((0..h).map(|y| row_band(y, h) * h as f64 / 2.0));
        s.row_lum_sum.resize(h, 0.0);
        s.row_bad.resize(h, 0);
        self.refill(image, 0..h, None);
    }

    /// Rebuilds after the texels of `rows` (image rows, row 0 at the top) changed: only the table
    /// rows they reach (one more either side for bilinear lookup) and the marginals, in the
    /// existing buffers. The result equals [`Self::rebuild`] bit for bit, except that the
    /// compensation threshold is kept while the mean moves less than [`MEAN_TOLERANCE`] of
    /// itself (past it, the compensated table is rebuilt whole). An image of another size, or
    /// tables downsampled or not yet built, get a full rebuild.
    pub fn update_rows(&mut self, image: &RgbImage, rows: Range<usize>) {
        let s = &self.state;
        let (w, h) = (image.width.max(1), image.height.max(1));
        let options = EnvTableOptions { compensate: s.compensate, max_width: s.max_width, lookup: self.lookup };
        if s.size != (w, h) || self.resolution != [w, h] || self.distribution.is_none() {
            return self.rebuild(image, options);
        }
        let mean = s.compensate.then_some(s.mean);
        self.refill(image, rows.start.min(h)..rows.end.min(h), mean);
    }

    /// Recomputes texel rows `rows` and every table row they reach. `keep_mean`: the threshold
    /// the compensated table was built with, kept if the new mean is within tolerance of it.
    pub(super) fn refill(&mut self, image: &RgbImage, rows: Range<usize>, keep_mean: Option<f64>) {
        let (w, h) = self.state.size;
        let lookup = self.lookup;
        let s = &mut self.state;
        // Pass 1 (compensation only): row luminance sums, for the mean the threshold needs.
        if s.compensate {
            s.row_lum_sum[rows.clone()].par_iter_mut().enumerate().for_each_init(
                || vec![0.0; w],
                |lum, (i, sum)| {
                    lanes::widest(
                        #[inline(always)]
                        || {
                            lum_row(image, rows.start + i, lum);
                            *sum = row_sum(lum);
                        },
                    )
                },
            );
        }
        let mean = solid_angle_mean(&s.row_lum_sum, &s.band, w, lookup);
        let halo = usize::from(lookup == EnvLookup::Bilinear);
        let mut table_rows = rows.start.saturating_sub(halo)..(rows.end + halo).min(h);
        // Tables of another size (or none yet) are made afresh and filled whole.
        let reuse = |d: Option<PiecewiseConstant2D>| match d.filter(|d| d.resolution() == [w, h]) {
            Some(d) => (d, false),
            None => (PiecewiseConstant2D::unfilled(w, h, glam::Vec2::ZERO, glam::Vec2::ONE), true),
        };
        let (mut plain, made) = reuse(self.distribution.take());
        if made {
            table_rows = 0..h;
        }
        let comp = if s.compensate {
            let kept = keep_mean.filter(|&m| (mean - m).abs() <= MEAN_TOLERANCE * m && self.compensated.is_some());
            if kept.is_none() {
                // A new threshold changes every compensated cell.
                table_rows = 0..h;
                s.mean = mean;
            }
            let (comp, made) = reuse(self.compensated.take());
            if made {
                table_rows = 0..h;
            }
            Some(comp)
        } else {
            None
        };
        let bad: Vec<AtomicUsize> = (0..h).map(|_| AtomicUsize::new(0)).collect();
        let threshold = s.compensate.then_some(s.mean);
        let band = &s.band;
        // Pass 2: every table row in the range, both tables from one read of the texels.
        let mut comp = comp;
        let init = |own: Range<usize>| Window::new(image, lookup, own, w, h);
        let mut dists: Vec<&mut PiecewiseConstant2D> = vec![&mut plain];
        dists.extend(comp.as_mut());
        PiecewiseConstant2D::fill_rows(
            &mut dists,
            table_rows.clone(),
            init,
            #[inline(always)]
            |win: &mut Window, y: usize, out: &mut [&mut [f64]]| fill_row(win, y, band[y], threshold, &bad, out),
        );
        // Rows in the table range but outside `rows` were reread: their counts are the same.
        for y in rows {
            s.row_bad[y] = bad[y].load(Ordering::Relaxed);
        }
        self.bad_texels = s.row_bad.iter().sum();
        let lit = |d: &PiecewiseConstant2D| d.marginal().integral() > 0.0;
        self.distribution = lit(&plain).then_some(plain);
        self.compensated = comp.filter(|c| self.distribution.is_some() && lit(c));
    }

    /// The reference build: whole-image passes in f64, as the tables were first written; the
    /// fast build is tested against it, and it serves tables smaller than the image (the
    /// importance area-averaged onto the table grid).
    pub fn build_reference(image: &RgbImage, options: EnvTableOptions) -> Self {
        let (w, h) = (image.width.max(1), image.height.max(1));
        let mut lum = vec![0.0; w * h];
        let (mut bad, mut row_lum_sum) = (0, vec![0.0; h]);
        for (y, row) in lum.chunks_mut(w).enumerate() {
            bad += lum_row(image, y, row);
            row_lum_sum[y] = row_sum(row);
        }
        if options.lookup == EnvLookup::Bilinear {
            lum = footprint_average(&lum, w, h);
        }
        let band: Vec<f64> = (0..h).map(|y| row_band(y, h) * h as f64 / 2.0).collect();
        let importance: Vec<f64> = lum.iter().enumerate().map(|(i, l)| l * band[i / w]).collect();
        let [nw, nh] = table_resolution(w, h, options.max_width);
        let distribution = distribution_of(&downsample(&importance, w, h, nw, nh), nw, nh);
        let mean = solid_angle_mean(&row_lum_sum, &band, w, options.lookup);
        let compensated = if options.compensate && distribution.is_some() {
            let comp: Vec<f64> = lum.iter().enumerate().map(|(i, &l)| excess(l, mean) * band[i / w]).collect();
            distribution_of(&downsample(&comp, w, h, nw, nh), nw, nh)
        } else {
            None
        };
        let row_divisor = (0..nh).map(|row| row_divisor(row, nh)).collect();
        Self {
            resolution: [nw, nh],
            distribution,
            compensated,
            bad_texels: bad,
            lookup: options.lookup,
            row_divisor,
            state: BuildState { compensate: options.compensate, max_width: options.max_width, ..Default::default() },
        }
    }
}

/// The separable footprint filter over a whole `w` x `h` grid (wrapping in u, clamped in v).
fn footprint_average(lum: &[f64], w: usize, h: usize) -> Vec<f64> {
    let mut rows = vec![0.0; w * h];
    for (l, r) in lum.chunks(w).zip(rows.chunks_mut(w)) {
        filter_row(l, r);
    }
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        let (up, down) = (y.saturating_sub(1), (y + 1).min(h - 1));
        for x in 0..w {
            out[y * w + x] = filter3(rows[up * w + x], rows[y * w + x], rows[down * w + x]);
        }
    }
    out
}

/// For each of `coarse` equal cells over [0, 1], the fine cells (of `fine`) it overlaps and the
/// fraction of the coarse cell each covers (the fractions sum to 1), in exact integer arithmetic.
pub(super) fn overlap_weights(fine: usize, coarse: usize) -> Vec<Vec<(usize, f64)>> {
    (0..coarse)
        .map(|c| {
            // In units of 1 / (fine * coarse): coarse cell c is [c * fine, (c + 1) * fine).
            let (c0, c1) = (c * fine, (c + 1) * fine);
            (c0 / coarse..c1.div_ceil(coarse).min(fine))
                .filter_map(|i| {
                    let len = c1.min((i + 1) * coarse).saturating_sub(c0.max(i * coarse));
                    (len > 0).then_some((i, len as f64 / fine as f64))
                })
                .collect()
        })
        .collect()
}

/// Area-averages a `w` x `h` grid onto `nw` x `nh` cells. A coarse cell is nonzero exactly when
/// a fine cell it overlaps is.
pub(super) fn downsample(f: &[f64], w: usize, h: usize, nw: usize, nh: usize) -> Vec<f64> {
    if (nw, nh) == (w, h) {
        return f.to_vec();
    }
    let (wu, wv) = (overlap_weights(w, nw), overlap_weights(h, nh));
    let mut rows = vec![0.0; nw * h];
    for y in 0..h {
        for (x, ws) in wu.iter().enumerate() {
            rows[y * nw + x] = ws.iter().map(|&(i, k)| f[y * w + i] * k).sum();
        }
    }
    let mut out = vec![0.0; nw * nh];
    for (y, ws) in wv.iter().enumerate() {
        for x in 0..nw {
            out[y * nw + x] = ws.iter().map(|&(j, k)| rows[j * nw + x] * k).sum();
        }
    }
    out
}

/// A distribution of `f`, or None if it is zero everywhere.
fn distribution_of(f: &[f64], nw: usize, nh: usize) -> Option<PiecewiseConstant2D> {
    let f32s: Vec<f32> = f.iter().map(|&v| cell(v) as f32).collect();
    if f32s.iter().all(|&v| v <= 0.0) {
        return None;
    }
    Some(PiecewiseConstant2D::new(&f32s, nw, nh))
}

/// Per-texel luminance of the radiance `lookup` returns, averaged over each texel's footprint,
/// and how many texels were not finite (the reference's first pass; tests read it).
pub fn texel_luminance(image: &RgbImage, lookup: EnvLookup) -> (Vec<f64>, usize) {
    let (w, h) = (image.width.max(1), image.height.max(1));
    let mut lum = vec![0.0; w * h];
    let bad = lum.chunks_mut(w).enumerate().map(|(y, row)| lum_row(image, y, row)).sum();
    if lookup == EnvLookup::Bilinear {
        lum = footprint_average(&lum, w, h);
    }
    (lum, bad)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane luminance equals the scalar `texel_lum` bit for bit, and counts the same bad
    /// texels, on the hard values (NaN, infinities, negatives, -0, subnormals, f32::MAX) in rows
    /// that end in whole blocks and in a tail, at every instruction-set level the CPU has.
    #[test]
    fn lane_luminance_equals_the_scalar_texel_luminance() {
        let hard = [0.0, -0.0, 1.0, -2.5, f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e-42, f32::MAX, 0.3, 7e5];
        for w in [16, 37, 64 + 5] {
            let pixels: Vec<Vec3> = (0..w)
                .map(|i| {
                    Vec3::new(hard[i % hard.len()], hard[(i * 5 + 1) % hard.len()], hard[(i * 7 + 3) % hard.len()])
                })
                .collect();
            let image = RgbImage { width: w, height: 1, pixels };
            let want: Vec<u64> = image.pixels.iter().map(|&t| texel_lum(t).to_bits()).collect();
            let want_bad = image.pixels.iter().filter(|t| !t.is_finite()).count();
            let mut ran = 0;
            for &level in lanes::Level::ALL {
                let mut out = vec![f64::NAN; w];
                let Some(bad) = lanes::at_level(level, || lum_row(&image, 0, &mut out)) else { continue };
                let got: Vec<u64> = out.iter().map(|v| v.to_bits()).collect();
                assert_eq!((got, bad), (want.clone(), want_bad), "width {w}, {level:?}");
                ran += 1;
            }
            // At least the baseline, and the level `widest` uses.
            assert!(ran > usize::from(lanes::level() != lanes::Level::Baseline), "{ran} levels ran");
        }
    }
}
