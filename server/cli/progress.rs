//! Progress for long commands: an indicatif bar on a terminal, a plain line every 10 % when the
//! output is a file or a pipe (CI logs, the `reproduce` runner's children).

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressStyle};

pub struct Progress {
    bar: Option<ProgressBar>,
    total: u64,
    label: String,
    next_line_at: u64,
}

impl Progress {
    pub fn new(total: u64, label: impl Into<String>) -> Self {
        let label = label.into();
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = ProgressBar::new(total);
            bar.set_style(
                ProgressStyle::with_template(
                    "{prefix} [{elapsed_precise}] {wide_bar} {pos}/{len} eta {eta} {msg}",
                )
                .expect("static template"),
            );
            bar.set_prefix(label.clone());
            bar
        });
        Self {
            bar,
            total,
            label,
            next_line_at: 0,
        }
    }

    /// Report position `pos` with a short status message (computed only when shown).
    pub fn update(&mut self, pos: u64, msg: impl FnOnce() -> String) {
        match &self.bar {
            Some(bar) => {
                bar.set_position(pos);
                if pos.is_multiple_of(1000) {
                    bar.set_message(msg());
                }
            }
            None if pos >= self.next_line_at => {
                eprintln!("{} {pos}/{} {}", self.label, self.total, msg());
                self.next_line_at = pos + (self.total / 10).max(1);
            }
            None => {}
        }
    }

    pub fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish();
        }
    }
}
