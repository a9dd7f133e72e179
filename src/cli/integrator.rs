//! `--integrator` values: clap's view of the renderer's integrator table
//! ([`render::INTEGRATORS`]), so names, help lines and tests come from one place.

use std::sync::OnceLock;

use clap::builder::PossibleValue;
use clap::ValueEnum;
use render::{IntegratorInfo, INTEGRATORS};

/// One `--integrator` choice: a row of the integrator table.
#[derive(Clone, Copy, Debug)]
pub(crate) struct IntegratorChoice {
    /// The table row (name, help line, kind).
    pub(crate) info: &'static IntegratorInfo,
}

impl ValueEnum for IntegratorChoice {
    fn value_variants<'a>() -> &'a [Self] {
        static CHOICES: OnceLock<Vec<IntegratorChoice>> = OnceLock::new();
        CHOICES.get_or_init(|| INTEGRATORS.iter().map(|info| Self { info }).collect())
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.info.name).help(self.info.description))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_table_row_parses_to_its_kind() {
        assert_eq!(IntegratorChoice::value_variants().len(), INTEGRATORS.len());
        for info in INTEGRATORS {
            let parsed = IntegratorChoice::from_str(info.name, false).unwrap();
            assert_eq!(parsed.info, info);
        }
        assert!(IntegratorChoice::from_str("nope", false).is_err());
    }
}
