//! Error-vs-time plots: log-log SVG line charts of several methods over seeds (plotters).
//!
//! The report's convergence plot is one of these; an example can draw its own (an
//! error-vs-time ladder, say) with [`log_log_svg`] or [`write_log_log_svg`].

use std::path::Path;

use plotters::prelude::*;

use crate::ExperimentError;

/// A qualitative palette (Okabe-Ito, then Tableau) cycled over methods; the report's page uses
/// the same colours.
const PALETTE: [(u8, u8, u8); 10] = [
    (0, 114, 178),
    (213, 94, 0),
    (0, 158, 115),
    (204, 121, 167),
    (230, 159, 0),
    (86, 180, 233),
    (120, 120, 120),
    (240, 228, 66),
    (148, 103, 189),
    (140, 86, 75),
];

/// The colour of method `i` as CSS `rgb(..)`.
pub(crate) fn css_colour(i: usize) -> String {
    let (r, g, b) = PALETTE[i % PALETTE.len()];
    format!("rgb({r},{g},{b})")
}

/// The smallest time or error a log-log plot draws.
pub const MIN_PLOTTED: f64 = 1e-150;

/// The largest time or error a log-log plot draws. With [`MIN_PLOTTED`] it keeps the padded
/// axis ranges, and their ratio, finite (plotters' logarithmic axes never finish on an
/// infinite range).
pub const MAX_PLOTTED: f64 = 1e150;

/// True for a sample a log-log plot can draw: time and error in
/// [`MIN_PLOTTED`]`..=`[`MAX_PLOTTED`].
fn drawable(&(t, e): &(f64, f64)) -> bool {
    let ok = |v: f64| (MIN_PLOTTED..=MAX_PLOTTED).contains(&v);
    ok(t) && ok(e)
}

/// One method's lines: its name and one series of `(time, error)` samples per seed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Curve {
    /// Legend label.
    pub name: String,
    /// One series per seed, in increasing time; samples outside
    /// [`MIN_PLOTTED`]`..=`[`MAX_PLOTTED`] (zero, say) are not drawn.
    pub series: Vec<Vec<(f64, f64)>>,
}

/// Titles of a [`log_log_svg`] chart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Axes<'a> {
    /// The caption above the chart.
    pub caption: &'a str,
    /// The horizontal axis (time).
    pub x_label: &'a str,
    /// The vertical axis (error).
    pub y_label: &'a str,
}

impl Axes<'static> {
    /// relMSE against render time: the report's convergence plot.
    pub const RELMSE_VS_TIME: Axes<'static> = Axes {
        caption: "relMSE vs render time (log-log)",
        x_label: "time [s]",
        y_label: "relMSE",
    };
}

/// The median over seeds of time and error at each sample index, when every series has the
/// same number of samples (all drawable); empty otherwise.
fn median_curve(series: &[Vec<(f64, f64)>]) -> Vec<(f64, f64)> {
    let Some(first) = series.first() else {
        return Vec::new();
    };
    let n = first.len();
    let usable = |s: &Vec<(f64, f64)>| s.len() == n && s.iter().all(drawable);
    if !series.iter().all(usable) {
        return Vec::new();
    }
    (0..n)
        .filter_map(|i| {
            let times: Vec<f64> = series.iter().map(|s| s[i].0).collect();
            let errors: Vec<f64> = series.iter().map(|s| s[i].1).collect();
            let (t, _, _) = render::metrics::median_min_max(&times)?;
            let (e, _, _) = render::metrics::median_min_max(&errors)?;
            Some((t, e))
        })
        .collect()
}

/// An SVG (without the `xmlns` attribute, for inlining in HTML) plotting error against time on
/// log-log axes, one thin line per seed and a thick median line, coloured per curve. `None`
/// when no curve has a drawable sample (time and error in
/// [`MIN_PLOTTED`]`..=`[`MAX_PLOTTED`]).
///
/// # Errors
/// A message when plotters fails to draw.
pub fn log_log_svg(axes: Axes<'_>, curves: &[Curve]) -> Result<Option<String>, String> {
    let positive = |p: &&(f64, f64)| drawable(p);
    let points = curves
        .iter()
        .flat_map(|c| c.series.iter())
        .flat_map(|s| s.iter().filter(positive));
    let (mut t0, mut t1, mut e0, mut e1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    let mut any = false;
    for &(t, e) in points {
        any = true;
        (t0, t1, e0, e1) = (t0.min(t), t1.max(t), e0.min(e), e1.max(e));
    }
    if !any {
        return Ok(None);
    }
    // Pad the ranges by a factor (and widen degenerate ones) so that lines do not touch the frame.
    let (t0, t1) = (t0 / 1.3, t1 * 1.3);
    let (e0, e1) = (e0 / 1.5, e1 * 1.5);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 420)).into_drawing_area();
        let err = |e: &dyn std::fmt::Display| format!("convergence plot: {e}");
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .caption(axes.caption, ("sans-serif", 18))
            .build_cartesian_2d((t0..t1).log_scale(), (e0..e1).log_scale())
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(axes.x_label)
            .y_desc(axes.y_label)
            .x_label_formatter(&|v| format!("{v:.3}"))
            .y_label_formatter(&|v| format!("{v:.1e}"))
            .draw()
            .map_err(|e| err(&e))?;
        for (i, c) in curves.iter().enumerate() {
            let (r, g, b) = PALETTE[i % PALETTE.len()];
            let colour = RGBColor(r, g, b);
            for s in &c.series {
                let line: Vec<(f64, f64)> = s.iter().filter(positive).copied().collect();
                chart
                    .draw_series(LineSeries::new(line, colour.mix(0.35).stroke_width(1)))
                    .map_err(|e| err(&e))?;
            }
            let median = median_curve(&c.series);
            let drawn = chart
                .draw_series(LineSeries::new(median, colour.stroke_width(3)).point_size(3))
                .map_err(|e| err(&e))?;
            drawn.label(c.name.as_str()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(3))
            });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    // Inline SVG in HTML needs no namespace declaration; dropping it keeps the page free of URLs.
    Ok(Some(svg.replacen(
        " xmlns=\"http://www.w3.org/2000/svg\"",
        "",
        1,
    )))
}

