//! Placing's fixed scene: the table, the hoop (tasks.md's basket with a square opening in its
//! top, or the authors' ring on an overhang and a pole) and the safety gate's workspace and
//! no-entry box around it.

use super::super::tabletop::{self, Part, Region, TABLE_TOP_Z, TableWorld};
use super::super::{Cuboid, HoopShape};

/// The hoop's outer half sizes in x and y; it stands on the table centred at (0, 0).
pub const HOOP_HALF_X: f32 = 0.25;
pub const HOOP_HALF_Y: f32 = 0.15;
/// Height of the hoop's top surface (0.25 m above the table).
pub const HOOP_TOP_Z: f32 = 1.0;
/// Half side of the square opening (the ring) at the centre of the hoop's top.
pub const OPENING_HALF: f32 = 0.1;
/// Thickness of the walls and of the top plates.
const SHEET: f32 = 0.01;

pub const BALL_RADIUS: f32 = 0.025;

/// Where the gripper may aim (the gate's workspace), as an open box.
pub(crate) const WORKSPACE: Region<3> = Region {
    lo: [-0.6, -0.3, 0.80],
    hi: [0.2, 0.3, 1.65],
};
/// The no-entry box under and beside the hoop [authors' values]. It reaches over the hoop's
/// top only for x > -0.17, so the gripper can still touch the hoop from the -x side.
pub(crate) const NO_ENTRY: Region<3> = Region {
    lo: [-0.17, -0.16, 0.80],
    hi: [0.2, 0.16, 1.03],
};
/// Gripper travel per step at full action \[authors: their expert moves 0.9-1.3 cm per step\].
pub const STEP_SIZE: f32 = 0.012;
/// The first version's travel per step (`variant = "uniform"`).
pub const UNIFORM_STEP_SIZE: f32 = 0.02;
/// The robot's home pose, holding the ball behind the hoop \[authors\].
pub const HOME: [f32; 3] = [-0.315, 0.0, 1.00];
/// How far along the action the gate probes \[authors\]; larger than the move itself.
pub const LOOKAHEAD: f32 = 0.07;
/// The uniform variant's gripper starts above this height (its reset's random moves may take
/// it lower).
pub const START_MIN_Z: f32 = 1.05;

/// The safety gate's test for the probe point `p = gripper + LOOKAHEAD * a`.
pub(crate) fn gate_allows(p: &[f32; 3]) -> bool {
    WORKSPACE.contains(p) && !NO_ENTRY.contains(p)
}

/// Whether (x, y) lies over the opening (open square: the edges belong to the plates).
pub fn over_opening(x: f32, y: f32) -> bool {
    x.abs() < OPENING_HALF && y.abs() < OPENING_HALF
}

/// The table: it covers the workspace and the hoop with a margin.
pub(crate) fn table() -> Cuboid {
    tabletop::table([-0.2, 0.0], [0.5, 0.4])
}

fn slab(center: [f32; 3], half_extents: [f32; 3]) -> Cuboid {
    Cuboid {
        center,
        half_extents,
    }
}

/// The four walls, from the table up to the underside of the top plates.
pub(crate) fn walls() -> [Cuboid; 4] {
    let (bottom, top) = (TABLE_TOP_Z, HOOP_TOP_Z - SHEET);
    let (zc, hz) = ((bottom + top) / 2.0, (top - bottom) / 2.0);
    let t = SHEET / 2.0;
    [
        slab([-(HOOP_HALF_X - t), 0.0, zc], [t, HOOP_HALF_Y, hz]),
        slab([HOOP_HALF_X - t, 0.0, zc], [t, HOOP_HALF_Y, hz]),
        // The y walls fit between the x walls, so no two parts overlap.
        slab([0.0, -(HOOP_HALF_Y - t), zc], [HOOP_HALF_X - SHEET, t, hz]),
        slab([0.0, HOOP_HALF_Y - t, zc], [HOOP_HALF_X - SHEET, t, hz]),
    ]
}

/// The top: four plates framing the opening, flush with `HOOP_TOP_Z`.
pub(crate) fn top_plates() -> [Cuboid; 4] {
    let (zc, hz) = (HOOP_TOP_Z - SHEET / 2.0, SHEET / 2.0);
    // Full-length plates in front of and behind the opening...
    let hy = (HOOP_HALF_Y - OPENING_HALF) / 2.0;
    let yc = OPENING_HALF + hy;
    // ...and shorter ones left and right of it.
    let hx = (HOOP_HALF_X - OPENING_HALF) / 2.0;
    let xc = OPENING_HALF + hx;
    [
        slab([0.0, -yc, zc], [HOOP_HALF_X, hy, hz]),
        slab([0.0, yc, zc], [HOOP_HALF_X, hy, hz]),
        slab([-xc, 0.0, zc], [hx, OPENING_HALF, hz]),
        slab([xc, 0.0, zc], [hx, OPENING_HALF, hz]),
    ]
}

