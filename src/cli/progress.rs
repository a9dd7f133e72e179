//! An indicatif progress bar behind the render session's `Progress` trait.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use render::session::Progress;

/// A progress bar on stderr with ETA and rate; hidden when stderr is not a terminal.
#[derive(Debug)]
pub(crate) struct BarProgress {
    bar: ProgressBar,
}

impl BarProgress {
    /// A bar whose rate is shown in `unit`s per second (e.g. "samples").
    pub(crate) fn new(unit: &str) -> Self {
        let template = format!(
            "{{spinner}} [{{elapsed_precise}}] {{wide_bar}} {{percent:>3}}% \
             {{human_pos}}/{{human_len}} {unit} ({{per_sec}}, ETA {{eta}})"
        );
        let style = ProgressStyle::with_template(&template)
            .unwrap_or_else(|_| ProgressStyle::default_bar());
        let bar =
            ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr()).with_style(style);
        Self { bar }
    }

    /// Removes the bar from the terminal.
    pub(crate) fn finish(&self) {
        self.bar.finish_and_clear();
    }

    /// A handle to the same bar, e.g. for printing a line above it from the Ctrl-C handler.
    pub(crate) fn handle(&self) -> ProgressBar {
        self.bar.clone()
    }
}

impl Progress for BarProgress {
    fn set_total(&self, total: u64) {
        self.bar.set_length(total);
    }

    fn advance(&self, done: u64) {
        self.bar.inc(done);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_sync_and_counts() {
        fn assert_sync<T: Sync + Send>() {}
        assert_sync::<BarProgress>();
        let p = BarProgress::new("samples");
        p.set_total(10);
        p.advance(3);
        p.advance(4);
        assert_eq!(p.bar.position(), 7);
        assert_eq!(p.bar.length(), Some(10));
        p.finish();
    }
}
