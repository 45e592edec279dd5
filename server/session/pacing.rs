//! What both session loops keep besides the algorithm: the pace people watch a session at, and
//! how often it reports its progress.

use std::time::{Duration, Instant};

use super::events::{Controls, Halt, SessionEvent, SessionSink};

/// Paces a session people watch to `hz` steps a second (`pace_hz`, 20 by default), so that its
/// frames play at a watchable rate. A step that runs late (a slow update, a long wait for an
/// answer) does not make the next ones come in a burst to catch up: the pace goes on from then.
pub(super) struct Pacer {
    period: Duration,
    next_tick: Instant,
}

impl Pacer {
    /// Ticks every `1 / hz` seconds from now.
    pub(super) fn new(hz: f64) -> Self {
        Self::starting_at(hz, Instant::now())
    }

    fn starting_at(hz: f64, start: Instant) -> Self {
        Self {
            period: Duration::from_secs_f64(1.0 / hz),
            next_tick: start,
        }
    }

    /// Waits for the next tick after a step. A control that comes meanwhile ends the wait
    /// early ([`Controls::sleep`]); a stop or shutdown is returned.
    pub(super) fn wait(&mut self, controls: &mut Controls) -> Option<Halt> {
        let wait = self.wait_at(Instant::now())?;
        controls.sleep(wait)
    }

    /// How long to wait at `now` for the next tick; none when behind, and then the pace goes on
    /// from `now` rather than catching up.
    fn wait_at(&mut self, now: Instant) -> Option<Duration> {
        self.next_tick += self.period;
        if self.next_tick > now {
            Some(self.next_tick - now)
        } else {
            self.next_tick = now;
            None
        }
    }
}

/// Reports a session's progress (`SessionEvent::Progress`) at most once every `every`, so that
/// a fast loop does not flood the server with events; a preference session, whose steps are
/// queries, reports every one.
pub(super) struct ProgressReports {
    every: Duration,
    last: Instant,
}

impl ProgressReports {
    /// At most once every `every`, counted from now.
    pub(super) fn every(every: Duration) -> Self {
        Self {
            every,
            last: Instant::now(),
        }
    }

    /// After every step.
    pub(super) fn every_step() -> Self {
        Self::every(Duration::ZERO)
    }

    /// Reports `progress` if the last report is `every` old.
    pub(super) fn tick(&mut self, sink: &dyn SessionSink, progress: u64) {
        if self.due_at(Instant::now()) {
            Self::now(sink, progress);
        }
    }

    /// Reports `progress` whenever it was last reported (at an ending, whose progress is the
    /// one the session ends with).
    pub(super) fn now(sink: &dyn SessionSink, progress: u64) {
        sink.send(SessionEvent::Progress { progress });
    }

    fn due_at(&mut self, now: Instant) -> bool {
        let due = now.saturating_duration_since(self.last) >= self.every;
        if due {
            self.last = now;
        }
        due
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    #[test]
    fn the_pacer_waits_out_the_rest_of_each_tick() {
        let t0 = Instant::now();
        let mut pacer = Pacer::starting_at(20.0, t0);
        assert_eq!(pacer.wait_at(t0 + 10 * MS), Some(40 * MS));
        // The next tick is 50 ms after the last, not after the step that followed it.
        assert_eq!(pacer.wait_at(t0 + 60 * MS), Some(40 * MS));
    }

    #[test]
    fn the_pacer_does_not_burst_after_a_stall() {
        let t0 = Instant::now();
        let mut pacer = Pacer::starting_at(20.0, t0);
        // A step took a second (20 ticks): no wait now...
        let late = t0 + 1000 * MS;
        assert_eq!(pacer.wait_at(late), None);
        // ...and the next step, right after, waits a whole tick instead of running at once.
        assert_eq!(pacer.wait_at(late + MS), Some(49 * MS));
        assert_eq!(pacer.wait_at(late + 50 * MS), Some(50 * MS));
    }

    #[test]
    fn progress_is_reported_at_most_once_a_period() {
        let mut reports = ProgressReports::every(250 * MS);
        let t0 = reports.last;
        assert!(!reports.due_at(t0 + 100 * MS));
        assert!(reports.due_at(t0 + 250 * MS));
        assert!(!reports.due_at(t0 + 400 * MS));
        assert!(reports.due_at(t0 + 600 * MS));
    }

    #[test]
    fn every_step_reports_every_step() {
        let mut reports = ProgressReports::every_step();
        let t0 = reports.last;
        assert!(reports.due_at(t0));
        assert!(reports.due_at(t0));
    }
}
