//! The task's scene as Rerun archetypes: what an episode's `Geometry` fixes (table, goal, hoop,
//! terrain, flags) and what a step's `RenderState` moves (gripper, ball, lander, flames). Values
//! cross from the simulator as plain `[f32; N]` arrays: rapier's and rerun's glam versions differ.
//!
//! Entity paths are listed in the module doc of `record`.

use anyhow::Context;
use rerun::{
    Arrows2D, Boxes3D, Color, EncodedImage, FillMode, LineStrips2D, LineStrips3D, Points3D,
    RecordingStream, Scalars, ViewCoordinates,
};

use crate::sim::{Cuboid, Geometry, Pose2, Pose3, RenderState};

/// `Color::from_rgb` is not `const`; its datatype's constructor is.
const fn rgb(r: u8, g: u8, b: u8) -> Color {
    Color(rerun::datatypes::Rgba32::from_rgb(r, g, b))
}

const TABLE: Color = rgb(166, 124, 82);
const GOAL: Color = rgb(80, 180, 90);
const HOOP: Color = rgb(150, 150, 165);
const GATE: Color = rgb(120, 120, 120);
const NO_ENTRY: Color = rgb(210, 70, 60);
const GRIPPER_OPEN: Color = rgb(240, 150, 40);
const GRIPPER_CLOSED: Color = rgb(90, 90, 100);
const BALL_HELD: Color = rgb(60, 120, 220);
const BALL_FREE: Color = rgb(220, 60, 160);
const TERRAIN: Color = rgb(200, 200, 200);
const FLAG: Color = rgb(230, 200, 40);
const HULL: Color = rgb(128, 102, 230);
const LEG_FREE: Color = rgb(128, 102, 230);
const LEG_CONTACT: Color = rgb(60, 200, 90);
const FLAME: Color = rgb(255, 120, 30);

/// The gripper drawn as a box of these half extents (metres) around its pose; the simulator
/// models it as a point, so the size is only for display.
const GRIPPER_HALF_EXTENTS: [f32; 3] = [0.02, 0.02, 0.03];
/// Half thickness of the flat boxes that draw rectangles on the table (goal, Reaching's gate).
const FLAT: f32 = 0.001;

/// Gymnasium's side engines eject 14 px up and 12 px out from the hull's centre (SCALE 30).
const SIDE_ENGINE_HEIGHT: f32 = 14.0 / 30.0;
const SIDE_ENGINE_AWAY: f32 = 12.0 / 30.0;
/// A full-throttle flame's length in world units (display only).
const MAIN_FLAME_LENGTH: f32 = 1.0;
const SIDE_FLAME_LENGTH: f32 = 0.6;

/// What a step's render state needs from the episode's geometry to be drawn.
#[derive(Default)]
pub(super) struct Scene {
    /// Placing's ball radius.
    ball_radius: Option<f32>,
    lander: Option<LanderShape>,
}

/// Lunar Lander's body shapes and the world height (for the y flip).
struct LanderShape {
    world_height: f32,
    hull: Vec<[f32; 2]>,
    leg_half_extents: [f32; 2],
}

/// Whether a geometry lasts for the whole recording (logged static) or changes per episode
/// (Lunar Lander's terrain: logged at the episode's first step).
pub(super) fn is_static(geometry: &Geometry) -> bool {
    !matches!(geometry, Geometry::LunarLander { .. })
}

/// Axes for the 3D tasks: the simulator's z is up.
pub(super) fn log_view_coordinates(rec: &RecordingStream) -> anyhow::Result<()> {
    rec.log_static("world", &ViewCoordinates::RIGHT_HAND_Z_UP())?;
    Ok(())
}

