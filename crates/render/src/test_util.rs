//! Helpers shared by the crate's unit tests: a progress observer that raises the cancel flag.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use mcmc_core::Progress;

/// A [`Progress`] that sets `flag` at its `after`-th report: a deterministic Ctrl-C in the
/// middle of a render (with one thread, at an exact point of the work).
#[derive(Debug)]
pub(crate) struct CancelAfter<'a> {
    flag: &'a AtomicBool,
    after: u64,
    seen: AtomicU64,
}

impl<'a> CancelAfter<'a> {
    /// Sets `flag` at the `after`-th call of [`Progress::advance`].
    pub(crate) fn new(flag: &'a AtomicBool, after: u64) -> Self {
        Self {
            flag,
            after,
            seen: AtomicU64::new(0),
        }
    }
}

impl Progress for CancelAfter<'_> {
    fn set_total(&self, _: u64) {}

    fn advance(&self, _: u64) {
        if self.seen.fetch_add(1, Ordering::Relaxed) + 1 >= self.after {
            self.flag.store(true, Ordering::Relaxed);
        }
    }
}
