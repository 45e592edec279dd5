//! Progress of a grid, every run queued, running, finished or failed: an indicatif bar of
//! finished/total runs with elapsed time, ETA and the counts on a terminal, one plain line per
//! event otherwise (logs, CI, `nohup`).

use std::cell::RefCell;
use std::io::IsTerminal;
use std::rc::Rc;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::report::runner::{Event, RunStatus};

/// Prints the grid's progress; cheap to clone (the bar and the counts are shared), so the
/// follow-up hook can print through the same bar without tearing it.
#[derive(Clone)]
pub struct Progress {
    bar: Option<ProgressBar>,
    total: usize,
    board: Rc<RefCell<Board>>,
}

/// Which runs are where, by label.
#[derive(Default)]
struct Board {
    queued: Vec<String>,
    running: Vec<String>,
    done: usize,
    failed: usize,
}

impl Progress {
    /// A bar when stdout is a terminal, plain lines when it is not.
    pub fn new(total: usize) -> Self {
        let bar = std::io::stdout().is_terminal().then(|| {
            let bar =
                ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stdout());
            let style = ProgressStyle::with_template(
                "[{elapsed_precise}] {bar:32.cyan/blue} {pos}/{len} runs, ETA {eta}  {msg}",
            )
            .expect("the template is valid")
            .progress_chars("=> ");
            bar.set_style(style);
            // The bar ticks on its own so elapsed time moves while hour-long runs are going.
            bar.enable_steady_tick(Duration::from_secs(1));
            bar
        });
        Self {
            bar,
            total,
            board: Rc::default(),
        }
    }

    /// A line above the bar (or on its own without one).
    pub fn line(&self, text: &str) {
        match &self.bar {
            Some(bar) => bar.println(text),
            None => println!("{text}"),
        }
    }

    /// Shows one of the runner's events.
    pub fn event(&self, event: &Event<'_>) {
        let text = self.board.borrow_mut().track(event, self.total);
        match &self.bar {
            Some(bar) => {
                if let Event::Finished(outcome) = event {
                    bar.inc(1);
                    if outcome.status == RunStatus::Skipped {
                        // Instant skips would make the rate, and so the ETA, meaningless.
                        bar.reset_eta();
                    }
                }
                // Successes and plain starts show in the counts; the rest deserve a line.
                let quiet = matches!(
                    event,
                    Event::Started(_) | Event::Queued { .. } | Event::Added(_)
                ) || matches!(event, Event::Finished(o) if o.status == RunStatus::Succeeded);
                if let Some(text) = text.filter(|_| !quiet) {
                    bar.println(text);
                }
                bar.set_message(self.board.borrow().message());
            }
            None => {
                if let Some(text) = text {
                    println!("{text}");
                }
            }
        }
    }

    /// Removes the bar, leaving its last state on screen.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_with_message(self.board.borrow().message());
        }
    }
}

impl Board {
    /// Moves the run an event is about; returns the event's line, if it has one.
    fn track(&mut self, event: &Event<'_>, total: usize) -> Option<String> {
        match event {
            Event::Added(_) => None,
            Event::Note(text) => Some(text.to_string()),
            Event::Queued { spec, job } => {
                let label = spec.label();
                let requeued = remove(&mut self.running, &label);
                self.queued.push(label.clone());
                match (job, requeued) {
                    (Some(job), true) => Some(format!("again {label} (Slurm task {job} requeued)")),
                    (Some(job), false) => Some(format!("queue {label} (Slurm task {job})")),
                    (None, _) => None,
                }
            }
            Event::Started(spec) => {
                let label = spec.label();
                remove(&mut self.queued, &label);
                self.running.push(label.clone());
                Some(format!("start {label}"))
            }
            Event::Finished(outcome) => {
                let label = outcome.spec.label();
                remove(&mut self.queued, &label);
                remove(&mut self.running, &label);
                self.done += 1;
                let text = match &outcome.status {
                    RunStatus::Skipped => format!("skip  {label} (already finished)"),
                    RunStatus::Succeeded => format!("done  {label} ({:.1} s)", outcome.seconds),
                    RunStatus::Failed(why) => {
                        self.failed += 1;
                        format!(
                            "FAIL  {label}: {why} (see {})",
                            outcome.spec.dir.join("stderr.log").display()
                        )
                    }
                };
                Some(format!("[{}/{total}] {text}", self.done))
            }
        }
    }

    /// The bar's message: what runs, how many wait, how many failed.
    fn message(&self) -> String {
        let mut parts = Vec::new();
        match self.running.as_slice() {
            [] => {}
            [one] => parts.push(format!("running {one}")),
            [first, rest @ ..] => parts.push(format!("running {first} and {} more", rest.len())),
        }
        if !self.queued.is_empty() {
            parts.push(format!("{} queued", self.queued.len()));
        }
        if self.failed > 0 {
            parts.push(format!("{} failed", self.failed));
        }
        parts.join("; ")
    }
}

/// Removes `label` from `list`; whether it was there.
fn remove(list: &mut Vec<String>, label: &str) -> bool {
    let before = list.len();
    list.retain(|l| l != label);
    list.len() != before
}
