//! Line plots as PNG (plotters, drawn into memory and written atomically): the benchmark's
//! frame time along the camera path. The font (DejaVu Sans, assets/fonts with its licence)
//! is built in, so a machine without fonts draws the same plot.

use anyhow::{Result, anyhow};
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use std::path::Path;

const FONT: &[u8] = include_bytes!("../../../../assets/fonts/DejaVuSans.ttf");

/// One named series of (x, y) points.
pub(crate) struct Series {
    pub(crate) name: String,
    pub(crate) points: Vec<(f64, f64)>,
}

/// How the axes map values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Axes {
    /// Linear x from the data's least to its greatest value, linear y from 0.
    Linear,
    /// Logarithmic x and y over the data's positive values (powers of ten marked).
    LogLog,
}

/// Plots `series` as lines on linear axes into a `size` PNG at `path`.
pub(crate) fn line_plot(
    path: &Path,
    size: (u32, u32),
    title: &str,
    labels: (&str, &str),
    series: &[Series],
) -> Result<()> {
    plot(path, size, title, labels, series, Axes::Linear)
}

/// Plots `series` as lines on `axes` into a `size` PNG at `path` (points a log axis cannot
/// show, ≤ 0, are left out).
pub(crate) fn plot(
    path: &Path,
    size: (u32, u32),
    title: &str,
    labels: (&str, &str),
    series: &[Series],
    axes: Axes,
) -> Result<()> {
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    let series: Vec<Series> = series
        .iter()
        .map(|s| Series {
            name: s.name.clone(),
            points: s
                .points
                .iter()
                .copied()
                .filter(|p| {
                    p.0.is_finite()
                        && p.1.is_finite()
                        && (axes == Axes::Linear || (p.0 > 0.0 && p.1 > 0.0))
                })
                .collect(),
        })
        .collect();
    let all = || series.iter().flat_map(|s| s.points.iter());
    let (x0, x1) = all().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
        (a.min(p.0), b.max(p.0))
    });
    let (ymin, ymax) = all().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.1), b.max(p.1))
    });
    if !(x0 < x1 && ymax > 0.0) {
        return Err(anyhow!("nothing to plot in {title}"));
    }
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        match axes {
            Axes::Linear => draw(
                &root,
                (title, labels, SeriesLabelPosition::UpperLeft),
                &series,
                x0..x1,
                0.0..ymax * 1.08,
            )?,
            Axes::LogLog => {
                let (y0, y1) = if ymin < ymax {
                    (ymin / 1.3, ymax * 1.3)
                } else {
                    (ymin / 2.0, ymax * 2.0)
                };
                draw(
                    &root,
                    (title, labels, SeriesLabelPosition::UpperRight),
                    &series,
                    (x0..x1).log_scale(),
                    (y0..y1).log_scale(),
                )?
            }
        }
    }
    app::atomic::write_atomic(path, |w| {
        render::image::write_png_rgb8(w, size.0, size.1, &rgb)
    })?;
    Ok(())
}

/// Draws the chart: axes, one line per series, the legend.
fn draw<X, Y>(
    root: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    (title, (x_label, y_label), legend): (&str, (&str, &str), SeriesLabelPosition),
    series: &[Series],
    x: X,
    y: Y,
) -> Result<()>
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let e = |e: DrawingAreaErrorKind<_>| anyhow!("drawing {title}: {e}");
    root.fill(&WHITE).map_err(e)?;
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(72)
        .build_cartesian_2d(x, y)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", 15))
        .draw()
        .map_err(e)?;
    for (i, s) in series.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        chart
            .draw_series(LineSeries::new(
                s.points.iter().copied(),
                colour.stroke_width(2),
            ))
            .map_err(e)?
            .label(s.name.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 22, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .position(legend)
        .label_font(("sans-serif", 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

/// A tick label: plain decimals from 0.001 to 9999 (as many places as the value needs, at
/// most three significant digits), else scientific notation.
fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.abs().log10().floor();
    if (-3.0..4.0).contains(&e) {
        let places = (2.0 - e).max(0.0) as usize;
        let s = format!("{v:.places$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{v:.1e}")
    }
}

#[cfg(test)]
mod tests {
    use super::tick;

    #[test]
    fn ticks_are_short() {
        assert_eq!(tick(0.30000000004), "0.3");
        assert_eq!(tick(0.035), "0.035");
        assert_eq!(tick(10.0), "10");
        assert_eq!(tick(256.0), "256");
        assert_eq!(tick(2.5), "2.5");
        assert_eq!(tick(1.5e-5), "1.5e-5");
        assert_eq!(tick(0.0), "0");
    }
}
