//! The trainer's websocket: `protocol` (the typed messages, parsed once) and `socket` (the
//! connection: auth, catch-up, relay, answers).

pub mod protocol;
pub mod socket;
