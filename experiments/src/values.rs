//! Values an example measures per run beyond the harness's record (a learned scale's median,
//! an adaptation summary, ...), gathered in [`crate::Experiment::inspect`] and looked up by
//! scene, method and seed like [`crate::Results`]' measures.

use crate::record::RunRecord;
use crate::table::median;

/// One value of type `T` per run, keyed by the run's scene, method and seed.
///
/// # Example
/// ```
/// # let record = |method: &str, seed| experiments::RunRecord {
/// #     scene: "s".into(), method: method.into(), seed, seconds: 1.0, samples: 1,
/// #     metrics: render::metrics::Metrics { mse: 0.0, rmse: 0.0, relmse: 0.0, rrmse: 0.0, mad: 0.0 },
/// #     stats: Default::default(), load: None, image: "x.exr".into(), convergence: Vec::new(),
/// # };
/// use experiments::RunValues;
///
/// let mut sigma = RunValues::default();
/// sigma.push(&record("RA", 0), 0.1);
/// sigma.push(&record("RA", 1), 0.3);
/// sigma.push(&record("FIXED", 0), f64::NAN);
/// assert_eq!(sigma.get("s", "RA", 1), Some(&0.3));
/// assert!((sigma.median("s", "RA") - 0.2).abs() < 1e-12);
/// assert!(sigma.median("s", "FIXED").is_nan());
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct RunValues<T> {
    values: Vec<(String, String, u64, T)>,
}

impl<T> Default for RunValues<T> {
    fn default() -> Self {
        Self { values: Vec::new() }
    }
}

impl<T> RunValues<T> {
    /// Records `value` for `record`'s run (a second value for the same run is kept too;
    /// [`RunValues::get`] returns the first).
    pub fn push(&mut self, record: &RunRecord, value: T) {
        self.values.push((
            record.scene.clone(),
            record.method.clone(),
            record.seed,
            value,
        ));
    }

    /// The values of `method` on `scene` with their seeds, in the order recorded.
    pub fn of<'v>(
        &'v self,
        scene: &'v str,
        method: &'v str,
    ) -> impl Iterator<Item = (u64, &'v T)> + 'v {
        self.values
            .iter()
            .filter(move |v| v.0 == scene && v.1 == method)
            .map(|v| (v.2, &v.3))
    }

    /// The value of `method` on `scene` with `seed`.
    #[must_use]
    pub fn get(&self, scene: &str, method: &str, seed: u64) -> Option<&T> {
        self.values
            .iter()
            .find(|v| v.0 == scene && v.1 == method && v.2 == seed)
            .map(|v| &v.3)
    }
}

impl RunValues<f64> {
    /// The median over the seeds of `method` on `scene`, NaN values left out (NaN if none
    /// is left).
    #[must_use]
    pub fn median(&self, scene: &str, method: &str) -> f64 {
        let values: Vec<f64> = self
            .of(scene, method)
            .map(|(_, &v)| v)
            .filter(|v| !v.is_nan())
            .collect();
        median(&values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::tiny_experiment;

    #[test]
    fn values_are_found_by_scene_method_and_seed_only() {
        let (results, _) = tiny_experiment("values");
        let mut seconds = RunValues::default();
        for r in &results.records {
            seconds.push(r, r.seconds);
        }
        let pt: Vec<u64> = seconds.of("cornell-box", "PT").map(|(s, _)| s).collect();
        assert_eq!(pt, results.plan.seeds);
        let run = results.run("cornell-box", "BDPT", 2).unwrap();
        assert_eq!(seconds.get("cornell-box", "BDPT", 2), Some(&run.seconds));
        assert_eq!(
            seconds.median("cornell-box", "BDPT"),
            results.median("cornell-box", "BDPT", crate::Measure::Seconds)
        );
        // Negative controls: another scene, method or seed finds nothing.
        assert_eq!(seconds.get("other", "BDPT", 2), None);
        assert_eq!(seconds.get("cornell-box", "BDPT", 99), None);
        assert!(seconds.median("cornell-box", "nope").is_nan());
    }
}
