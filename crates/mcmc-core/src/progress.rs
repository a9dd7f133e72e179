//! Progress reporting for long-running work (render loops, renderers, examples).

/// Receives progress reports from long-running work (e.g. an indicatif bar). Shared between
/// worker threads, so it takes `&self`.
pub trait Progress: Sync {
    /// The total amount of work, in the unit of [`Progress::advance`], once it is known (may be
    /// called again with a better estimate).
    fn set_total(&self, total: u64);
    /// `done` more units of work finished.
    fn advance(&self, done: u64);
}

/// A [`Progress`] that ignores every report.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn set_total(&self, _total: u64) {}
    fn advance(&self, _done: u64) {}
}
