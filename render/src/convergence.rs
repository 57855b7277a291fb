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

use crate::Image;

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

/// relMSE's ε (`voxbrick bench-error`, `bench-gpu --lights`): pixels far darker than 0.1
/// weigh as if they were 0.1, so black pixels do not dominate the mean.
pub const REL_MSE_EPSILON: f64 = 1e-2;

/// Relative MSE of `image` against `reference`: the mean over pixel channels of
/// (x − r)² / (r² + ε), ε = [`REL_MSE_EPSILON`]; None when the sizes differ.
pub fn rel_mse(image: &Image, reference: &Image) -> Option<f64> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return None;
    }
    let mut sum = 0.0;
    for (a, r) in image.pixels.iter().zip(&reference.pixels) {
        for k in 0..3 {
            let (a, r) = (f64::from(a[k]), f64::from(r[k]));
            sum += (a - r).powi(2) / (r * r + REL_MSE_EPSILON);
        }
    }
    Some(sum / (3 * image.pixels.len()).max(1) as f64)
}

/// The reference's own relMSE (its noise) from two independent halves of it, each of R/2
/// samples: E[(a − b)²] = 2 σ²/(R/2) = 4 σ²/R, and the average of the halves has σ²/R.
pub fn reference_noise(half_a: &Image, half_b: &Image) -> Option<f64> {
    rel_mse(half_a, half_b).map(|e| e / 4.0)
}

/// A straight line through (log₂ spp, log₂ error) points, fitted by weighted least squares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogLogFit {
    /// d log(error) / d log(spp): −1 for independent samples.
    pub slope: f64,
    /// The slope's standard error (from the points' own standard errors).
    pub slope_se: f64,
}

