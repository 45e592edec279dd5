//! The trainer's websocket (`socket`): auth, catch-up, relay of the session's broadcasts, and
//! answers handed to the session's owner. Its messages are the types of [`crate::protocol`].

pub mod socket;
