//! Whether one method beat another on a scene: medians over seeds and seed-by-seed wins
//! ([`Results::compare`]), for the orderings papers claim ("RA-QUADTREE <= RA-GRID").

use std::fmt;

use crate::record::Measure;
use crate::results::Results;

/// `method` against `other` on one scene in one measure (lower is better).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    /// The measure compared.
    pub measure: Measure,
    /// The median of `method` over its seeds.
    pub median: f64,
    /// The median of `other` over its seeds.
    pub other_median: f64,
    /// Seeds (run by both) where `method` was at most `other`.
    pub wins: usize,
    /// Seeds run by both.
    pub seeds: usize,
}

impl Comparison {
    /// True if the median of `method` is at most that of `other` (false if either is NaN).
    #[must_use]
    pub fn holds(&self) -> bool {
        self.median <= self.other_median
    }
}

impl fmt::Display for Comparison {
    /// `holds (0.0123 vs 0.0456; 3/5 seeds)` or `does not hold (...)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ({} vs {}; {}/{} seeds)",
            if self.holds() {
                "holds"
            } else {
                "does not hold"
            },
            self.measure.format(self.median),
            self.measure.format(self.other_median),
            self.wins,
            self.seeds
        )
    }
}

impl Results {
    /// Compares `method` with `other` on `scene` in `measure` (lower is better): both medians
    /// over seeds and on how many common seeds `method` was at most `other`.
    ///
    /// # Example
    /// The claim "BDPT <= PT in relMSE" on a scene:
    /// `println!("BDPT <= PT {}", results.compare(scene, "BDPT", "PT", Measure::RelMse))`
    /// prints e.g. `BDPT <= PT holds (0.0120 vs 0.0310; 3/3 seeds)`.
    #[must_use]
    pub fn compare(&self, scene: &str, method: &str, other: &str, measure: Measure) -> Comparison {
        let mut wins = 0;
        let mut seeds = 0;
        for run in self.runs(scene, method) {
            if let Some(o) = self.run(scene, other, run.seed) {
                seeds += 1;
                if measure.of(run) <= measure.of(o) {
                    wins += 1;
                }
            }
        }
        Comparison {
            measure,
            median: self.median(scene, method, measure),
            other_median: self.median(scene, other, measure),
            wins,
            seeds,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::tiny_experiment;

    #[test]
    fn medians_and_wins_and_the_reverse() {
        let (results, _) = tiny_experiment("compare");
        let s = "cornell-box";
        let c = results.compare(s, "BDPT", "PT", Measure::Seconds);
        let r = results.compare(s, "PT", "BDPT", Measure::Seconds);
        assert_eq!((c.seeds, r.seeds), (3, 3));
        assert_eq!(c.median, r.other_median);
        assert_eq!(c.holds(), c.median <= c.other_median);
        assert!(
            c.wins + r.wins >= 3,
            "every seed is won by one side (ties by both)"
        );
        let same = results.compare(s, "PT", "PT", Measure::RelMse);
        assert!(same.holds() && same.wins == 3);
        assert!(
            same.to_string().starts_with("holds (") && same.to_string().ends_with("3/3 seeds)")
        );
        // Negative control: an unknown method shares no seed and never holds.
        let none = results.compare(s, "nope", "PT", Measure::RelMse);
        assert_eq!((none.seeds, none.wins, none.holds()), (0, 0, false));
        assert!(none.to_string().starts_with("does not hold (- vs"));
    }
}
