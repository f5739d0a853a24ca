//! The progress of a long run on stderr: `auto` shows a bar (indicatif) on a terminal once a
//! run has taken two seconds — steps done, steps per second, time left, and that no claim has
//! been breached (the run would have halted) — `always` a line per report everywhere, `never`
//! (or `--quiet`) nothing; it changes no result.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub enum When {
    Auto,
    Always,
    Never,
}

impl When {
    /// `--quiet` wins over `--progress`.
    pub fn unless(self, quiet: bool) -> When {
        if quiet {
            When::Never
        } else {
            self
        }
    }
}

/// On a terminal, a bar from two seconds into the run; elsewhere (`always`) a line per report,
/// twice a second at most.
pub struct Progress {
    planned: u64,
    terminal: bool,
    start: Instant,
    shown: Option<Instant>,
    bar: Option<ProgressBar>,
}

/// How long a run goes before a bar appears: a short run stays quiet.
const QUIET_FOR: f64 = 2.0;

impl Progress {
    pub fn new(when: When, planned: u64) -> Option<Progress> {
        let terminal = std::io::stderr().is_terminal();
        let on = when == When::Always || (when == When::Auto && terminal);
        on.then(|| Progress { planned, terminal, start: Instant::now(), shown: None, bar: None })
    }

    pub fn at(&mut self, step: u64) {
        self.at_in("step", step);
    }

    /// The same, naming what is counted (`forward`, `backward`, ...).
    pub fn at_in(&mut self, what: &str, step: u64) {
        let elapsed = self.start.elapsed().as_secs_f64();
        if self.terminal {
            if elapsed < QUIET_FOR {
                return;
            }
            let planned = self.planned;
            let bar = self.bar.get_or_insert_with(|| {
                let bar = ProgressBar::with_draw_target(Some(planned), ProgressDrawTarget::stderr());
                let style = ProgressStyle::with_template(
                    "{prefix} {bar:30} {pos}/{len} ({percent}%), {rate}/s, {eta} left, {msg}",
                )
                .expect("a fixed template")
                .with_key("rate", |s: &ProgressState, w: &mut dyn std::fmt::Write| {
                    let _ = write!(w, "{:.0}", s.per_sec());
                });
                bar.set_style(style);
                bar.set_message("no claim breached so far");
                bar
            });
            bar.set_prefix(what.to_string());
            bar.set_position(step);
            return;
        }
        let now = Instant::now();
        if self.shown.is_some_and(|t| now - t < Duration::from_millis(500)) {
            return;
        }
        let mut line = format!(
            "{what} {step}/{} ({:.0}%), {elapsed:.1} s",
            self.planned,
            100.0 * step as f64 / self.planned as f64
        );
        // an estimate from the first half second would be mostly start-up
        if elapsed >= 0.5 {
            line += &format!(", about {:.0} s left", elapsed * (self.planned - step) as f64 / step.max(1) as f64);
        }
        eprintln!("lagra: {line}");
        self.shown = Some(now);
    }

    /// Clears the bar before the report.
    pub fn done(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
