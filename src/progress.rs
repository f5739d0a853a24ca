//! The progress line of a long run on stderr: `auto` shows it on a terminal once a run has
//! taken a second, `always` everywhere (a line per report), `never` not at all; it changes no
//! result.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub enum When {
    Auto,
    Always,
    Never,
}

/// The progress line: on a terminal one line rewritten in place (from a second into the run,
/// twice a second), elsewhere (`always`) a line per report.
pub struct Progress {
    planned: u64,
    terminal: bool,
    start: Instant,
    shown: Option<Instant>,
}

impl Progress {
    pub fn new(when: When, planned: u64) -> Option<Progress> {
        let terminal = std::io::stderr().is_terminal();
        let on = when == When::Always || (when == When::Auto && terminal);
        on.then(|| Progress { planned, terminal, start: Instant::now(), shown: None })
    }

    pub fn at(&mut self, step: u64) {
        self.at_in("step", step);
    }

    /// The same, naming what is counted (`forward`, `backward`, ...).
    pub fn at_in(&mut self, what: &str, step: u64) {
        let (now, elapsed) = (Instant::now(), self.start.elapsed().as_secs_f64());
        let due = self.shown.is_none_or(|t| now - t >= Duration::from_millis(500));
        if !due || (self.terminal && elapsed < 1.0) {
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
        if self.terminal {
            eprint!("\r{line}\x1b[K");
        } else {
            eprintln!("lagra: {line}");
        }
        self.shown = Some(now);
    }

    /// Clears a terminal's line before the report.
    pub fn done(&self) {
        if self.terminal && self.shown.is_some() {
            eprint!("\r\x1b[K");
        }
    }
}
