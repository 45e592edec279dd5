//! The server's end of a session thread's event channel.

use tokio::sync::mpsc::UnboundedSender;

use crate::session::{SessionEvent, SessionSink};

/// Forwards events into the session's consumer task. Unbounded because the session thread must
/// never block on the async side; frames come at the pace rate, and a synthetic session's answers
/// are drained in batches faster than it makes them.
pub struct ChannelSink(pub UnboundedSender<SessionEvent>);

impl SessionSink for ChannelSink {
    fn send(&self, event: SessionEvent) {
        // The consumer ends only after `Ended`; a send after that is a no-op by design.
        let _ = self.0.send(event);
    }
}
