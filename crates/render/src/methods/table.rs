//! The table of integrators: the one place that names them, from which the CLI's
//! `--integrator` values and their help, the default settings of each, and the tests that run
//! every integrator, are built.

use super::{
    BdptSettings, DrmltSettings, LqmcSettings, MalaSettings, MethodSettings, MmltSettings,
    PathMltSettings, PssmltSettings, PtSettings, QmcSettings,
};
use crate::mlt::mala::MalaVariant;

/// Which light-transport algorithm renders the image. Every variant has one row in
/// [`INTEGRATORS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum IntegratorKind {
    /// Unidirectional path tracing with next-event estimation and MIS.
    #[default]
    Pt,
    /// Bidirectional path tracing with MIS over all strategies (the reference renderer).
    Bdpt,
    /// Primary-sample-space MLT over BDPT (Kelemen et al. 2002): all strategies per sample.
    Pssmlt,
    /// Primary-sample-space MLT over the unidirectional path tracer with next-event
    /// estimation ([`super::pssmlt`] with [`super::PathBase::Pt`]).
    PssmltPt,
    /// Multiplexed MLT (Hachisuka et al. 2014): one BDPT strategy per sample, path length
    /// chosen per chain.
    Mmlt,
    /// Delayed-rejection MLT (Rioux-Lavoie et al. 2020) over PSSMLT or MMLT
    /// ([`super::drmlt`]).
    Drmlt,
    /// Halton QMC path tracing: the "Halton points" baseline of Tessari et al.
    /// ([`crate::integrator::qmc`]).
    Qmc,
    /// Halton QMC path tracing with Faure's digit permutations under the per-pixel rotation
    /// ([`crate::integrator::qmc`]).
    QmcFaure,
    /// Local quasi-Monte Carlo exploration of Halton seed paths (Tessari et al.;
    /// [`super::lqmc`]).
    Lqmc,
    /// Langevin MLT (Luan et al. 2020) over MMLT, plain MALA ([`super::mala`]).
    Mala,
    /// Langevin MLT with online adaptation.
    MalaOnline,
    /// Langevin MLT with cache-driven adaptation.
    MalaCache,
    /// Langevin MLT with hybrid adaptation.
    MalaHybrid,
    /// Path-space MLT (Veach & Guibas 1997; Otsu et al. 2018, section 8.1) over `pathspace`
    /// ([`super::pathmlt`]).
    PathMlt,
}

/// One row of the integrator table.
#[derive(Clone, Copy, Debug)]
pub struct IntegratorInfo {
    /// The name on the command line (`--integrator NAME`).
    pub name: &'static str,
    /// One line for `--help`.
    pub description: &'static str,
    /// True for the Markov chain integrators: their budget is in mutations per pixel and they
    /// take the MCMC settings (chains, bootstrap, large and small steps).
    pub is_mcmc: bool,
    /// What the render session runs.
    pub kind: IntegratorKind,
    /// The integrator's default settings (the command line's defaults); the session renders
    /// with [`super::Method::render`] of these settings.
    pub settings: fn() -> MethodSettings,
}

impl PartialEq for IntegratorInfo {
    /// Rows are equal when they run the same integrator (each kind has one row).
    fn eq(&self, other: &Self) -> bool {
        self.kind == other.kind
    }
}

impl Eq for IntegratorInfo {}