impl Scene {
    /// Log `geometry` (static when [`is_static`], else at the current time) and keep what the
    /// steps need.
    pub(super) fn log_geometry(
        &mut self,
        rec: &RecordingStream,
        geometry: &Geometry,
    ) -> anyhow::Result<()> {
        let stat = is_static(geometry);
        let log = |path: &str, archetype: &dyn rerun::AsComponents| {
            rec.log_with_static(path, stat, archetype)
                .with_context(|| format!("logging {path}"))
        };
        match geometry {
            // Nothing fixed to draw: its frames carry the whole scene.
            Geometry::Remote { .. } => {}
            Geometry::Reaching {
                table,
                goal,
                workspace,
            } => {
                let top = table.center[2] + table.half_extents[2];
                log("world/table", &solid_boxes(&[*table], TABLE))?;
                log("world/goal", &solid_boxes(&[flat_rect(*goal, top)], GOAL))?;
                log(
                    "world/workspace",
                    &wire_boxes(&[flat_rect(*workspace, top + FLAT)], GATE),
                )?;
            }
            Geometry::Placing {
                table,
                hoop_parts,
                opening,
                hoop_top_z,
                ball_radius,
                workspace,
                no_entry,
                ..
            } => {
                log("world/table", &solid_boxes(&[*table], TABLE))?;
                log("world/hoop", &solid_boxes(hoop_parts, HOOP))?;
                log(
                    "world/hoop/opening",
                    &LineStrips3D::new([rect_loop(*opening, *hoop_top_z)]).with_colors([GOAL]),
                )?;
                log("world/workspace", &wire_boxes(&[aabb(*workspace)], GATE))?;
                log("world/no_entry", &wire_boxes(&[aabb(*no_entry)], NO_ENTRY))?;
                self.ball_radius = Some(*ball_radius);
            }
            Geometry::LunarLander {
                world,
                terrain,
                flags,
                flag_height,
                hull,
                leg_half_extents,
            } => {
                let h = world[1];
                let flip = |[x, y]: [f32; 2]| [x, h - y];
                log(
                    "world/terrain",
                    &LineStrips2D::new([terrain.iter().copied().map(flip).collect::<Vec<_>>()])
                        .with_colors([TERRAIN]),
                )?;
                // Gymnasium's flags: a 50 px pole and a 25 x 10 px pennant at its top.
                let mut strips = Vec::with_capacity(4);
                for &[x, y] in flags {
                    let top = y + flag_height;
                    strips.push(vec![flip([x, y]), flip([x, top])]);
                    strips.push(vec![
                        flip([x, top]),
                        flip([x, top - 0.2 * flag_height]),
                        flip([x + 0.5 * flag_height, top - 0.1 * flag_height]),
                        flip([x, top]),
                    ]);
                }
                log(
                    "world/flags",
                    &LineStrips2D::new(strips).with_colors([FLAG]),
                )?;
                self.lander = Some(LanderShape {
                    world_height: h,
                    hull: hull.clone(),
                    leg_half_extents: *leg_half_extents,
                });
            }
        }
        Ok(())
    }

