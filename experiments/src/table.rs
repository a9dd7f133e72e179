//! Markdown tables and the summaries they hold: median [min, max] over seeds and ratios to a
//! baseline.

use std::fmt::Write as _;

use crate::record::Measure;

/// A GitHub-flavoured markdown table: a header row and rows of cells.
///
/// # Example
/// ```
/// use experiments::Table;
///
/// let mut t = Table::new(["method", "relMSE"]);
/// t.push_row(["PT", "0.0123"]);
/// t.push_row(["a | b", "0.5"]);
/// assert_eq!(
///     t.to_markdown(),
///     "| method | relMSE |\n|---|---|\n| PT | 0.0123 |\n| a \\| b | 0.5 |\n"
/// );
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Table {
    headers: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column headings and no rows.
    #[must_use]
    pub fn new<S: Into<String>>(headers: impl IntoIterator<Item = S>) -> Self {
        Self {
            headers: headers.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row; missing cells are left empty, extra cells are kept (and widen the
    /// table's rows, not its header).
    pub fn push_row<S: Into<String>>(&mut self, cells: impl IntoIterator<Item = S>) {
        self.rows.push(cells.into_iter().map(Into::into).collect());
    }

    /// The column headings.
    #[must_use]
    pub fn headers(&self) -> &[String] {
        &self.headers
    }

    /// The rows, in insertion order.
    #[must_use]
    pub fn rows(&self) -> &[Vec<String>] {
        &self.rows
    }

    /// The table as markdown, one line per row, `|` inside a cell escaped.
    #[must_use]
    pub fn to_markdown(&self) -> String {
        let line = |cells: &[String], width: usize| {
            let mut s = String::from("|");
            for i in 0..width.max(cells.len()) {
                let cell = cells.get(i).map_or("", String::as_str);
                let _ = write!(s, " {} |", cell.replace('|', "\\|"));
            }
            s.push('\n');
            s
        };
        let width = self.headers.len();
        let mut out = line(&self.headers, width);
        out.push('|');
        out.push_str(&"---|".repeat(width));
        out.push('\n');
        for row in &self.rows {
            out.push_str(&line(row, width));
        }
        out
    }
}

/// `median [min, max]` of `values` in `measure`'s format; `-` for no values.
///
/// # Example
/// ```
/// use experiments::{median_range, Measure};
///
/// assert_eq!(median_range(Measure::RelMse, &[0.02, 0.01, 0.04]), "0.0200 [0.0100, 0.0400]");
/// assert_eq!(median_range(Measure::RelMse, &[]), "-");
/// ```
#[must_use]
pub fn median_range(measure: Measure, values: &[f64]) -> String {
    match render::metrics::median_min_max(values) {
        Some((median, min, max)) => format!(
            "{} [{}, {}]",
            measure.format(median),
            measure.format(min),
            measure.format(max)
        ),
        None => "-".to_owned(),
    }
}

/// The median of `values` (NaN for none): the statistic the paper examples report over seeds,
/// because MCMC errors are heavy-tailed.
#[must_use]
pub fn median(values: &[f64]) -> f64 {
    render::metrics::median_min_max(values).map_or(f64::NAN, |s| s.0)
}

/// `value / baseline` with two decimals (`x0.53` style without the `x`), `-` when either is
/// not a positive finite number.
///
/// # Example
/// ```
/// assert_eq!(experiments::ratio(0.01, 0.02), "0.50");
/// assert_eq!(experiments::ratio(0.01, 0.0), "-");
/// ```
#[must_use]
pub fn ratio(value: f64, baseline: f64) -> String {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    if ok(value) && ok(baseline) {
        format!("{:.2}", value / baseline)
    } else {
        "-".to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_and_long_rows_keep_the_shape() {
        let mut t = Table::new(["a", "b", "c"]);
        t.push_row(["1"]);
        t.push_row(["1", "2", "3", "4"]);
        assert_eq!(
            t.to_markdown(),
            "| a | b | c |\n|---|---|---|\n| 1 |  |  |\n| 1 | 2 | 3 | 4 |\n"
        );
        assert_eq!(t.rows().len(), 2);
        assert_eq!(t.headers()[2], "c");
    }

    #[test]
    fn medians_of_even_counts_average_the_middle_pair() {
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(&[]).is_nan());
        assert_eq!(
            median_range(Measure::Acceptance, &[0.5, 0.25]),
            "0.375 [0.250, 0.500]"
        );
        assert_eq!(ratio(3.0, 2.0), "1.50");
        assert_eq!(ratio(f64::NAN, 2.0), "-");
    }
}