/// Writes [`log_log_svg`] to `path` as a standalone SVG file (with its namespace, atomically).
/// Returns `false`, writing nothing, when there is no drawable sample.
///
/// # Errors
/// [`ExperimentError::Io`] if the file cannot be written, [`ExperimentError::Invalid`] if
/// plotting fails.
pub fn write_log_log_svg(
    path: impl AsRef<Path>,
    axes: Axes<'_>,
    curves: &[Curve],
) -> Result<bool, ExperimentError> {
    let path = path.as_ref();
    let Some(svg) = log_log_svg(axes, curves).map_err(ExperimentError::Invalid)? else {
        return Ok(false);
    };
    let svg = svg.replacen("<svg", "<svg xmlns=\"http://www.w3.org/2000/svg\"", 1);
    render::files::write_bytes_atomic(path, svg).map_err(|source| ExperimentError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(name: &str, scale: f64) -> Curve {
        Curve {
            name: name.into(),
            series: (1..=3)
                .map(|seed| {
                    (0..4)
                        .map(|k| {
                            let t = 0.5 * 2f64.powi(k);
                            (t, scale * f64::from(seed) / t)
                        })
                        .collect()
                })
                .collect(),
        }
    }

    #[test]
    fn median_curve_is_pointwise_and_needs_equal_lengths() {
        let c = curve("a", 1.0);
        let m = median_curve(&c.series);
        assert_eq!(m.len(), 4);
        assert_eq!(m[0], (0.5, 2.0 / 0.5));
        let mut ragged = c.series.clone();
        ragged[1].pop();
        assert!(median_curve(&ragged).is_empty());
    }

    #[test]
    fn svg_has_caption_and_legend_and_nothing_without_samples() {
        let svg = log_log_svg(
            Axes::RELMSE_VS_TIME,
            &[curve("low", 0.1), curve("high", 1.0)],
        )
        .unwrap()
        .unwrap();
        assert!(svg.starts_with("<svg") && !svg.contains("xmlns"));
        assert!(svg.contains("relMSE vs render time") && svg.contains("high"));
        let empty = Curve {
            name: "x".into(),
            series: vec![vec![(0.0, 1.0)]],
        };
        assert_eq!(log_log_svg(Axes::RELMSE_VS_TIME, &[empty]).unwrap(), None);
    }

    /// `log_log_svg` of `curves` on its own thread, failing the test if it takes more than a
    /// minute (a hang is the failure this guards against).
    fn plot_within_a_minute(curves: Vec<Curve>) -> Option<String> {
        let (send, receive) = std::sync::mpsc::channel();
        std::thread::spawn(move || send.send(log_log_svg(Axes::RELMSE_VS_TIME, &curves)));
        receive
            .recv_timeout(std::time::Duration::from_secs(60))
            .expect("the plot did not finish")
            .unwrap()
    }

    #[test]
    fn extreme_finite_samples_finish_and_are_left_out() {
        for extreme in [(1.0, 1e308), (1e-308, 1.0), (f64::MAX, f64::MIN_POSITIVE)] {
            // Alone: nothing drawable.
            let alone = Curve {
                name: "x".into(),
                series: vec![vec![extreme]],
            };
            assert_eq!(plot_within_a_minute(vec![alone]), None, "{extreme:?}");
            // With ordinary samples: a plot of those.
            let mut mixed = curve("mixed", 1.0);
            mixed.series[0].push(extreme);
            let svg = plot_within_a_minute(vec![mixed]).expect("a plot");
            assert!(svg.contains("mixed") && !svg.contains("inf") && !svg.contains("NaN"));
        }
        // The bounds themselves are drawn.
        let edges = Curve {
            name: "edges".into(),
            series: vec![vec![(MIN_PLOTTED, MAX_PLOTTED), (MAX_PLOTTED, MIN_PLOTTED)]],
        };
        assert!(plot_within_a_minute(vec![edges]).is_some());
    }
}
