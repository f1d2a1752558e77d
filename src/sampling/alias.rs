//! `AliasTable`: O(1) sampling of a discrete distribution (Walker 1977), built by Vose's (1991)
//! method in f64. Light samplers use it to choose lights in proportion to their power.

/// One bin: keep its own outcome with probability `q`, else take `alias`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bin {
    q: f32,
    alias: u32,
    pmf: f32,
}

/// A table that returns outcome i with probability w_i / sum(w).
///
/// Invariants: outcomes with zero, negative or NaN weight have pmf 0, `q = 0`, and an alias with
/// positive weight, so they are never returned; +inf weights count as `f32::MAX`. At most
/// `u32::MAX` entries.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AliasTable {
    bins: Vec<Bin>,
    total_weight: f64,
}

impl AliasTable {
    /// A table over `weights` (Vose's method, in f64 so pmfs sum to 1 to f64 rounding).
    pub fn new(weights: &[f32]) -> Self {
        let weights = &weights[..weights.len().min(u32::MAX as usize)];
        let w: Vec<f64> = weights.iter().map(|&x| if x > 0.0 { x.min(f32::MAX) as f64 } else { 0.0 }).collect();
        let total_weight: f64 = w.iter().sum();
        let n = w.len();
        let mut bins: Vec<Bin> = w
            .iter()
            .map(|&wi| Bin { q: 0.0, alias: 0, pmf: if total_weight > 0.0 { (wi / total_weight) as f32 } else { 0.0 } })
            .collect();
        if total_weight <= 0.0 {
            return Self { bins, total_weight: 0.0 };
        }
        // Scaled probabilities p_i = n w_i / W average 1; pair each under-full bin with an
        // over-full one that tops it up (Vose 1991, "A Linear Algorithm for Generating Random
        // Numbers with a Given Distribution").
        let mut p: Vec<f64> = w.iter().map(|&wi| wi / total_weight * n as f64).collect();
        let (mut small, mut large): (Vec<u32>, Vec<u32>) = (0..n as u32).partition(|&i| p[i as usize] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            let (si, li) = (s as usize, l as usize);
            bins[si].q = p[si] as f32;
            bins[si].alias = l;
            p[li] = (p[li] + p[si]) - 1.0; // this form loses less than p_l - (1 - p_s)
            if p[li] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // Leftovers are 1 up to rounding, except a zero weight stranded by rounding: it keeps q = 0
        // and takes the heaviest outcome as alias.
        let heaviest = (0..n).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0) as u32;
        for i in large.into_iter().chain(small) {
            let b = &mut bins[i as usize];
            if w[i as usize] > 0.0 {
                (b.q, b.alias) = (1.0, i);
            } else {
                (b.q, b.alias) = (0.0, heaviest);
            }
        }
        Self { bins, total_weight }
    }

    /// Samples an outcome with one uniform `u` in [0, 1): the integer part of u n picks a bin and
    /// the fractional part, computed exactly in f64, decides between the bin and its alias.
    /// Returns (index, pmf); None when the table is empty or all weights are 0.
    ///
    /// One f32 carries ~24 bits, shared between bin and remainder, so each outcome's realised
    /// probability is its pmf to within ~2^-24 (absolute).
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        if self.total_weight <= 0.0 || self.bins.is_empty() {
            return None;
        }
        let n = self.bins.len();
        if n == 1 {
            // One outcome (a one-light scene): the result is the same for every u.
            return Some((0, self.bins[0].pmf));
        }
        let t = (u as f64).clamp(0.0, 1.0) * n as f64; // exact: 24-bit mantissa times n < 2^32
        let i = (t as usize).min(n - 1);
        let remainder = t - i as f64; // in [0, 1] for u <= 1; 1 only for u = 1, which keeps the alias
        let bin = self.bins[i];
        let chosen = if remainder < bin.q as f64 { i } else { bin.alias as usize };
        Some((chosen, self.bins[chosen].pmf))
    }

    /// Probability of outcome `i` (0 out of range or for zero weights).
    pub fn pmf(&self, i: usize) -> f32 {
        self.bins.get(i).map_or(0.0, |b| b.pmf)
    }

    /// Number of outcomes.
    pub fn len(&self) -> usize {
        self.bins.len()
    }

    /// True if there are no outcomes.
    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    /// Sum of the (cleaned) weights, in f64.
    pub fn total_weight(&self) -> f64 {
        self.total_weight
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_and_all_zero_tables_sample_none() {
        assert!(AliasTable::new(&[]).sample(0.5).is_none());
        assert!(AliasTable::new(&[]).is_empty());
        let t = AliasTable::new(&[0.0, -1.0, f32::NAN]);
        assert_eq!(t.len(), 3);
        assert!(t.sample(0.0).is_none() && t.sample(0.99).is_none());
        assert_eq!(t.total_weight(), 0.0);
    }

    #[test]
    fn single_positive_weight_is_always_chosen() {
        let t = AliasTable::new(&[0.0, 0.0, 5.0, 0.0]);
        for k in 0..=400 {
            let u = k as f32 / 400.0;
            assert_eq!(t.sample(u), Some((2, 1.0)), "u = {u}");
        }
        // A table of one outcome (the shortcut) and one of zero weight.
        let one = AliasTable::new(&[3.0]);
        for u in [0.0, 0.5, 1.0, f32::NAN] {
            assert_eq!(one.sample(u), Some((0, 1.0)), "u = {u}");
        }
        assert!(AliasTable::new(&[0.0]).sample(0.5).is_none());
    }

    #[test]
    fn infinite_weight_is_clamped() {
        let t = AliasTable::new(&[f32::INFINITY, 1.0]);
        assert!(t.total_weight().is_finite());
        assert_eq!(t.pmf(0), 1.0);
    }
}