/// The authors' `BasketHoopObject` as their scene places it (read from their MuJoCo model), as
/// (what stands on the table, the top): the pole on the far side (+x) standing on a 1 cm base
/// plate; four 1 cm bars framing the opening at the top (z 0.99 to 1.0) and the overhang that
/// carries them from the pole. The ring's short bars fit between its long ones, so no two parts
/// overlap.
fn ring_parts() -> ([Cuboid; 2], [Cuboid; 5]) {
    let (zc, hz) = (HOOP_TOP_Z - SHEET / 2.0, SHEET / 2.0);
    let bar = OPENING_HALF - SHEET / 2.0;
    let (pole_bottom, pole_top) = (TABLE_TOP_Z + SHEET, HOOP_TOP_Z - SHEET);
    let stand = [
        slab(
            [0.245, 0.0, (pole_bottom + pole_top) / 2.0],
            [hz, hz, (pole_top - pole_bottom) / 2.0],
        ),
        slab([0.0, 0.0, TABLE_TOP_Z + hz], [HOOP_HALF_X, HOOP_HALF_Y, hz]),
    ];
    let top = [
        slab([0.0, -bar, zc], [OPENING_HALF, hz, hz]),
        slab([0.0, bar, zc], [OPENING_HALF, hz, hz]),
        slab([-bar, 0.0, zc], [hz, OPENING_HALF - SHEET, hz]),
        slab([bar, 0.0, zc], [hz, OPENING_HALF - SHEET, hz]),
        // The overhang, from the ring's far edge to the pole.
        slab([0.175, 0.0, zc], [0.075, hz, hz]),
    ];
    (stand, top)
}

/// `shape`'s hoop as (what stands on the table, the top): a free ball that lands on the first
/// has missed; the second is the ring or the plates around the opening.
fn walls_and_top(shape: HoopShape) -> (Vec<Cuboid>, Vec<Cuboid>) {
    match shape {
        HoopShape::Box => (walls().to_vec(), top_plates().to_vec()),
        HoopShape::Ring => {
            let (stand, top) = ring_parts();
            (stand.to_vec(), top.to_vec())
        }
    }
}

/// All solid parts of `shape`'s hoop, walls first.
pub(crate) fn parts(shape: HoopShape) -> Vec<Cuboid> {
    let (walls, top) = walls_and_top(shape);
    walls.into_iter().chain(top).collect()
}

/// Add `shape`'s hoop to a table-top world.
pub(crate) fn add_to(world: &mut TableWorld, shape: HoopShape) {
    let (walls, top) = walls_and_top(shape);
    for w in &walls {
        world.add_fixed(w, Part::HoopWall);
    }
    for p in &top {
        world.add_fixed(p, Part::HoopTop);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn top_z(c: &Cuboid) -> f32 {
        c.center[2] + c.half_extents[2]
    }

    #[test]
    fn plates_frame_exactly_the_opening_and_cover_the_rest_of_the_top() {
        // Sample the top on a grid: every point is either over the opening or under a plate.
        for i in 0..=50 {
            for j in 0..=30 {
                let x = -HOOP_HALF_X + 0.5 * i as f32 / 50.0 * 0.999 + 0.0001;
                let y = -HOOP_HALF_Y + 0.3 * j as f32 / 30.0 * 0.999 + 0.0001;
                let covered = top_plates().iter().any(|p| {
                    (x - p.center[0]).abs() <= p.half_extents[0]
                        && (y - p.center[1]).abs() <= p.half_extents[1]
                });
                assert_ne!(covered, over_opening(x, y), "({x}, {y})");
            }
        }
        assert!(
            top_plates()
                .iter()
                .all(|p| (top_z(p) - HOOP_TOP_Z).abs() < 1e-6)
        );
    }

    #[test]
    fn ring_parts_do_not_overlap_and_leave_the_opening_clear() {
        let parts = parts(HoopShape::Ring);
        let overlap = |a: &Cuboid, b: &Cuboid| {
            (0..3).all(|i| {
                (a.center[i] - b.center[i]).abs() < a.half_extents[i] + b.half_extents[i] - 1e-6
            })
        };
        for (i, a) in parts.iter().enumerate() {
            for b in &parts[i + 1..] {
                assert!(!overlap(a, b), "{a:?} and {b:?}");
            }
        }
        // Nothing above the base plate reaches inside the ring's inner edge, and nothing stands
        // above the top.
        let inner = OPENING_HALF - SHEET;
        for c in &parts {
            let above_base = c.center[2] - c.half_extents[2] > TABLE_TOP_Z + SHEET - 1e-6;
            let reaches_in = (0..2).all(|i| c.center[i].abs() - c.half_extents[i] < inner - 1e-6);
            assert!(!(above_base && reaches_in), "{c:?} intrudes on the opening");
            assert!(top_z(c) <= HOOP_TOP_Z + 1e-6);
        }
    }

    #[test]
    fn walls_stand_on_the_table_below_the_top() {
        for w in walls() {
            assert!((w.center[2] - w.half_extents[2] - TABLE_TOP_Z).abs() < 1e-6);
            assert!(top_z(&w) <= HOOP_TOP_Z - SHEET + 1e-6);
        }
    }

    #[test]
    fn gate_on_both_sides_of_each_boundary() {
        let ok = [-0.3, 0.0, 1.2];
        assert!(gate_allows(&ok));
        let e = 1e-3;
        for (axis, lo, hi) in [(0, -0.6, 0.2), (1, -0.3, 0.3), (2, 0.80, 1.65)] {
            for (edge, inward) in [(lo, e), (hi, -e)] {
                let mut p = ok;
                p[axis] = edge + inward;
                assert!(gate_allows(&p), "{p:?}");
                p[axis] = edge - inward;
                assert!(!gate_allows(&p), "{p:?}");
            }
        }
        // The no-entry box, from each open side: x from -0.17, y from ±0.16, z from 1.03.
        for (p_out, p_in) in [
            ([-0.17 - e, 0.0, 0.9], [-0.17 + e, 0.0, 0.9]),
            ([0.0, -0.16 - e, 0.9], [0.0, -0.16 + e, 0.9]),
            ([0.0, 0.16 + e, 0.9], [0.0, 0.16 - e, 0.9]),
            ([0.0, 0.0, 1.03 + e], [0.0, 0.0, 1.03 - e]),
        ] {
            assert!(gate_allows(&p_out), "{p_out:?}");
            assert!(!gate_allows(&p_in), "{p_in:?}");
        }
    }
}
