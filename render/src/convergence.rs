//! Image error against run time: what `voxbrick bench-gpu --convergence` prints.
//!
//! Each measurement is a render of n samples per pixel, its GPU time and its mean squared
//! error (over pixels and channels) against a reference render of R samples with an
//! independent seed. For an unbiased estimator E[MSE(n)] = σ²/n + σ²/R, with σ² the per-sample
//! variance averaged over pixels, so σ² is estimated from the measurement with the fewest
//! samples and the reference's share σ²/R is taken off every MSE. What is left times n should
//! stay at σ² as n grows: a ratio that climbs with n is bias (error that more samples do not
//! remove). MSE × time is the work-normalised error: lower is better, and it is what to
//! compare between renderers, variants and settings at equal quality.

/// One measurement: samples per pixel, seconds it took, MSE against the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    /// Samples per pixel.
    pub spp: u32,
    /// Render time in seconds.
    pub seconds: f64,
    /// Mean squared error against the reference.
    pub mse: f64,
}

/// One row of the table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// The measurement.
    pub measured: Measurement,
    /// MSE less the reference's own noise (σ²/R), never below 0.
    pub mse: f64,
    /// √mse over the reference image's mean value (relative RMS error).
    pub relative_rmse: f64,
    /// mse · n / σ²: 1 while the error falls as 1/n; growth with n is bias.
    pub variance_ratio: f64,
    /// mse · seconds relative to the first row's (lower is better).
    pub relative_cost: f64,
}

/// The table for `measurements` (the first must have the fewest samples), a reference of
/// `reference_spp` samples whose mean pixel value is `reference_mean`. Empty when there is
/// nothing to measure against (no measurement, or a reference without light).
pub fn table(measurements: &[Measurement], reference_spp: u32, reference_mean: f64) -> Vec<Row> {
    let Some(first) = measurements.first() else {
        return Vec::new();
    };
    let r = f64::from(reference_spp.max(1));
    let sigma2 = first.mse / (1.0 / f64::from(first.spp.max(1)) + 1.0 / r);
    if !(sigma2 > 0.0 && reference_mean > 0.0) {
        return Vec::new();
    }
    let corrected = |m: &Measurement| (m.mse - sigma2 / r).max(0.0);
    let base = corrected(first) * first.seconds;
    measurements
        .iter()
        .map(|m| {
            let mse = corrected(m);
            Row {
                measured: *m,
                mse,
                relative_rmse: mse.sqrt() / reference_mean,
                variance_ratio: mse * f64::from(m.spp) / sigma2,
                relative_cost: if base > 0.0 {
                    mse * m.seconds / base
                } else {
                    f64::NAN
                },
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unbiased(sigma2: f64, bias2: f64, r: u32) -> Vec<Measurement> {
        [1u32, 4, 16, 64, 256]
            .iter()
            .map(|&n| Measurement {
                spp: n,
                seconds: 0.001 * n as f64,
                mse: sigma2 / n as f64 + sigma2 / r as f64 + bias2,
            })
            .collect()
    }

    #[test]
    fn an_unbiased_estimator_keeps_the_variance_ratio_at_one() {
        let rows = table(&unbiased(0.5, 0.0, 4096), 4096, 0.25);
        assert_eq!(rows.len(), 5);
        for row in &rows {
            assert!((row.variance_ratio - 1.0).abs() < 1e-9, "{row:?}");
            // Time proportional to n and error to 1/n: the same cost at every n.
            assert!((row.relative_cost - 1.0).abs() < 1e-9, "{row:?}");
        }
        let expected = (0.5f64 / 256.0).sqrt() / 0.25;
        assert!((rows[4].relative_rmse - expected).abs() < 1e-12);
    }

    #[test]
    fn bias_shows_as_a_growing_variance_ratio() {
        let rows = table(&unbiased(0.5, 1e-4, 4096), 4096, 0.25);
        assert!(rows[4].variance_ratio > 1.04, "{:?}", rows[4]);
        assert!(
            rows.windows(2)
                .all(|w| w[1].variance_ratio > w[0].variance_ratio)
        );
    }

    #[test]
    fn nothing_to_measure_gives_no_rows() {
        assert!(table(&[], 64, 1.0).is_empty());
        assert!(table(&unbiased(0.0, 0.0, 64), 64, 1.0).is_empty());
        assert!(table(&unbiased(0.5, 0.0, 64), 64, 0.0).is_empty());
    }
}
