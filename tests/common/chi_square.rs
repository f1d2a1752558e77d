//! Pearson's chi-square test of sample counts against the probabilities a sampler claims.

/// Standard normal upper quantiles, for `critical`.
pub const Z_1E4: f64 = 3.719;
pub const Z_1E5: f64 = 4.265;

/// Pearson's statistic of `counts` against `probs` (summing to 1 over every outcome, including
/// any "no sample" cell), cells expected below 5 pooled into one; returns (statistic, degrees of
/// freedom). A sample in a cell of probability 0 fails at once.
pub fn chi_square(counts: &[u64], probs: &[f64]) -> (f64, usize) {
    assert_eq!(counts.len(), probs.len());
    let n: u64 = counts.iter().sum();
    let (mut stat, mut cells, mut pooled_obs, mut pooled_exp) = (0.0, 0usize, 0.0, 0.0);
    for (i, (&c, &p)) in counts.iter().zip(probs).enumerate() {
        assert!(p > 0.0 || c == 0, "cell {i} has probability {p} but {c} samples");
        let e = p * n as f64;
        if e < 5.0 {
            pooled_obs += c as f64;
            pooled_exp += e;
        } else {
            stat += (c as f64 - e).powi(2) / e;
            cells += 1;
        }
    }
    if pooled_exp > 0.0 {
        stat += (pooled_obs - pooled_exp).powi(2) / pooled_exp;
        cells += 1;
    }
    (stat, cells.saturating_sub(1))
}

/// The upper quantile of chi-square with `dof` degrees of freedom at the normal quantile `z`
/// (Wilson and Hilferty 1931).
pub fn critical(dof: usize, z: f64) -> f64 {
    let k = dof.max(1) as f64;
    k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3)
}

/// Asserts `counts` follow `probs` at significance 1e-4 (per test); returns the statistic.
pub fn assert_chi_square(what: &str, counts: &[u64], probs: &[f64]) -> f64 {
    let (stat, dof) = chi_square(counts, probs);
    let limit = critical(dof, Z_1E4);
    assert!(stat < limit, "{what}: chi-square {stat:.1} >= {limit:.1} (dof {dof})");
    stat
}
