//! The trainer's websocket (`socket`): auth, catch-up, relay of the session's broadcasts, and
//! answers handed to the session's owner; `rate_limit`: how many messages a socket may send.
//! Its messages are the types of [`crate::protocol`].

pub mod rate_limit;
pub mod socket;
