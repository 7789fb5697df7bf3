//! Progress bars of the tools: drawn on stderr with `indicatif` when stderr
//! is a terminal (and `TERM` is not `dumb`), nothing at all otherwise, so
//! output to a pipe or a file stays as it was. A tool keeps its periodic
//! log lines for pipes and prints them only while no bar is shown
//! ([`Progress::shown`]).

use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A progress bar on stderr, or nothing when stderr is not a terminal.
pub struct Progress {
    bar: ProgressBar,
}

impl Progress {
    /// A bar of `len` steps (`None`: a spinner with a count), counting in
    /// `unit` (e.g. "messages"), named `prefix` (the tool).
    pub fn new(prefix: &'static str, len: Option<u64>, unit: &str) -> Progress {
        Progress::with_target(prefix, len, unit, ProgressDrawTarget::stderr())
    }

    /// [`Progress::new`] drawing to `target` (tests: a hidden target).
    pub fn with_target(
        prefix: &'static str,
        len: Option<u64>,
        unit: &str,
        target: ProgressDrawTarget,
    ) -> Progress {
        let bar = ProgressBar::with_draw_target(len, target);
        // the templates are constants of this file: a unit test parses both
        if let Ok(style) = ProgressStyle::with_template(&template(len.is_some(), unit)) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_prefix(prefix);
        if !bar.is_hidden() {
            bar.enable_steady_tick(Duration::from_millis(200));
        }
        Progress { bar }
    }

    /// Whether a bar is drawn (stderr is a terminal).
    pub fn shown(&self) -> bool {
        !self.bar.is_hidden()
    }

    /// Advance by `n` steps.
    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
    }

    /// Set the position to `pos` steps.
    pub fn set_position(&self, pos: u64) {
        self.bar.set_position(pos);
    }

    /// Steps so far.
    pub fn position(&self) -> u64 {
        self.bar.position()
    }

    /// The text after the bar.
    pub fn set_message(&self, msg: impl Into<std::borrow::Cow<'static, str>>) {
        self.bar.set_message(msg);
    }

    /// Print a line above the bar (or plainly to stderr when no bar is shown).
    pub fn println(&self, line: impl AsRef<str>) {
        if self.shown() {
            self.bar.println(line);
        } else {
            eprintln!("{}", line.as_ref());
        }
    }

    /// Remove the bar from the terminal.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// The bar's layout: with a length, a bar and the time left; without, a spinner.
fn template(bounded: bool, unit: &str) -> String {
    if bounded {
        format!(
            "{{prefix}} {{elapsed_precise}} [{{wide_bar:.cyan/blue}}] {{human_pos}}/{{human_len}} {unit} ({{eta}} left) {{msg}}"
        )
    } else {
        format!("{{prefix}} {{spinner}} {{elapsed_precise}} {{human_pos}} {unit} {{msg}}")
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if !self.bar.is_finished() {
            self.bar.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hidden_bar_counts_but_shows_nothing() {
        let p = Progress::with_target(
            "phri-test",
            Some(10),
            "messages",
            ProgressDrawTarget::hidden(),
        );
        assert!(!p.shown());
        p.inc(3);
        p.inc(4);
        assert_eq!(p.position(), 7);
        let s = Progress::with_target("phri-test", None, "messages", ProgressDrawTarget::hidden());
        s.set_position(5);
        assert_eq!(s.position(), 5);
    }

    #[test]
    fn the_templates_parse() {
        for bounded in [true, false] {
            let t = template(bounded, "messages");
            assert!(ProgressStyle::with_template(&t).is_ok(), "{t}");
            assert!(t.contains("messages"));
        }
    }
}