/// Every integrator, in `--help` order; the first is the default. Adding an integrator is one
/// row here, its [`IntegratorKind`] variant and its module under [`crate::methods`] (settings,
/// presets, render function; docs/architecture.md lists the files).
pub const INTEGRATORS: &[IntegratorInfo] = &[
    IntegratorInfo {
        name: "pt",
        description: "unidirectional path tracing with next-event estimation and MIS",
        is_mcmc: false,
        kind: IntegratorKind::Pt,
        settings: || PtSettings::default().into(),
    },
    IntegratorInfo {
        name: "bdpt",
        description: "bidirectional path tracing, all strategies with MIS (the reference)",
        is_mcmc: false,
        kind: IntegratorKind::Bdpt,
        settings: || BdptSettings::default().into(),
    },
    IntegratorInfo {
        name: "pssmlt",
        description: "primary-sample-space MLT over BDPT (Kelemen et al. 2002)",
        is_mcmc: true,
        kind: IntegratorKind::Pssmlt,
        settings: || PssmltSettings::default().into(),
    },
    IntegratorInfo {
        name: "pssmlt-pt",
        description: "primary-sample-space MLT over the path tracer with next-event estimation (the PSSMLT of the DRMLT paper and of local QMC's KMLT baseline)",
        is_mcmc: true,
        kind: IntegratorKind::PssmltPt,
        settings: || PssmltSettings::path_traced().into(),
    },
    IntegratorInfo {
        name: "mmlt",
        description: "multiplexed MLT: one BDPT strategy per sample (Hachisuka et al. 2014)",
        is_mcmc: true,
        kind: IntegratorKind::Mmlt,
        settings: || MmltSettings::default().into(),
    },
    IntegratorInfo {
        name: "drmlt",
        description: "delayed-rejection MLT (Rioux-Lavoie et al. 2020): two-stage bold-then-timid kernels (--dr-variant) over PSSMLT or MMLT (--dr-on)",
        is_mcmc: true,
        kind: IntegratorKind::Drmlt,
        settings: || DrmltSettings::default().into(),
    },
    IntegratorInfo {
        name: "qmc",
        description: "path tracing driven by per-pixel Cranley-Patterson-rotated Halton points (the Halton QMC baseline of Tessari et al.)",
        is_mcmc: false,
        kind: IntegratorKind::Qmc,
        settings: || QmcSettings::default().into(),
    },
    IntegratorInfo {
        name: "qmc-faure",
        description: "qmc with Faure-permuted Halton digits: no clustering in the large prime bases, lower error per sample than pt",
        is_mcmc: false,
        kind: IntegratorKind::QmcFaure,
        settings: || QmcSettings::faure().into(),
    },
    IntegratorInfo {
        name: "lqmc",
        description: "local quasi-Monte Carlo (Tessari et al.): Halton seed paths explored by rank-1 lattices, prefixes re-traced and reconnected to the static suffix",
        is_mcmc: false,
        kind: IntegratorKind::Lqmc,
        settings: || LqmcSettings::default().into(),
    },
    IntegratorInfo {
        name: "mala",
        description: "Langevin MLT (Luan et al. 2020) over MMLT: plain MALA on shallow depths, Kelemen beyond",
        is_mcmc: true,
        kind: IntegratorKind::Mala,
        settings: || MalaSettings::with_variant(MalaVariant::Plain).into(),
    },
    IntegratorInfo {
        name: "mala-online",
        description: "Langevin MLT: MALA with online (Adam-like, diminishing) adaptation",
        is_mcmc: true,
        kind: IntegratorKind::MalaOnline,
        settings: || MalaSettings::with_variant(MalaVariant::Online).into(),
    },
    IntegratorInfo {
        name: "mala-cache",
        description: "Langevin MLT: MALA with cache-driven adaptation (gradient cache shared by all chains)",
        is_mcmc: true,
        kind: IntegratorKind::MalaCache,
        settings: || MalaSettings::with_variant(MalaVariant::Cache).into(),
    },
    IntegratorInfo {
        name: "mala-hybrid",
        description: "Langevin MLT: MALA with hybrid adaptation (online until the cache is full, then cache-driven)",
        is_mcmc: true,
        kind: IntegratorKind::MalaHybrid,
        settings: || MalaSettings::with_variant(MalaVariant::Hybrid).into(),
    },
    IntegratorInfo {
        name: "pathmlt",
        description: "path-space MLT (Veach & Guibas 1997): a lens or multi-chain perturbation (--perturbation) and the bidirectional mutation, 0.5 each; pinhole camera and area lights only",
        is_mcmc: true,
        kind: IntegratorKind::PathMlt,
        settings: || PathMltSettings::default().into(),
    },
];

