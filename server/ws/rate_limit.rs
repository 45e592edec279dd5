//! How many messages one trainer socket may send: a token bucket. A refused message is not
//! queued (the socket task would have to hold answers the session may no longer want), so the
//! refusal says when a token is free again and the client sends again then
//! (`retry_after_ms` in the `rate_limited` error).

use std::time::{Duration, Instant};

/// Messages per second a socket may send on average, and the burst it may save up.
pub const MESSAGES_PER_SECOND: f64 = 20.0;
pub const BURST: f64 = 40.0;

pub struct RateLimit {
    tokens: f64,
    at: Instant,
}

impl RateLimit {
    pub fn new(now: Instant) -> Self {
        Self {
            tokens: BURST,
            at: now,
        }
    }

    /// Take a token for a message at `now`, or say how long until one is free.
    pub fn take(&mut self, now: Instant) -> Result<(), Duration> {
        let refilled = now.saturating_duration_since(self.at).as_secs_f64() * MESSAGES_PER_SECOND;
        self.tokens = (self.tokens + refilled).min(BURST);
        self.at = now;
        // Within rounding of a whole token counts: a client that waits the wait it was told
        // must not be refused for the last bit of a float.
        if self.tokens >= 1.0 - 1e-9 {
            self.tokens = (self.tokens - 1.0).max(0.0);
            Ok(())
        } else {
            Err(Duration::from_secs_f64(
                (1.0 - self.tokens) / MESSAGES_PER_SECOND,
            ))
        }
    }
}

/// A wait as whole milliseconds, rounded up: a client that waits exactly this long finds the
/// token there.
pub fn whole_ms(wait: Duration) -> u64 {
    wait.as_nanos().div_ceil(1_000_000) as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refusal_says_when_the_next_message_is_taken() {
        let start = Instant::now();
        let mut limit = RateLimit::new(start);
        for _ in 0..BURST as usize {
            assert!(limit.take(start).is_ok());
        }
        let wait = limit.take(start).unwrap_err();
        assert_eq!(whole_ms(wait), 50, "one token at 20 a second");
        // Refused messages spend nothing: a little before the wait is up it is still too early,
        // and at the wait the message is taken.
        let early = limit.take(start + wait - Duration::from_millis(5));
        assert!(early.unwrap_err() <= Duration::from_millis(5));
        assert!(
            limit
                .take(start + Duration::from_millis(whole_ms(wait)))
                .is_ok()
        );
    }
}
