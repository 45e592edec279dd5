//! Progress of a grid: an indicatif bar of finished/total runs with elapsed time and ETA on a
//! terminal, one plain line per event otherwise (logs, CI, `nohup`).

use std::cell::Cell;
use std::io::IsTerminal;
use std::rc::Rc;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::report::grid::RunSpec;
use crate::report::runner::{Event, RunStatus};

/// Prints the grid's progress; cheap to clone (the bar is shared), so the follow-up hook can
/// print through the same bar without tearing it.
#[derive(Clone)]
pub struct Progress {
    bar: Option<ProgressBar>,
    total: usize,
    done: Rc<Cell<usize>>,
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
            done: Rc::new(Cell::new(0)),
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
    pub fn event(&self, event: &Event<'_>, running: &[String]) {
        match event {
            Event::Added(_) => {}
            Event::Started(spec) => match &self.bar {
                Some(bar) => bar.set_message(running_message(running)),
                None => println!("start {}", spec.label()),
            },
            Event::Finished(outcome) => {
                let label = outcome.spec.label();
                let done = self.done.get() + 1;
                self.done.set(done);
                let text = match &outcome.status {
                    RunStatus::Skipped => format!("skip  {label} (already finished)"),
                    RunStatus::Succeeded => format!("done  {label} ({:.1} s)", outcome.seconds),
                    RunStatus::Failed(why) => format!(
                        "FAIL  {label}: {why} (see {})",
                        outcome.spec.dir.join("stderr.log").display()
                    ),
                };
                match &self.bar {
                    Some(bar) => {
                        // Skips and failures deserve a line; a success shows in the count.
                        if !matches!(outcome.status, RunStatus::Succeeded) {
                            bar.println(&text);
                        }
                        bar.inc(1);
                        bar.set_message(running_message(running));
                        if outcome.status == RunStatus::Skipped {
                            // Instant skips would make the rate, and so the ETA, meaningless.
                            bar.reset_eta();
                        }
                    }
                    None => println!("[{done}/{}] {text}", self.total),
                }
            }
        }
    }

    /// Removes the bar, leaving its last state on screen.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_with_message("");
        }
    }
}

fn running_message(running: &[String]) -> String {
    match running {
        [] => String::new(),
        [one] => format!("running {one}"),
        [first, rest @ ..] => format!("running {first} and {} more", rest.len()),
    }
}

/// Labels of the runs in flight, kept by the caller from Started/Finished events.
pub fn track(running: &mut Vec<String>, event: &Event<'_>) {
    match event {
        Event::Started(spec) => running.push(RunSpec::label(spec)),
        Event::Finished(outcome) => {
            let label = outcome.spec.label();
            running.retain(|l| *l != label);
        }
        Event::Added(_) => {}
    }
}
