//! DRPL: preference learning over scene-graph segments (algorithms.md section 3), free of IO.
//!
//! - `belief`: the Bayesian belief over the reward weights theta (APReL's sampling-based
//!   belief: softmax user, uniform prior on the ball, Metropolis-Hastings).
//! - `acquisition`: how a query is scored among candidates (uniform, APReL's mutual information).

pub mod acquisition;
pub mod belief;
