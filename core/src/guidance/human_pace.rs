//! A person's pace: at most N queries in any minute of the robot's time, whatever the query
//! rule would like. DREF asks on almost every step while abstract states are new (Lunar
//! Lander's k = 60 asked on over 90 % of its first 800 steps), which an oracle does not mind
//! and a person cannot keep up with. The rule still decides *which* moments to ask; the pace
//! only holds a query back while the last minute already had N. Off by default, so the paper's
//! behaviour stays the default.
//!
//! Time is counted in environment steps at the session's pace (`pace_hz`, 20 by default: a
//! minute is 1200 steps), so a headless run and a session at any speed ask the same queries.

use serde::{Deserialize, Serialize};

/// A person's pace when a DREF session with a human trainer does not set one: one query about
/// every 2 s. The rule's own ceiling is a share of steps (10 %), which at 20 Hz is 120 queries
/// a minute, more than a person answers with thought; the scripted person ended Reaching
/// solved at 30 a minute (`docs/results/scripted-person/`).
pub const PEOPLE_QUERIES_PER_MINUTE: u32 = 30;

/// At most `max_per_minute` queries in any `steps_per_minute` consecutive steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct HumanPace {
    pub max_per_minute: u32,
    pub steps_per_minute: u64,
}

impl HumanPace {
    /// The pace of `max_per_minute` queries at `pace_hz` steps a second.
    pub fn new(max_per_minute: u32, pace_hz: f64) -> Self {
        Self {
            max_per_minute,
            steps_per_minute: (60.0 * pace_hz).round().max(1.0) as u64,
        }
    }

    /// Whether a query may be asked at step `now`, given the steps of the queries asked so far
    /// (`(step, replay slot)` in the order asked).
    pub fn allows(&self, now: u64, asked: &[(u64, usize)]) -> bool {
        // Queries at steps s with s + window > now, i.e. in the last `window` steps.
        let first_recent = asked.partition_point(|(s, _)| s + self.steps_per_minute <= now);
        ((asked.len() - first_recent) as u64) < u64::from(self.max_per_minute)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_minute_is_sixty_seconds_of_steps() {
        assert_eq!(HumanPace::new(10, 20.0).steps_per_minute, 1200);
        assert_eq!(HumanPace::new(10, 1000.0).steps_per_minute, 60_000);
    }

    #[test]
    fn at_most_n_in_any_window() {
        let pace = HumanPace {
            max_per_minute: 2,
            steps_per_minute: 10,
        };
        let mut asked: Vec<(u64, usize)> = Vec::new();
        let mut at = Vec::new();
        for now in 0..40u64 {
            if pace.allows(now, &asked) {
                asked.push((now, 0));
                at.push(now);
            }
        }
        // Two at once, then two more once the first leaves the window.
        assert_eq!(at, vec![0, 1, 10, 11, 20, 21, 30, 31]);
        for w in at.windows(3) {
            assert!(w[2] - w[0] >= 10, "{w:?}");
        }
    }
}
