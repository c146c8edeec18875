//! Progress on stderr, for work that can take more than a couple of seconds.
//!
//! On a terminal: a bar with its count, elapsed time and ETA where the total is known
//! ([`Progress::bar`]), a spinner with the elapsed time where it is not
//! ([`Progress::spinner`]). When stderr is not a terminal nothing is drawn; only the
//! one-line summaries of finished steps ([`note`], [`Progress::finish`]) are printed, so a
//! log keeps what happened. `--quiet` ([`set_quiet`]) silences both; errors and warnings
//! are printed by their callers regardless. Nothing here writes to stdout.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

static QUIET: AtomicBool = AtomicBool::new(false);

/// Silence every bar and summary line (the CLI's `--quiet`).
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// Whether [`set_quiet`] was called with `true`.
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// Whether bars are drawn: stderr is a terminal and not [`quiet`].
pub fn drawn() -> bool {
    !quiet() && std::io::stderr().is_terminal()
}

/// Print a one-line summary on stderr unless [`quiet`].
pub fn note(line: impl std::fmt::Display) {
    if !quiet() {
        eprintln!("{line}");
    }
}

/// One step's progress: a bar or a spinner, hidden unless [`drawn`].
pub struct Progress {
    bar: ProgressBar,
}

impl Progress {
    /// A bar for `total` units of `what` (e.g. "cases", "trials"), labelled `label`.
    pub fn bar(label: &str, total: u64, what: &str) -> Self {
        let bar = ProgressBar::with_draw_target(Some(total), target());
        bar.set_style(
            ProgressStyle::with_template(&format!(
                "{{prefix}} [{{bar:30}}] {{pos}}/{{len}} {what} {{elapsed}} (ETA {{eta}}) {{msg}}"
            ))
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        bar.set_prefix(label.to_string());
        Progress { bar }
    }

    /// A spinner for work of unknown length, labelled `label`.
    pub fn spinner(label: &str) -> Self {
        let bar = ProgressBar::with_draw_target(None, target());
        bar.set_style(
            ProgressStyle::with_template("{spinner} {prefix} {elapsed} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        bar.set_prefix(label.to_string());
        bar.enable_steady_tick(Duration::from_millis(120));
        Progress { bar }
    }

    /// Set the count of finished units.
    pub fn set(&self, done: u64) {
        self.bar.set_position(done);
    }

    /// One more unit finished.
    pub fn inc(&self) {
        self.bar.inc(1);
    }

    /// The text after the bar (a running figure, the current item).
    pub fn message(&self, msg: impl Into<String>) {
        self.bar.set_message(msg.into());
    }

    /// Print a line above the bar (a [`note`] that does not tear the bar).
    pub fn println(&self, line: impl std::fmt::Display) {
        if quiet() {
        } else if self.bar.is_hidden() {
            eprintln!("{line}");
        } else {
            self.bar.println(line.to_string());
        }
    }

    /// Remove the bar and print `summary` as a [`note`].
    pub fn finish(self, summary: impl std::fmt::Display) {
        self.bar.finish_and_clear();
        note(summary);
    }

    /// Remove the bar without a summary.
    pub fn clear(self) {
        self.bar.finish_and_clear();
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        // An error path that drops the bar must not leave a half-drawn line behind.
        if !self.bar.is_finished() {
            self.bar.finish_and_clear();
        }
    }
}

fn target() -> ProgressDrawTarget {
    if drawn() {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quiet_hides_bars_which_still_count() {
        set_quiet(true);
        assert!(quiet() && !drawn());
        let p = Progress::bar("test", 3, "units");
        p.inc();
        p.set(3);
        assert_eq!(p.bar.position(), 3);
        assert!(p.bar.is_hidden());
        p.clear();
        set_quiet(false);
        assert!(!quiet());
    }
}
