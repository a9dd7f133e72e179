//! The record one job-list run leaves in its scene's run directory,
//! `runs/seed<seed>.json`: every method's [`RunRecord`] of the (scene, seed) slot and what the
//! run was made with, so `--collect` can rebuild the experiment's results without rendering.

use std::path::{Path, PathBuf};

use mcmc_core::stats::AcceptanceStats;
use render::metrics::Metrics;
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::load::LoadAverage;
use crate::plan::Plan;
use crate::record::RunRecord;
use crate::report::ConvergencePoint;
use crate::stats::{LargeStepStats, RunStats};
use crate::sweep::joblist::{read_bounded, write_atomic};
use crate::sweep::mode::RunId;
use crate::ExperimentError;

/// The value of [`SlotRecord::format`] this version writes and reads.
const RECORD_FORMAT: &str = "chainlight-run/1";

/// `runs/seed<seed>.json`: one run of a job list.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SlotRecord {
    /// [`RECORD_FORMAT`].
    format: String,
    /// The run's id.
    pub(crate) id: String,
    /// The experiment's name.
    pub(crate) experiment: String,
    /// The regime's label (`64spp`, `2s`).
    pub(crate) regime: String,
    /// Image side in pixels.
    pub(crate) size: u32,
    /// The methods, in the order they ran.
    pub(crate) methods: Vec<String>,
    /// The commit the run was made from.
    pub(crate) commit: String,
    /// Wall-clock seconds of the whole run (every method, convergence renders included).
    pub(crate) wall_seconds: Num,
    /// Every method's final render.
    records: Vec<Record>,
}

impl SlotRecord {
    /// The record of run `id` of `plan`: `records` of `methods`.
    pub(crate) fn new(
        id: &RunId,
        plan: &Plan,
        methods: Vec<String>,
        commit: String,
        wall_seconds: f64,
        records: &[RunRecord],
    ) -> Self {
        Self {
            format: RECORD_FORMAT.into(),
            id: id.to_string(),
            experiment: plan.name.clone(),
            regime: plan.regime.label(),
            size: plan.size,
            methods,
            commit,
            wall_seconds: Num(wall_seconds),
            records: records.iter().map(Record::from).collect(),
        }
    }

    /// `<run dir>/runs/seed<seed>.json`.
    pub(crate) fn path(run_dir: &Path, seed: u64) -> PathBuf {
        run_dir.join("runs").join(format!("seed{seed}.json"))
    }

    /// Writes the record (replaced atomically).
    pub(crate) fn write(&self, path: &Path) -> Result<(), ExperimentError> {
        let json = serde_json::to_string_pretty(self).expect("a run record serialises");
        write_atomic(path, format!("{json}\n").as_bytes())
    }

    /// Reads a record; `None` if the file does not exist.
    pub(crate) fn read(path: &Path) -> Result<Option<Self>, ExperimentError> {
        if !path.exists() {
            return Ok(None);
        }
        let slot: Self = serde_json::from_str(&read_bounded(path)?)
            .map_err(|e| ExperimentError::format(path, e))?;
        if slot.format != RECORD_FORMAT {
            let m = format!("format {:?}, expected {RECORD_FORMAT:?}", slot.format);
            return Err(ExperimentError::format(path, m));
        }
        Ok(Some(slot))
    }

    /// The records, checked to be run `id` of `plan` with `methods`: a record made with
    /// another budget, size or method list is refused, naming what differs.
    pub(crate) fn records_for(
        self,
        path: &Path,
        id: &RunId,
        plan: &Plan,
        methods: &[String],
    ) -> Result<Vec<RunRecord>, ExperimentError> {
        let differs = |what: &str, recorded: String, now: String| {
            Err(ExperimentError::format(
                path,
                format!("recorded with {what} {recorded}, this experiment has {now}: run the job again (--run-one {id})"),
            ))
        };
        if self.id != id.to_string() {
            return differs("the id", self.id, id.to_string());
        }
        if self.experiment != plan.name {
            return differs("the experiment", self.experiment, plan.name.clone());
        }
        if self.regime != plan.regime.label() {
            return differs("the budget", self.regime, plan.regime.label());
        }
        if self.size != plan.size {
            return differs("the size", self.size.to_string(), plan.size.to_string());
        }
        if self.methods != methods {
            return differs(
                "the methods",
                format!("{:?}", self.methods),
                format!("{methods:?}"),
            );
        }
        let records = self
            .records
            .into_iter()
            .map(Record::into_run_record)
            .collect::<Result<Vec<_>, _>>()
            .map_err(|m| ExperimentError::format(path, m))?;
        let expected = methods
            .iter()
            .map(|m| (id.scene.as_str(), m.as_str(), id.seed));
        let found = records
            .iter()
            .map(|r| (r.scene.as_str(), r.method.as_str(), r.seed));
        if !found.eq(expected) {
            return Err(ExperimentError::format(
                path,
                format!("its records are not one per method of {id} in order"),
            ));
        }
        Ok(records)
    }
}

