//! When each method flag of `chainlight render` has an effect ([`RULES`]): a flag typed on the
//! command line that would change nothing for the chosen integrator and its other settings is
//! an error naming the flag, the integrator and where the flag applies.

use render::methods::MethodSettings;
use render::mlt::direct::DirectPass;
use render::mlt::dr::{DrBase, DrVariant};
use render::{IntegratorKind, INTEGRATORS};
use IntegratorKind as K;
use MethodSettings as M;

/// When one method flag has an effect.
pub(crate) struct FlagRule {
    /// The flag's clap id (the field of [`MethodFlags`]); the flag is `--` and the id with
    /// dashes for underscores.
    pub(crate) id: &'static str,
    /// True if the flag changes what a render with these settings does.
    pub(crate) applies: fn(&MethodSettings) -> bool,
    /// Where else it applies, beyond the integrators whose default settings it applies to
    /// (for the error message; empty if nowhere).
    pub(crate) also: &'static str,
}

impl FlagRule {
    /// The flag as typed, e.g. `--large-step`.
    pub(crate) fn flag(&self) -> String {
        format!("--{}", self.id.replace('_', "-"))
    }

    /// The integrators the flag applies to with their default settings, and `also`.
    pub(crate) fn applies_to(&self) -> String {
        let names: Vec<&str> = INTEGRATORS
            .iter()
            .filter(|row| (self.applies)(&row.kind.settings()))
            .map(|row| row.name)
            .collect();
        let mut text = names.join(", ");
        if !self.also.is_empty() {
            text.push_str("; ");
            text.push_str(self.also);
        }
        text
    }
}

/// The chain methods of primary sample space (what `ChainSettings` configures).
fn pss_chains(m: &MethodSettings) -> bool {
    matches!(m, M::Pssmlt(_) | M::Mmlt(_) | M::Drmlt(_) | M::Mala(_))
}

/// Delayed rejection's cheap-then-expensive variant: MALA (and the Kelemen small step beyond
/// its depths) on MMLT.
fn drmlt_langevin(m: &MethodSettings) -> bool {
    matches!(m, M::Drmlt(s) if s.variant == DrVariant::CheapThenExpensive)
}

/// The chain methods with a direct-lighting pass setting (PSSMLT over BDPT or the path
/// tracer, MMLT, Langevin MLT).
fn has_direct_pass(m: &MethodSettings) -> bool {
    matches!(m, M::Pssmlt(_) | M::Mmlt(_) | M::Mala(_))
        || (m.kind() == K::Drmlt && !drmlt_langevin(m))
}

/// A chain method with its direct-lighting pass on.
fn direct_pass_on(m: &MethodSettings) -> bool {
    let pass = match m {
        M::Pssmlt(s) => s.direct,
        M::Mmlt(s) => s.direct.pass,
        M::Mala(s) => s.direct.pass,
        M::Drmlt(s) if !drmlt_langevin(m) => s.direct.pass,
        _ => return false,
    };
    !matches!(pass, DirectPass::Off | DirectPass::Fixed(0))
}