    /// Log one step's `state` at the current time.
    pub(super) fn log_state(
        &self,
        rec: &RecordingStream,
        state: &RenderState,
    ) -> anyhow::Result<()> {
        match state {
            RenderState::Remote { frame, .. } => {
                // The env's own rendering, as encoded (PNG or JPEG): only on the steps it was
                // asked for one (people watching).
                if let Some(frame) = frame {
                    rec.log(
                        "world/frame",
                        &EncodedImage::new(frame.data.to_vec())
                            .with_media_type(frame.media_type.mime()),
                    )?;
                }
            }
            RenderState::Reaching { gripper } => {
                rec.log("world/gripper", &gripper_box(gripper, GRIPPER_OPEN))?;
            }
            RenderState::Placing {
                gripper,
                gripper_closed,
                grip_level,
                ball,
                ball_held,
            } => {
                let radius = self
                    .ball_radius
                    .context("a Placing step was recorded before its episode's geometry")?;
                let colour = if *gripper_closed {
                    GRIPPER_CLOSED
                } else {
                    GRIPPER_OPEN
                };
                rec.log("world/gripper", &gripper_box(gripper, colour))?;
                rec.log(
                    "gripper/closed",
                    &Scalars::single(f64::from(u8::from(*gripper_closed))),
                )?;
                // The gradual gripper's integrated command: the ball drops at the release level.
                rec.log("gripper/level", &Scalars::single(f64::from(*grip_level)))?;
                rec.log(
                    "world/ball",
                    &Points3D::new([*ball])
                        .with_radii([radius])
                        .with_colors([if *ball_held { BALL_HELD } else { BALL_FREE }]),
                )?;
            }
            RenderState::LunarLander {
                hull,
                legs,
                leg_contact,
                main_engine,
                side_engine,
            } => {
                let shape = self
                    .lander
                    .as_ref()
                    .context("a Lunar Lander step was recorded before its episode's geometry")?;
                let view = |pose: &Pose2, [px, py]: [f32; 2]| {
                    let [x, y] = to_world(pose, [px, py]);
                    [x, shape.world_height - y]
                };
                let mut outline: Vec<[f32; 2]> =
                    shape.hull.iter().map(|&p| view(hull, p)).collect();
                outline.extend(outline.first().copied());
                rec.log(
                    "world/lander/hull",
                    &LineStrips2D::new([outline]).with_colors([HULL]),
                )?;

                let [hw, hh] = shape.leg_half_extents;
                let corners = [[-hw, -hh], [hw, -hh], [hw, hh], [-hw, hh], [-hw, -hh]];
                let strips = legs
                    .iter()
                    .map(|leg| corners.iter().map(|&c| view(leg, c)).collect::<Vec<_>>());
                let colours = leg_contact.map(|c| if c { LEG_CONTACT } else { LEG_FREE });
                rec.log(
                    "world/lander/legs",
                    &LineStrips2D::new(strips).with_colors(colours),
                )?;

                let (origins, vectors) = flames(shape, hull, *main_engine, *side_engine);
                rec.log(
                    "world/lander/flames",
                    &Arrows2D::from_vectors(vectors)
                        .with_origins(origins)
                        .with_colors([FLAME]),
                )?;
                rec.log("engines/main", &Scalars::single(f64::from(*main_engine)))?;
                rec.log("engines/side", &Scalars::single(f64::from(*side_engine)))?;
            }
        }
        Ok(())
    }
}

/// The exhaust arrows (origins and vectors, in view coordinates) for this step's throttles:
/// the main engine below the hull, the firing side engine out of the hull's side.
fn flames(
    shape: &LanderShape,
    hull: &Pose2,
    main: f32,
    side: f32,
) -> (Vec<[f32; 2]>, Vec<[f32; 2]>) {
    let bottom = shape
        .hull
        .iter()
        .map(|p| p[1])
        .fold(f32::INFINITY, f32::min);
    let mut local = Vec::with_capacity(2);
    if main > 0.0 {
        local.push(([0.0, bottom], [0.0, -main * MAIN_FLAME_LENGTH]));
    }
    if side != 0.0 {
        // Direction +1 (a1 > 0.5) ejects on the hull's left and pushes it right.
        let s = side.signum();
        local.push((
            [-s * SIDE_ENGINE_AWAY, SIDE_ENGINE_HEIGHT],
            [-s * side.abs() * SIDE_FLAME_LENGTH, 0.0],
        ));
    }
    let (c, s) = (hull.angle.cos(), hull.angle.sin());
    local
        .into_iter()
        .map(|(origin, [vx, vy])| {
            let [x, y] = to_world(hull, origin);
            (
                [x, shape.world_height - y],
                // Rotate the vector with the hull, then flip y for the view.
                [c * vx - s * vy, -(s * vx + c * vy)],
            )
        })
        .unzip()
}

/// A body-frame point in world coordinates.
fn to_world(pose: &Pose2, [px, py]: [f32; 2]) -> [f32; 2] {
    let (c, s) = (pose.angle.cos(), pose.angle.sin());
    [pose.x + c * px - s * py, pose.y + s * px + c * py]
}

fn gripper_box(pose: &Pose3, colour: Color) -> Boxes3D {
    Boxes3D::from_centers_and_half_sizes([pose.position], [GRIPPER_HALF_EXTENTS])
        .with_quaternions([rerun::Quaternion::from_xyzw(pose.rotation)])
        .with_fill_mode(FillMode::Solid)
        .with_colors([colour])
}