/// Fits `points` of (spp, mean error, standard error of that mean); None with fewer than two
/// usable points (positive error and spp). A point's weight is 1 / var(log error), var(log e)
/// ≈ (se / e)²; a point without spread gets the smallest spread of the others.
pub fn log_log_fit(points: &[(f64, f64, f64)]) -> Option<LogLogFit> {
    let usable: Vec<_> = points
        .iter()
        .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.2.is_finite())
        .collect();
    if usable.len() < 2 {
        return None;
    }
    let floor = usable
        .iter()
        .map(|p| p.2 / p.1)
        .filter(|r| *r > 0.0)
        .fold(f64::INFINITY, f64::min);
    let floor = if floor.is_finite() { floor } else { 1e-3 };
    let pts: Vec<(f64, f64, f64)> = usable
        .iter()
        .map(|p| {
            let rel = (p.2 / p.1).max(floor) / std::f64::consts::LN_2;
            (p.0.log2(), p.1.log2(), 1.0 / (rel * rel))
        })
        .collect();
    let w: f64 = pts.iter().map(|p| p.2).sum();
    let mx = pts.iter().map(|p| p.2 * p.0).sum::<f64>() / w;
    let my = pts.iter().map(|p| p.2 * p.1).sum::<f64>() / w;
    let sxx: f64 = pts.iter().map(|p| p.2 * (p.0 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = pts.iter().map(|p| p.2 * (p.0 - mx) * (p.1 - my)).sum();
    Some(LogLogFit {
        slope: sxy / sxx,
        slope_se: (1.0 / sxx).sqrt(),
    })
}

/// The time at which a curve of (error, time) points reaches `error`: log-log interpolation
/// between the two points around it; outside the curve, from its nearest end along error ∝
/// time^`slope` (the curve's fitted slope against samples, time being proportional to them).
/// None with fewer than two points of positive error and time, or a slope that is not negative.
pub fn time_at_error(curve: &[(f64, f64)], error: f64, slope: f64) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> = curve
        .iter()
        .filter(|p| p.0 > 0.0 && p.1 > 0.0)
        .map(|p| (p.0.ln(), p.1.ln()))
        .collect();
    let usable = error > 0.0 && slope < 0.0;
    if pts.len() < 2 || !usable {
        return None;
    }
    // In the order of time.
    pts.sort_by(|a, b| a.1.total_cmp(&b.1));
    let e = error.ln();
    let (first, last) = (pts[0], pts[pts.len() - 1]);
    if e >= first.0 {
        return Some((first.1 + (e - first.0) / slope).exp());
    }
    if e <= last.0 {
        return Some((last.1 + (e - last.0) / slope).exp());
    }
    // The first crossing of the error in time order.
    let k = pts.windows(2).position(|w| e <= w[0].0 && e >= w[1].0)?;
    let (a, b) = (pts[k], pts[k + 1]);
    if a.0 == b.0 {
        return Some(a.1.exp());
    }
    Some((a.1 + (e - a.0) * (b.1 - a.1) / (b.0 - a.0)).exp())
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

    fn image(values: &[f32]) -> Image {
        Image {
            width: values.len() as u32,
            height: 1,
            pixels: values.iter().map(|&v| [v; 3]).collect(),
        }
    }

    #[test]
    fn relative_mse_weighs_each_pixel_by_its_reference() {
        let r = image(&[1.0, 0.0]);
        let x = image(&[1.5, 0.5]);
        let expected = (0.25 / (1.0 + REL_MSE_EPSILON) + 0.25 / REL_MSE_EPSILON) / 2.0;
        assert!((rel_mse(&x, &r).unwrap() - expected).abs() < 1e-12);
        assert_eq!(rel_mse(&r, &r), Some(0.0));
        assert_eq!(rel_mse(&image(&[1.0]), &r), None);
    }

    #[test]
    fn halves_of_a_reference_give_its_noise() {
        // Halves of R/2 samples differing by ±d: their mean has noise d²/4 per pixel.
        let (a, b) = (image(&[1.2, 0.8]), image(&[0.8, 1.2]));
        let noise = reference_noise(&a, &b).unwrap();
        assert!((noise - rel_mse(&a, &b).unwrap() / 4.0).abs() < 1e-15);
        assert!(noise > 0.0);
    }

    #[test]
    fn the_fit_finds_the_power_law_and_its_uncertainty() {
        let pts: Vec<_> = [1.0, 2.0, 4.0, 8.0, 16.0]
            .iter()
            .map(|&n: &f64| (n, 0.3 / n, 0.03 / n))
            .collect();
        let fit = log_log_fit(&pts).unwrap();
        assert!((fit.slope + 1.0).abs() < 1e-12, "{fit:?}");
        // 10 % standard errors over a decade and a bit of spp: a few hundredths.
        assert!(fit.slope_se > 0.01 && fit.slope_se < 0.1, "{fit:?}");
        let steeper: Vec<_> = pts.iter().map(|p| (p.0, p.1 / p.0.sqrt(), p.2)).collect();
        assert!((log_log_fit(&steeper).unwrap().slope + 1.5).abs() < 1e-12);
        assert!(log_log_fit(&pts[..1]).is_none());
    }

    #[test]
    fn time_at_error_interpolates_and_extrapolates_power_laws() {
        // error = 1 / time: the time for an error is its inverse, inside and outside.
        let curve: Vec<_> = [1.0, 2.0, 4.0, 8.0]
            .iter()
            .map(|&t: &f64| (1.0 / t, t))
            .collect();
        for e in [0.6, 0.3, 0.125, 0.05, 2.0] {
            let t = time_at_error(&curve, e, -1.0).unwrap();
            assert!((t - 1.0 / e).abs() < 1e-9 * t, "{e}: {t}");
        }
        // Beyond the end the given slope rules: error ∝ time^-2 halves the extra time.
        let t = time_at_error(&curve, 0.125 / 4.0, -2.0).unwrap();
        assert!((t - 16.0).abs() < 1e-9, "{t}");
        assert!(time_at_error(&curve[..1], 0.5, -1.0).is_none());
        assert!(time_at_error(&curve, 0.0, -1.0).is_none());
        assert!(time_at_error(&curve, 0.5, 0.0).is_none());
    }

    #[test]
    fn nothing_to_measure_gives_no_rows() {
        assert!(table(&[], 64, 1.0).is_empty());
        assert!(table(&unbiased(0.0, 0.0, 64), 64, 1.0).is_empty());
        assert!(table(&unbiased(0.5, 0.0, 64), 64, 0.0).is_empty());
    }
}