/// Every method flag and when it has an effect (what `MethodFlags::apply` sets and the
/// method then reads).
pub(crate) const RULES: &[FlagRule] = &[
    FlagRule {
        id: "large_step",
        applies: pss_chains,
        also: "",
    },
    FlagRule {
        id: "large_step_mis",
        applies: |m| {
            matches!(m, M::Pssmlt(_) | M::Mmlt(_))
                || matches!(m, M::Drmlt(d) if d.variant != DrVariant::CheapThenExpensive)
        },
        also: "",
    },
    FlagRule {
        id: "raster_mutation",
        applies: |m| matches!(m, M::Pssmlt(_) | M::Mmlt(_)),
        also: "",
    },
    FlagRule {
        id: "chain_allocation",
        applies: |m| m.kind() == K::Mmlt,
        also: "",
    },
    FlagRule {
        id: "strategy_strata",
        applies: |m| m.kind() == K::Mmlt,
        also: "",
    },
    FlagRule {
        id: "bdpt_normalization",
        applies: |m| m.kind() == K::Mmlt,
        also: "",
    },
    FlagRule {
        id: "direct_samples",
        applies: has_direct_pass,
        also: "",
    },
    FlagRule {
        id: "direct_share",
        applies: has_direct_pass,
        also: "",
    },
    FlagRule {
        id: "direct_depth",
        applies: direct_pass_on,
        also: "not with --direct-samples 0 (no direct pass)",
    },
    FlagRule {
        id: "small_step",
        applies: |m| matches!(m, M::Pssmlt(_) | M::Mmlt(_) | M::Mala(_)) || drmlt_langevin(m),
        also: "drmlt with --dr-variant cheap-then-expensive (its other rules have their own \
               second-stage kernels)",
    },
    FlagRule {
        id: "chains",
        applies: |m| pss_chains(m) || m.kind() == K::PathMlt,
        also: "",
    },
    FlagRule {
        id: "bootstrap_samples",
        applies: |m| pss_chains(m) || m.kind() == K::PathMlt,
        also: "",
    },
    FlagRule {
        id: "normalization",
        applies: |m| pss_chains(m) || m.kind() == K::PathMlt,
        also: "",
    },
    FlagRule {
        id: "roulette",
        applies: |m| match m {
            M::Pt(_) | M::Qmc(_) | M::Bdpt(_) | M::Pssmlt(_) => true,
            // The all-strategy BDPT samples of the depth normalisation; MMLT's own paths have
            // a fixed length.
            M::Mmlt(s) => s.bdpt_normalization > 0,
            M::Drmlt(s) => s.on != DrBase::Mmlt && !drmlt_langevin(m),
            _ => false,
        },
        also: "mmlt with --bdpt-normalization N > 0; not drmlt with --dr-on mmlt or \
               --dr-variant cheap-then-expensive (fixed-length paths)",
    },
    FlagRule {
        id: "sampler",
        applies: |m| matches!(m, M::Pt(_) | M::Bdpt(_)) || direct_pass_on(m),
        also: "pssmlt, mmlt and mala* only with their direct pass (not with --direct-samples 0)",
    },
    FlagRule {
        id: "strategy_images",
        applies: |m| m.kind() == K::Bdpt,
        also: "",
    },
    FlagRule {
        id: "dr_variant",
        applies: |m| m.kind() == K::Drmlt,
        also: "",
    },
    FlagRule {
        id: "dr_on",
        applies: |m| m.kind() == K::Drmlt && !drmlt_langevin(m),
        also: "not with --dr-variant cheap-then-expensive (always on MMLT)",
    },
    FlagRule {
        id: "dr_fixed_strategy",
        applies: |m| matches!(m, M::Drmlt(s) if s.on == DrBase::Mmlt && s.variant == DrVariant::Orbital),
        also: "drmlt with --dr-on mmlt and --dr-variant orbital",
    },
    FlagRule {
        id: "perturbation",
        applies: |m| m.kind() == K::PathMlt,
        also: "",
    },
    FlagRule {
        id: "adapt",
        applies: |m| m.kind() == K::PathMlt,
        also: "",
    },
    FlagRule {
        id: "sigma",
        applies: |m| m.kind() == K::PathMlt,
        also: "",
    },
    FlagRule {
        id: "target_acceptance",
        applies: |m| m.kind() == K::PathMlt,
        also: "",
    },
    FlagRule {
        id: "mala_preset",
        applies: |m| matches!(m, M::Mala(_)) || drmlt_langevin(m),
        also: "drmlt with --dr-variant cheap-then-expensive",
    },
    FlagRule {
        id: "mala_kernel",
        applies: |m| matches!(m, M::Mala(_)),
        also: "",
    },
    FlagRule {
        id: "mala_max_depth",
        applies: |m| matches!(m, M::Mala(_)) || drmlt_langevin(m),
        also: "drmlt with --dr-variant cheap-then-expensive",
    },
    FlagRule {
        id: "mala_gradient",
        applies: |m| matches!(m, M::Mala(_)) || drmlt_langevin(m),
        also: "drmlt with --dr-variant cheap-then-expensive",
    },
    FlagRule {
        id: "lqmc_preset",
        applies: |m| m.kind() == K::Lqmc,
        also: "",
    },
];

