//! Which version of a table-top task to build (tasks.md): the authors' robosuite tasks as the
//! default, the first version of our spec behind `variant = "uniform"`, and Placing's switches
//! for its success rule, its gripper observation and the release point of its gripper.
//!
//! The first versions started the gripper anywhere on the table and moved it 5 mm (Reaching) or
//! 2 cm (Placing) per step, and Placing released the ball on the first "open" command. That made
//! both tasks far easier for plain SAC than the authors' (tasks.md says by how much), so they are
//! kept for comparison only.

use std::fmt;

use serde::{Deserialize, Serialize};

/// The start pose, speed and gripper of Reaching and Placing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Variant {
    /// The authors' tasks: the robot's home pose with 5 % reset noise, 1.2 cm per step, and
    /// (Placing) a gripper that opens gradually.
    #[default]
    Authors,
    /// The first version: a uniform start, 5 mm (Reaching) or 2 cm (Placing) per step, and a
    /// ball released by the first "open" command.
    Uniform,
}

/// Where an episode of Reaching or Placing starts, before its reset moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Start {
    /// \[authors\] The robot's home pose.
    Home,
    /// Anywhere over the table (the first version's start; the paper's for DRPL's random
    /// trajectories: "agents starting at random positions and taking random actions").
    Uniform,
}

/// When a released ball counts as placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum PlacingSuccess {
    /// \[authors\] Released while its centre is over the opening and above the ring: success at
    /// once, no ball physics.
    Over,
    /// The first version: the released ball falls (rapier) and its centre passes below the
    /// ring inside the opening.
    Through,
}

/// What Placing's fourth observation `g` holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum GripObservation {
    /// \[authors\] The sign of the last gripper command: -1 if it was "open", else +1.
    #[default]
    Sign,
    /// The gripper's integrated command c itself (+1 closed, -1 fully open).
    Level,
}

/// Placing's hoop, the solid parts the gripper must not touch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum HoopShape {
    /// tasks.md's hoop: a closed box 0.5 x 0.3 x 0.25 m with the square opening in its top; its
    /// wall stands 6.5 cm in front of the home pose.
    #[default]
    Box,
    /// \[authors\] Their scene's `BasketHoopObject`: a thin square ring (the opening's edge)
    /// at the top, carried by an overhang and a pole on the far side (+x), over a base plate.
    /// Behind the safety gate the gripper cannot reach any of it (their random play never
    /// touched it: docs/results/calibration/).
    Ring,
}

impl HoopShape {
    pub(crate) fn is_box(&self) -> bool {
        *self == HoopShape::Box
    }
}

/// Placing's default release point: the ball drops once c <= 0.88, twelve net "open" steps
/// from closed. Calibrated against the authors' random-policy episodes (tasks.md; the figures
/// are in `docs/results/calibration/`).
pub const DEFAULT_RELEASE_AT: f32 = 0.88;

/// Every switch of a table-top task; Lunar Lander takes none.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EnvOptions {
    pub variant: Variant,
    /// Where episodes start; `None` is the variant's own (`home` for the authors' variant,
    /// `uniform` for the first version).
    pub start: Option<Start>,
    /// Placing's success rule; `None` is the variant's own (`over` for the authors' variant,
    /// `through` for the uniform one).
    pub success: Option<PlacingSuccess>,
    pub observe_grip: GripObservation,
    /// Placing (authors' variant): the ball is released when c <= `release_at`.
    pub release_at: f32,
    /// Placing's hoop. Left out of a config when it is the default box, so the configs of runs
    /// made before it existed read back equal.
    #[serde(skip_serializing_if = "HoopShape::is_box")]
    pub hoop: HoopShape,
}

impl Default for EnvOptions {
    fn default() -> Self {
        Self {
            variant: Variant::Authors,
            start: None,
            success: None,
            observe_grip: GripObservation::Sign,
            release_at: DEFAULT_RELEASE_AT,
            hoop: HoopShape::Box,
        }
    }
}

impl EnvOptions {
    /// Where episodes start after the variant's default is applied.
    pub fn start_pose(&self) -> Start {
        self.start.unwrap_or(match self.variant {
            Variant::Authors => Start::Home,
            Variant::Uniform => Start::Uniform,
        })
    }

    /// Placing's success rule after the variant's default is applied.
    pub fn placing_success(&self) -> PlacingSuccess {
        self.success.unwrap_or(match self.variant {
            Variant::Authors => PlacingSuccess::Over,
            Variant::Uniform => PlacingSuccess::Through,
        })
    }
}

impl fmt::Display for Variant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Variant::Authors => "authors",
            Variant::Uniform => "uniform",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_authors_tasks() {
        let o = EnvOptions::default();
        assert_eq!(o.variant, Variant::Authors);
        assert_eq!(o.placing_success(), PlacingSuccess::Over);
        assert_eq!(o.observe_grip, GripObservation::Sign);
        let uniform = EnvOptions {
            variant: Variant::Uniform,
            ..o
        };
        assert_eq!(uniform.placing_success(), PlacingSuccess::Through);
    }

    #[test]
    fn missing_fields_deserialise_to_defaults_and_unknown_ones_fail() {
        let o: EnvOptions = serde_json::from_str(r#"{"variant": "uniform"}"#).unwrap();
        assert_eq!(o.variant, Variant::Uniform);
        assert_eq!(o.release_at, DEFAULT_RELEASE_AT);
        assert!(serde_json::from_str::<EnvOptions>(r#"{"varient": "uniform"}"#).is_err());
    }
}