fn solid_boxes(boxes: &[Cuboid], colour: Color) -> Boxes3D {
    Boxes3D::from_centers_and_half_sizes(
        boxes.iter().map(|b| b.center),
        boxes.iter().map(|b| b.half_extents),
    )
    .with_fill_mode(FillMode::Solid)
    .with_colors([colour])
}

fn wire_boxes(boxes: &[Cuboid], colour: Color) -> Boxes3D {
    Boxes3D::from_centers_and_half_sizes(
        boxes.iter().map(|b| b.center),
        boxes.iter().map(|b| b.half_extents),
    )
    .with_fill_mode(FillMode::MajorWireframe)
    .with_colors([colour])
}

/// A rectangle `[x_min, y_min, x_max, y_max]` lying at height `z`, as a thin box.
fn flat_rect([x0, y0, x1, y1]: [f32; 4], z: f32) -> Cuboid {
    Cuboid {
        center: [(x0 + x1) / 2.0, (y0 + y1) / 2.0, z + FLAT],
        half_extents: [(x1 - x0) / 2.0, (y1 - y0) / 2.0, FLAT],
    }
}

/// A box `[x_min, y_min, z_min, x_max, y_max, z_max]`.
fn aabb([x0, y0, z0, x1, y1, z1]: [f32; 6]) -> Cuboid {
    Cuboid {
        center: [(x0 + x1) / 2.0, (y0 + y1) / 2.0, (z0 + z1) / 2.0],
        half_extents: [(x1 - x0) / 2.0, (y1 - y0) / 2.0, (z1 - z0) / 2.0],
    }
}

/// The closed outline of a rectangle `[x_min, y_min, x_max, y_max]` at height `z`.
fn rect_loop([x0, y0, x1, y1]: [f32; 4], z: f32) -> Vec<[f32; 3]> {
    vec![
        [x0, y0, z],
        [x1, y0, z],
        [x1, y1, z],
        [x0, y1, z],
        [x0, y0, z],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape() -> LanderShape {
        LanderShape {
            world_height: 10.0,
            hull: vec![[-0.5, -0.3], [0.5, -0.3], [0.0, 0.5]],
            leg_half_extents: [0.1, 0.2],
        }
    }

    #[test]
    fn body_points_rotate_with_the_pose() {
        let pose = Pose2 {
            x: 1.0,
            y: 2.0,
            angle: std::f32::consts::FRAC_PI_2,
        };
        let [x, y] = to_world(&pose, [1.0, 0.0]);
        assert!((x - 1.0).abs() < 1e-6 && (y - 3.0).abs() < 1e-6);
    }

    #[test]
    fn flames_point_down_and_out_in_the_flipped_view() {
        let upright = Pose2 {
            x: 5.0,
            y: 4.0,
            angle: 0.0,
        };
        let (origins, vectors) = flames(&shape(), &upright, 1.0, 0.0);
        // Main engine: from the hull's bottom (y = 3.7 in the world, 6.3 in the view), pushing
        // exhaust down in the world, i.e. +y in the view.
        assert_eq!(origins.len(), 1);
        assert!((origins[0][1] - 6.3).abs() < 1e-5);
        assert!(vectors[0][1] > 0.0 && vectors[0][0].abs() < 1e-6);
        // Direction +1 ejects to the left (-x); off engines draw nothing.
        let (origins, vectors) = flames(&shape(), &upright, 0.0, 0.7);
        assert_eq!(origins.len(), 1);
        assert!(origins[0][0] < 5.0 && vectors[0][0] < 0.0);
        assert!(flames(&shape(), &upright, 0.0, 0.0).0.is_empty());
    }

    #[test]
    fn rectangles_become_boxes_on_the_surface() {
        let c = flat_rect([-0.1, -0.2, 0.1, 0.2], 0.75);
        assert_eq!(c.half_extents, [0.1, 0.2, FLAT]);
        assert!((c.center[2] - (0.75 + FLAT)).abs() < 1e-7);
        let b = aabb([0.0, 0.0, 1.0, 2.0, 4.0, 3.0]);
        assert_eq!(
            (b.center, b.half_extents),
            ([1.0, 2.0, 2.0], [1.0, 2.0, 1.0])
        );
    }
}