/// Fails if a flag `given` on the command line has no effect on `method`, naming the flag, the
/// integrator and where the flag applies.
///
/// # Errors
/// The first such flag, as a message.
pub(crate) fn check_applicable(
    method: &MethodSettings,
    given: &dyn Fn(&str) -> bool,
) -> Result<(), String> {
    match RULES
        .iter()
        .find(|rule| given(rule.id) && !(rule.applies)(method))
    {
        None => Ok(()),
        Some(rule) => Err(format!(
            "{} does not apply to --integrator {} as configured (it would have no effect); \
             it applies to: {}",
            rule.flag(),
            method.kind().name(),
            rule.applies_to()
        )),
    }
}

#[cfg(test)]
mod tests {
    use clap::parser::ValueSource;
    use clap::{CommandFactory, FromArgMatches, Parser};

    use super::super::method_flags::MethodFlags;
    use super::*;

    /// The method flags alone, as `chainlight render` parses them.
    #[derive(Debug, Parser)]
    struct Flags {
        #[command(flatten)]
        method: MethodFlags,
    }

    /// Two valid values of each flag, with different effects (`None`: a switch, compared
    /// with leaving it off).
    const SAMPLES: &[(&str, Option<[&str; 2]>)] = &[
        ("large_step", Some(["0.5", "0.1"])),
        ("large_step_mis", Some(["on", "off"])),
        ("raster_mutation", Some(["on", "off"])),
        ("chain_allocation", Some(["joint", "per-depth"])),
        ("strategy_strata", Some(["on", "off"])),
        ("bdpt_normalization", Some(["1000", "2000"])),
        ("direct_samples", Some(["4", "8"])),
        ("direct_share", Some(["0.3", "0.5"])),
        ("direct_depth", Some(["1", "3"])),
        ("small_step", Some(["kelemen", "gaussian=0.01"])),
        ("chains", Some(["8", "16"])),
        ("bootstrap_samples", Some(["100", "200"])),
        ("normalization", Some(["bootstrap", "2.5"])),
        ("roulette", Some(["2", "off"])),
        ("sampler", Some(["independent", "sobol"])),
        ("strategy_images", None),
        ("dr_variant", Some(["green-mira", "tierney-mira"])),
        ("dr_on", Some(["mmlt", "pssmlt-pt"])),
        ("dr_fixed_strategy", None),
        ("perturbation", Some(["lens", "multichain"])),
        ("adapt", Some(["global", "grid"])),
        ("sigma", Some(["paper", "0.1"])),
        ("target_acceptance", Some(["0.8", "0.3"])),
        ("mala_preset", Some(["paper", "paper-values"])),
        ("mala_kernel", Some(["mala", "cheap-then-expensive"])),
        ("mala_max_depth", Some(["2", "4"])),
        ("mala_gradient", Some(["dual", "fd"])),
        ("lqmc_preset", Some(["code", "paper"])),
    ];

    const MCMC_PSS: &[&str] = &[
        "pssmlt",
        "pssmlt-pt",
        "mmlt",
        "drmlt",
        "mala",
        "mala-online",
        "mala-cache",
        "mala-hybrid",
    ];
    const MALA: &[&str] = &["mala", "mala-online", "mala-cache", "mala-hybrid"];

