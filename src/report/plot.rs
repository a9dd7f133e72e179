//! Convergence plots (relMSE vs time, log-log) drawn as SVG with plotters.

use plotters::prelude::*;

use super::manifest::ConvergenceSeries;

/// One method's curves: its name, colour index and one series per seed.
pub(crate) struct Curves<'a> {
    pub(crate) name: &'a str,
    pub(crate) series: &'a [ConvergenceSeries],
}

/// A qualitative palette (Okabe-Ito, then Tableau) cycled over methods; also used by the page.
pub(crate) const PALETTE: [(u8, u8, u8); 10] = [
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

/// The median over seeds of time and relMSE at each sample index, when every series has the
/// same number of samples (all positive); empty otherwise.
fn median_curve(series: &[ConvergenceSeries]) -> Vec<(f64, f64)> {
    let Some(first) = series.first() else {
        return Vec::new();
    };
    let n = first.points.len();
    let usable = |s: &ConvergenceSeries| {
        s.points.len() == n && s.points.iter().all(|p| p.time_s > 0.0 && p.relmse > 0.0)
    };
    if !series.iter().all(usable) {
        return Vec::new();
    }
    (0..n)
        .filter_map(|i| {
            let times: Vec<f64> = series.iter().map(|s| s.points[i].time_s).collect();
            let errors: Vec<f64> = series.iter().map(|s| s.points[i].relmse).collect();
            let (t, _, _) = render::metrics::median_min_max(&times)?;
            let (e, _, _) = render::metrics::median_min_max(&errors)?;
            Some((t, e))
        })
        .collect()
}

/// An SVG (without the `xmlns` attribute, for inlining in HTML) plotting relMSE against time on
/// log-log axes, one thin line per seed and a thick median line, coloured per method. `None` when no method has a sample
/// with positive time and error.
pub(crate) fn convergence_svg(curves: &[Curves<'_>]) -> Result<Option<String>, String> {
    let positive = |p: &&super::manifest::ConvergencePoint| p.time_s > 0.0 && p.relmse > 0.0;
    let points = curves
        .iter()
        .flat_map(|c| c.series.iter())
        .flat_map(|s| s.points.iter().filter(positive));
    let (mut t0, mut t1, mut e0, mut e1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    let mut any = false;
    for p in points {
        any = true;
        t0 = t0.min(p.time_s);
        t1 = t1.max(p.time_s);
        e0 = e0.min(p.relmse);
        e1 = e1.max(p.relmse);
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
            .caption("relMSE vs render time (log-log)", ("sans-serif", 18))
            .build_cartesian_2d((t0..t1).log_scale(), (e0..e1).log_scale())
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc("time [s]")
            .y_desc("relMSE")
            .x_label_formatter(&|v| format!("{v:.3}"))
            .y_label_formatter(&|v| format!("{v:.1e}"))
            .draw()
            .map_err(|e| err(&e))?;
        for (i, c) in curves.iter().enumerate() {
            let (r, g, b) = PALETTE[i % PALETTE.len()];
            let colour = RGBColor(r, g, b);
            for s in c.series {
                let line: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .filter(positive)
                    .map(|p| (p.time_s, p.relmse))
                    .collect();
                chart
                    .draw_series(LineSeries::new(line, colour.mix(0.35).stroke_width(1)))
                    .map_err(|e| err(&e))?;
            }
            let median = median_curve(c.series);
            let drawn = chart
                .draw_series(LineSeries::new(median, colour.stroke_width(3)).point_size(3))
                .map_err(|e| err(&e))?;
            drawn.label(c.name).legend(move |(x, y)| {
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