impl IntegratorKind {
    /// The Langevin MLT variant of the `mala*` integrators (`None` for the others).
    #[must_use]
    pub const fn mala_variant(self) -> Option<MalaVariant> {
        match self {
            IntegratorKind::Mala => Some(MalaVariant::Plain),
            IntegratorKind::MalaOnline => Some(MalaVariant::Online),
            IntegratorKind::MalaCache => Some(MalaVariant::Cache),
            IntegratorKind::MalaHybrid => Some(MalaVariant::Hybrid),
            _ => None,
        }
    }

    /// This integrator's row of [`INTEGRATORS`].
    ///
    /// # Panics
    /// If the variant has no row (a table defect, caught by the unit tests).
    #[must_use]
    pub const fn info(self) -> &'static IntegratorInfo {
        let mut i = 0;
        while i < INTEGRATORS.len() {
            if INTEGRATORS[i].kind as u8 == self as u8 {
                return &INTEGRATORS[i];
            }
            i += 1;
        }
        panic!("an IntegratorKind without a row in INTEGRATORS")
    }

    /// The command-line name (`pt`, `bdpt`, ...).
    #[must_use]
    pub const fn name(self) -> &'static str {
        self.info().name
    }

    /// True for the Markov chain integrators (budget in mutations per pixel).
    #[must_use]
    pub const fn is_mcmc(self) -> bool {
        self.info().is_mcmc
    }

    /// This integrator's default settings ([`IntegratorInfo::settings`]).
    #[must_use]
    pub fn settings(self) -> MethodSettings {
        (self.info().settings)()
    }

    /// The integrator called `name` on the command line, if any.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        INTEGRATORS
            .iter()
            .find(|info| info.name == name)
            .map(|info| info.kind)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_has_exactly_one_row_and_names_are_unique() {
        for (i, a) in INTEGRATORS.iter().enumerate() {
            assert!(
                INTEGRATORS[i + 1..]
                    .iter()
                    .all(|b| b.name != a.name && b.kind != a.kind),
                "{} twice",
                a.name
            );
            assert_eq!(a.kind.info(), a);
            assert_eq!(IntegratorKind::from_name(a.name), Some(a.kind));
            // A row's default settings run that row's integrator.
            assert_eq!(a.kind.settings().kind(), a.kind, "{}", a.name);
        }
        // Every variant has a row; the match has no wildcard arm, so a new variant does not
        // compile here until it is added to `all` (and then needs its row).
        use IntegratorKind::{
            Bdpt, Drmlt, Lqmc, Mala, MalaCache, MalaHybrid, MalaOnline, Mmlt, PathMlt, Pssmlt,
            PssmltPt, Pt, Qmc, QmcFaure,
        };
        let all = [
            Pt, Bdpt, Pssmlt, PssmltPt, Mmlt, Drmlt, Qmc, QmcFaure, Lqmc, Mala, MalaOnline,
            MalaCache, MalaHybrid, PathMlt,
        ];
        assert_eq!(all.len(), INTEGRATORS.len());
        for kind in all {
            match kind {
                Pt | Bdpt | Pssmlt | PssmltPt | Mmlt | Drmlt | Qmc | QmcFaure | Lqmc | Mala
                | MalaOnline | MalaCache | MalaHybrid | PathMlt => {
                    assert_eq!(kind.info().kind, kind)
                }
            }
        }
        assert_eq!(INTEGRATORS[0].kind, IntegratorKind::default());
        assert_eq!(IntegratorKind::from_name("nope"), None);
        assert!(IntegratorKind::Mmlt.is_mcmc() && !IntegratorKind::Bdpt.is_mcmc());
    }
}