/// A number that may be NaN or infinite (JSON numbers cannot), stored as a string: finite
/// values in Rust's shortest round-trip form (parsed back exactly by `str::parse`, whatever
/// float parser the JSON library uses), the others as `"NaN"`, `"inf"` and `"-inf"`. Plain
/// JSON numbers are read too.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Num(pub(crate) f64);

impl PartialEq for Num {
    /// Bitwise: a NaN equals itself.
    fn eq(&self, other: &Self) -> bool {
        self.0.to_bits() == other.0.to_bits()
    }
}

impl Serialize for Num {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self.0 {
            v if v.is_finite() => s.serialize_str(&format!("{v:?}")),
            v if v.is_nan() => s.serialize_str("NaN"),
            v if v > 0.0 => s.serialize_str("inf"),
            _ => s.serialize_str("-inf"),
        }
    }
}

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Repr {
            Number(f64),
            Text(String),
        }
        match Repr::deserialize(d)? {
            Repr::Number(v) => Ok(Self(v)),
            Repr::Text(t) => match t.as_str() {
                "NaN" => Ok(Self(f64::NAN)),
                "inf" => Ok(Self(f64::INFINITY)),
                "-inf" => Ok(Self(f64::NEG_INFINITY)),
                _ if t
                    .bytes()
                    .all(|b| b.is_ascii_digit() || b"+-.eE".contains(&b)) =>
                {
                    t.parse::<f64>()
                        .map(Self)
                        .map_err(|_| D::Error::custom(format!("{t:?} is not a number")))
                }
                _ => Err(D::Error::custom(format!(
                    "expected a number, NaN, inf or -inf, got {t:?}"
                ))),
            },
        }
    }
}

/// [`RunRecord`] as stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Record {
    scene: String,
    method: String,
    seed: u64,
    seconds: Num,
    samples: u64,
    /// MSE, RMSE, relMSE, rRMSE, MAD.
    metrics: [Num; 5],
    stats: Stats,
    /// The 1-, 5- and 15-minute load averages.
    load: Option<[Num; 3]>,
    image: PathBuf,
    /// (seconds, relMSE) pairs.
    convergence: Vec<[Num; 2]>,
}

/// [`RunStats`] as stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Stats {
    b: Option<Num>,
    b_standard_error: Option<Num>,
    acceptance: Option<Num>,
    mutations: Option<u64>,
    /// eta_s, eta_l, eta_0, p_large.
    large_step: Option<[Num; 4]>,
    acceptance_counts: Option<Counts>,
}

/// [`AcceptanceStats`] as stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Counts {
    steps: u64,
    proposed: Vec<u64>,
    accepted: Vec<u64>,
    accept_prob_sum: Vec<Num>,
    stage_tried: Vec<u64>,
    stage_accepted: Vec<u64>,
    non_finite: u64,
    stage_accept_prob_sum: Vec<Num>,
    move_prob_sum: Vec<Num>,
}

/// `values` as stored numbers.
fn nums<const N: usize>(values: [f64; N]) -> [Num; N] {
    values.map(Num)
}

/// Stored numbers as values.
fn values<const N: usize>(nums: [Num; N]) -> [f64; N] {
    nums.map(|n| n.0)
}

/// A stored array back in an array of the counts' length (the build's constants).
fn array<T: Copy, const N: usize>(stored: &[T], what: &str) -> Result<[T; N], String> {
    stored
        .try_into()
        .map_err(|_| format!("{what} has {} entries, this build counts {N}", stored.len()))
}

