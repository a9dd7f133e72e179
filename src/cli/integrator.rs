//! The table of integrators `--integrator` accepts: adding one is one line in [`INTEGRATORS`].

use clap::builder::PossibleValue;
use clap::ValueEnum;
use render::session::IntegratorKind;

/// One `--integrator` choice: its command-line name, the session enum value, a help line.
#[derive(Clone, Copy, Debug)]
pub(crate) struct IntegratorChoice {
    /// The name on the command line.
    pub(crate) name: &'static str,
    /// What the render session runs.
    pub(crate) kind: IntegratorKind,
    /// One line for `--help`.
    help: &'static str,
}

/// Every integrator the CLI offers, in `--help` order. The first is the default.
const INTEGRATORS: &[IntegratorChoice] = &[
    IntegratorChoice {
        name: "pt",
        kind: IntegratorKind::Pt,
        help: "unidirectional path tracing with next-event estimation and MIS",
    },
    IntegratorChoice {
        name: "bdpt",
        kind: IntegratorKind::Bdpt,
        help: "bidirectional path tracing, all strategies with MIS (the reference)",
    },
    IntegratorChoice {
        name: "pssmlt",
        kind: IntegratorKind::Pssmlt,
        help: "primary-sample-space MLT over BDPT (Kelemen et al. 2002)",
    },
    IntegratorChoice {
        name: "mmlt",
        kind: IntegratorKind::Mmlt,
        help: "multiplexed MLT: one BDPT strategy per sample (Hachisuka et al. 2014)",
    },
];

impl ValueEnum for IntegratorChoice {
    fn value_variants<'a>() -> &'a [Self] {
        INTEGRATORS
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.name).help(self.help))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_parse() {
        for (i, a) in INTEGRATORS.iter().enumerate() {
            assert!(
                INTEGRATORS[i + 1..].iter().all(|b| b.name != a.name),
                "{}",
                a.name
            );
            let parsed = IntegratorChoice::from_str(a.name, false).unwrap();
            assert_eq!(parsed.kind, a.kind);
        }
        assert_eq!(INTEGRATORS[0].kind, IntegratorKind::default());
    }
}
