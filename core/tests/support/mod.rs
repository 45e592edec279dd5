//! Helpers shared by the core crate's integration tests.

pub mod counting_alloc;
pub mod episodes;
pub mod gradient_check;