impl From<&RunRecord> for Record {
    fn from(r: &RunRecord) -> Self {
        let m = r.metrics;
        let s = r.stats;
        Self {
            scene: r.scene.clone(),
            method: r.method.clone(),
            seed: r.seed,
            seconds: Num(r.seconds),
            samples: r.samples,
            metrics: nums([m.mse, m.rmse, m.relmse, m.rrmse, m.mad]),
            stats: Stats {
                b: s.b.map(Num),
                b_standard_error: s.b_standard_error.map(Num),
                acceptance: s.acceptance.map(Num),
                mutations: s.mutations,
                large_step: s
                    .large_step
                    .map(|l| nums([l.eta_s, l.eta_l, l.eta_0, l.p_large])),
                acceptance_counts: s.acceptance_counts.map(|a| Counts {
                    steps: a.steps,
                    proposed: a.proposed.to_vec(),
                    accepted: a.accepted.to_vec(),
                    accept_prob_sum: a.accept_prob_sum.map(Num).to_vec(),
                    stage_tried: a.stage_tried.to_vec(),
                    stage_accepted: a.stage_accepted.to_vec(),
                    non_finite: a.non_finite,
                    stage_accept_prob_sum: a.stage_accept_prob_sum.map(Num).to_vec(),
                    move_prob_sum: a.move_prob_sum.map(Num).to_vec(),
                }),
            },
            load: r.load.map(|l| nums([l.one, l.five, l.fifteen])),
            image: r.image.clone(),
            convergence: r
                .convergence
                .iter()
                .map(|p| nums([p.time_s, p.relmse]))
                .collect(),
        }
    }
}

impl Record {
    /// The run record, or what does not fit this build's counts.
    fn into_run_record(self) -> Result<RunRecord, String> {
        let r = self;
        let [mse, rmse, relmse, rrmse, mad] = values(r.metrics);
        let s = r.stats;
        let f = |v: &[Num]| v.iter().map(|n| n.0).collect::<Vec<f64>>();
        let acceptance_counts = match s.acceptance_counts {
            None => None,
            Some(a) => Some(AcceptanceStats {
                steps: a.steps,
                proposed: array(&a.proposed, "proposed")?,
                accepted: array(&a.accepted, "accepted")?,
                accept_prob_sum: array(&f(&a.accept_prob_sum), "accept_prob_sum")?,
                stage_tried: array(&a.stage_tried, "stage_tried")?,
                stage_accepted: array(&a.stage_accepted, "stage_accepted")?,
                non_finite: a.non_finite,
                stage_accept_prob_sum: array(
                    &f(&a.stage_accept_prob_sum),
                    "stage_accept_prob_sum",
                )?,
                move_prob_sum: array(&f(&a.move_prob_sum), "move_prob_sum")?,
            }),
        };
        Ok(RunRecord {
            scene: r.scene,
            method: r.method,
            seed: r.seed,
            seconds: r.seconds.0,
            samples: r.samples,
            metrics: Metrics {
                mse,
                rmse,
                relmse,
                rrmse,
                mad,
            },
            stats: RunStats {
                b: s.b.map(|n| n.0),
                b_standard_error: s.b_standard_error.map(|n| n.0),
                acceptance: s.acceptance.map(|n| n.0),
                mutations: s.mutations,
                large_step: s
                    .large_step
                    .map(values)
                    .map(|[eta_s, eta_l, eta_0, p_large]| LargeStepStats {
                        eta_s,
                        eta_l,
                        eta_0,
                        p_large,
                    }),
                acceptance_counts,
            },
            load: r
                .load
                .map(values)
                .map(|[one, five, fifteen]| LoadAverage { one, five, fifteen }),
            image: r.image,
            convergence: r
                .convergence
                .into_iter()
                .map(|p| {
                    let [time_s, relmse] = values(p);
                    ConvergencePoint { time_s, relmse }
                })
                .collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_numbers_round_trip_and_unknown_words_are_refused() {
        for v in [
            0.1 + 0.2,
            -0.0,
            1e-300,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            let text = serde_json::to_string(&Num(v)).unwrap();
            let back: Num = serde_json::from_str(&text).unwrap();
            assert_eq!(back, Num(v), "{text}");
        }
        // Negative control: a plain f64 loses NaN (serde_json writes null).
        assert_eq!(serde_json::to_string(&f64::NAN).unwrap(), "null");
        let e = serde_json::from_str::<Num>("\"nan\"")
            .unwrap_err()
            .to_string();
        assert!(e.contains("expected a number, NaN, inf or -inf"), "{e}");
    }

    #[test]
    fn counts_of_another_length_are_refused() {
        let ok: Result<[u64; 2], String> = array(&[1, 2], "proposed");
        assert_eq!(ok, Ok([1, 2]));
        let e = array::<u64, 2>(&[1, 2, 3], "proposed").unwrap_err();
        assert_eq!(e, "proposed has 3 entries, this build counts 2");
    }
}
