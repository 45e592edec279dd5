//! The simulated tasks, free of IO: Gymnasium's `reset`/`step` contract on rapier.
//!
//! - `env`: the `Env` trait, spaces, `Step`, render state and geometry.
//! - `task`: the `Task` enum that names the three tasks and builds them.
//! - `options`: which version of a table-top task to build (the authors' or the first one).
//! - `reaching`, `placing`: table-top tasks on rapier3d (`tabletop` holds their shared world).
//! - `lunar_lander`: Gymnasium's `LunarLanderContinuous-v3` on rapier2d.
//! - `rollout`: run a random or heuristic policy for whole episodes and summarise them.
//! - `frame`, `interned`: what an env in another process brings (its own rendered frames, the
//!   names it declares at run time); the client itself lives in `remote_env`.

mod env;
mod frame;
pub mod interned;
pub mod lunar_lander;
mod options;
pub mod placing;
pub mod reaching;
pub mod rollout;
mod tabletop;
mod task;

pub use env::{
    BoxSpace, Cuboid, Env, EnvFault, EnvSpec, Geometry, Outcome, Pose2, Pose3, RenderState, Step,
};
pub use frame::{ImageFrame, MediaType};
pub use options::{
    DEFAULT_RELEASE_AT, EnvOptions, GripObservation, HoopShape, PlacingSuccess, Start, Variant,
};
pub use task::{DeclaredTask, Task, TaskRef, UnknownTask};