    /// Where each flag has an effect with the integrator's other settings at their defaults,
    /// written out from the methods' code independently of [`RULES`].
    fn expected(id: &str) -> Vec<&'static str> {
        let with = |base: &[&'static str], more: &[&'static str]| [base, more].concat();
        match id {
            "large_step" => MCMC_PSS.to_vec(),
            "large_step_mis" => vec!["pssmlt", "pssmlt-pt", "mmlt", "drmlt"],
            "raster_mutation" => vec!["pssmlt", "pssmlt-pt", "mmlt"],
            "chain_allocation" | "strategy_strata" | "bdpt_normalization" => vec!["mmlt"],
            // mmlt's pass is off by default: giving it samples or a share turns it on.
            "direct_samples" | "direct_share" => {
                with(MALA, &["pssmlt", "pssmlt-pt", "mmlt", "drmlt"])
            }
            "direct_depth" => with(MALA, &["pssmlt", "pssmlt-pt"]),
            // drmlt's default rule (orbital) has its own second-stage kernel.
            "small_step" => with(MALA, &["pssmlt", "pssmlt-pt", "mmlt"]),
            "chains" | "bootstrap_samples" | "normalization" => with(MCMC_PSS, &["pathmlt"]),
            "roulette" => vec![
                "pt",
                "bdpt",
                "pssmlt",
                "pssmlt-pt",
                "drmlt",
                "qmc",
                "qmc-faure",
            ],
            "sampler" => with(MALA, &["pt", "bdpt", "pssmlt", "pssmlt-pt"]),
            "strategy_images" => vec!["bdpt"],
            "dr_variant" | "dr_on" => vec!["drmlt"],
            // Only with --dr-on mmlt (not drmlt's default sampler).
            "dr_fixed_strategy" => vec![],
            "perturbation" | "adapt" | "sigma" | "target_acceptance" => vec!["pathmlt"],
            "mala_preset" | "mala_max_depth" | "mala_gradient" | "mala_kernel" => MALA.to_vec(),
            "lqmc_preset" => vec!["lqmc"],
            other => panic!("no expectation for {other}"),
        }
    }

    /// The settings of `integrator` with `args` typed.
    fn settings(integrator: &str, args: &[&str]) -> Result<MethodSettings, String> {
        let matches = Flags::command()
            .try_get_matches_from([&["flags"][..], args].concat())
            .unwrap_or_else(|e| panic!("{args:?}: {e}"));
        let flags = Flags::from_arg_matches(&matches).unwrap();
        let given = |id: &str| matches.value_source(id) == Some(ValueSource::CommandLine);
        let kind = IntegratorKind::from_name(integrator).unwrap();
        flags.method.settings(kind, &given)
    }

    /// The command-line words of flag `id` with value `value` (a switch has none).
    fn typed(id: &str, value: Option<&'static str>) -> Vec<String> {
        let mut words = vec![format!("--{}", id.replace('_', "-"))];
        words.extend(value.map(String::from));
        words
    }

    #[test]
    fn every_method_flag_has_a_rule_and_a_sample() {
        let command = Flags::command();
        let ids: Vec<&str> = command
            .get_arguments()
            .map(|a| a.get_id().as_str())
            .filter(|id| *id != "help")
            .collect();
        assert_eq!(ids.len(), RULES.len(), "{ids:?}");
        for id in ids {
            assert!(RULES.iter().any(|r| r.id == id), "{id} has no rule");
            assert!(SAMPLES.iter().any(|s| s.0 == id), "{id} has no sample");
        }
    }

    /// Every integrator x every flag: typed, the flag is accepted exactly where it has an
    /// effect; where accepted, its two sample values give different settings (the flag is
    /// really mapped); where refused, the message names the flag, the integrator and where it
    /// applies.
    #[test]
    fn every_flag_is_accepted_exactly_where_it_has_an_effect() {
        for row in INTEGRATORS {
            // Negative control: nothing typed, everything at its default, always accepted.
            assert_eq!(
                settings(row.name, &[]),
                Ok(row.kind.settings()),
                "{}",
                row.name
            );
            for &(id, values) in SAMPLES {
                let expect = expected(id).contains(&row.name);
                let [a, b] = values.map_or([None, None], |[a, b]| [Some(a), Some(b)]);
                let words = typed(id, a);
                let words: Vec<&str> = words.iter().map(String::as_str).collect();
                let result = settings(row.name, &words);
                assert_eq!(result.is_ok(), expect, "{} {words:?}: {result:?}", row.name);
                match result {
                    Ok(first) => {
                        let other = match b {
                            Some(b) => {
                                let words = typed(id, Some(b));
                                let words: Vec<&str> = words.iter().map(String::as_str).collect();
                                settings(row.name, &words).unwrap()
                            }
                            None => settings(row.name, &[]).unwrap(),
                        };
                        assert_ne!(first, other, "{} {id}: the flag changes nothing", row.name);
                    }
                    Err(message) => {
                        let rule = RULES.iter().find(|r| r.id == id).unwrap();
                        assert!(
                            message.contains(&rule.flag())
                                && message.contains(&format!("--integrator {}", row.name))
                                && message.contains(&rule.applies_to()),
                            "{message}"
                        );
                    }
                }
            }
        }
    }

    /// Flags whose effect depends on another setting of the same integrator.
    #[test]
    fn conditional_flags_follow_the_other_settings() {
        let cases: &[(&str, &[&str], bool)] = &[
            (
                "drmlt",
                &[
                    "--dr-variant",
                    "cheap-then-expensive",
                    "--mala-preset",
                    "code",
                ],
                true,
            ),
            (
                "drmlt",
                &["--dr-variant", "orbital", "--mala-gradient", "fd"],
                false,
            ),
            (
                "drmlt",
                &[
                    "--dr-variant",
                    "cheap-then-expensive",
                    "--small-step",
                    "gaussian=0.01",
                ],
                true,
            ),
            (
                "drmlt",
                &[
                    "--dr-variant",
                    "green-mira",
                    "--small-step",
                    "gaussian=0.01",
                ],
                false,
            ),
            (
                "drmlt",
                &["--dr-variant", "cheap-then-expensive", "--dr-on", "mmlt"],
                false,
            ),
            (
                "drmlt",
                &["--dr-variant", "cheap-then-expensive", "--roulette", "2"],
                false,
            ),
            ("drmlt", &["--dr-on", "mmlt", "--roulette", "2"], false),
            ("drmlt", &["--dr-on", "mmlt", "--dr-fixed-strategy"], true),
            (
                "drmlt",
                &[
                    "--dr-on",
                    "mmlt",
                    "--dr-variant",
                    "green-mira",
                    "--dr-fixed-strategy",
                ],
                false,
            ),
            ("drmlt", &["--dr-on", "pssmlt-pt", "--roulette", "2"], true),
            (
                "drmlt",
                &["--direct-samples", "4", "--direct-depth", "2"],
                true,
            ),
            ("drmlt", &["--dr-on", "pssmlt", "--roulette", "2"], true),
            (
                "mmlt",
                &["--bdpt-normalization", "1000", "--roulette", "2"],
                true,
            ),
            (
                "pssmlt",
                &["--direct-samples", "0", "--direct-depth", "1"],
                false,
            ),
            (
                "pssmlt",
                &["--direct-samples", "0", "--sampler", "sobol"],
                false,
            ),
            (
                "pssmlt",
                &["--direct-samples", "4", "--direct-depth", "1"],
                true,
            ),
            (
                "pssmlt",
                &["--direct-share", "0.2", "--sampler", "independent"],
                true,
            ),
        ];
        for &(integrator, args, ok) in cases {
            let result = settings(integrator, args);
            assert_eq!(result.is_ok(), ok, "{integrator} {args:?}: {result:?}");
        }
    }

    /// `--mala-preset code` brings the authors' large-step schedule unless `--large-step` is
    /// given; the other presets keep 0.3 (the negative control).
    #[test]
    fn the_code_preset_brings_its_large_step_schedule() {
        use render::methods::MalaSettings;
        use render::mlt::LargeStepMode;
        let large_step = |args: &[&str]| match settings("mala-hybrid", args).unwrap() {
            MethodSettings::Mala(s) => s.chain.large_step,
            other => panic!("{other:?}"),
        };
        assert_eq!(
            large_step(&["--mala-preset", "code"]),
            MalaSettings::CODE_LARGE_STEP
        );
        assert_eq!(
            large_step(&["--mala-preset", "code", "--large-step", "0.3"]),
            LargeStepMode::Fixed(0.3)
        );
        assert_eq!(
            large_step(&["--mala-preset", "paper-values"]),
            LargeStepMode::Fixed(0.3)
        );
        assert_eq!(
            large_step(&["--large-step", "0.1,0.4"]),
            LargeStepMode::Schedule {
                initial: 0.1,
                then: 0.4
            }
        );
    }
}
