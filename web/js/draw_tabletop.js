// Reaching and Placing on their table (core/src/sim/env.rs's `Geometry` and `RenderState`):
// Reaching from above, Placing from above and from the side, with the gripper, ball and hoop.

import { ARROW_PX, COLORS, arrow, clamp, dashedRect, rect, trailPath } from "./canvas_kit.js";

function tableTop(ctx, T, table) {
  const [cx, cy] = table.center;
  const [hx, hy] = table.half_extents;
  ctx.fillStyle = COLORS.tableTop;
  ctx.strokeStyle = COLORS.tableEdge;
  ctx.lineWidth = 2;
  ctx.beginPath();
  rect(ctx, T, cx - hx, cy - hy, cx + hx, cy + hy);
  ctx.fill();
  ctx.stroke();
}

/**
 * How far Placing's gripper is open, 0 (closed) to 1: the gripper opens gradually, and the ball
 * drops when its level reaches the geometry's release level, so the fingers show the way there.
 * Render files written before the gradual gripper carry only `gripper_closed`.
 */
function openness(g, s) {
  if (!s.ball_held) return 1;
  if (typeof s.grip_level !== "number") return s.gripper_closed ? 0 : 1;
  const release = typeof g.release_level === "number" ? g.release_level : -1;
  return Math.max(0, Math.min(1, (1 - s.grip_level) / Math.max(1e-6, 1 - release)));
}

/** Fingers' gap: `open` 0 is closed, 1 fully open (booleans read as 0 or 1). */
function fingerGap(width, open, closedFrac, openFrac) {
  const o = typeof open === "boolean" ? (open ? 1 : 0) : open;
  return width * (closedFrac + (openFrac - closedFrac) * o);
}

function gripperFromAbove(ctx, T, x, y, open, dpr) {
  const r = Math.max(9 * dpr, 0.022 * T.s);
  const px = T.x(x);
  const py = T.y(y);
  ctx.save();
  ctx.fillStyle = COLORS.gripper;
  ctx.beginPath();
  ctx.arc(px, py, r, 0, Math.PI * 2);
  ctx.fill();
  // Two fingers, apart as the gripper opens.
  const gap = fingerGap(r, open, 0.35, 0.9);
  ctx.fillStyle = COLORS.finger;
  ctx.fillRect(px - gap - r * 0.3, py - r * 1.25, r * 0.3, r * 2.5);
  ctx.fillRect(px + gap, py - r * 1.25, r * 0.3, r * 2.5);
  ctx.restore();
}

function gripperFromSide(ctx, T, x, z, open, dpr) {
  const px = T.x(x);
  const pz = T.y(z);
  const w = Math.max(8 * dpr, 0.03 * T.s);
  const gap = fingerGap(w, open, 0.35, 0.85);
  ctx.save();
  ctx.fillStyle = COLORS.gripper;
  ctx.fillRect(px - 3 * dpr, 0, 6 * dpr, pz - w * 0.6); // the arm from above
  ctx.fillRect(px - w, pz - w * 0.8, w * 2, w * 0.5); // the palm
  ctx.fillStyle = COLORS.finger;
  ctx.fillRect(px - gap - w * 0.25, pz - w * 0.4, w * 0.25, w * 1.2);
  ctx.fillRect(px + gap, pz - w * 0.4, w * 0.25, w * 1.2);
  ctx.restore();
}

function ball(ctx, T, x, y, radius, dpr) {
  ctx.save();
  ctx.fillStyle = COLORS.ball;
  ctx.strokeStyle = "#9c4a12";
  ctx.lineWidth = 1.5 * dpr;
  ctx.beginPath();
  ctx.arc(T.x(x), T.y(y), Math.max(5 * dpr, radius * T.s), 0, Math.PI * 2);
  ctx.fill();
  ctx.stroke();
  ctx.restore();
}

/** The hoop's boxes projected on x and world axis `up` (1: from above, 2: from the side). */
function hoopParts(ctx, T, parts, up, fill, dpr) {
  ctx.fillStyle = fill;
  ctx.strokeStyle = COLORS.hoopEdge;
  ctx.lineWidth = 1 * dpr;
  for (const p of parts) {
    const [cx, hx, cu, hu] = [p.center[0], p.half_extents[0], p.center[up], p.half_extents[up]];
    ctx.beginPath();
    rect(ctx, T, cx - hx, cu - hu, cx + hx, cu + hu);
    ctx.fill();
    ctx.stroke();
  }
}

export function drawReaching(ctx, T, g, s, opts, dpr) {
  ctx.fillStyle = "#f1efe9";
  ctx.fillRect(0, 0, ctx.canvas.width, ctx.canvas.height);
  tableTop(ctx, T, g.table);
  const w = g.workspace;
  dashedRect(ctx, T, w[0], w[1], w[2], w[3], COLORS.workspace, dpr);
  const [gx0, gy0, gx1, gy1] = g.goal;
  ctx.fillStyle = COLORS.goal;
  ctx.strokeStyle = COLORS.goalEdge;
  ctx.lineWidth = 2 * dpr;
  ctx.beginPath();
  rect(ctx, T, gx0, gy0, gx1, gy1);
  ctx.fill();
  ctx.stroke();
  ctx.fillStyle = COLORS.goalEdge;
  ctx.font = `${11 * dpr}px system-ui, sans-serif`;
  ctx.fillText("goal", T.x(gx0) + 4 * dpr, T.y(gy1) + 14 * dpr);
  if (!s) return;
  trailPath(ctx, T, (opts.trail || []).map((t) => [t.gripper.position[0], t.gripper.position[1]]), dpr);
  const [x, y] = s.gripper.position;
  gripperFromAbove(ctx, T, x, y, false, dpr);
  if (opts.action) arrow(ctx, T.x(x), T.y(y), clamp(opts.action[0]) * ARROW_PX * dpr, -clamp(opts.action[1]) * ARROW_PX * dpr, dpr);
}

export function drawPlacingTop(ctx, T, g, s, opts, dpr) {
  ctx.fillStyle = "#f1efe9";
  ctx.fillRect(0, 0, ctx.canvas.width, ctx.canvas.height);
  tableTop(ctx, T, g.table);
  const w = g.workspace;
  const n = g.no_entry;
  dashedRect(ctx, T, w[0], w[1], w[3], w[4], COLORS.workspace, dpr);
  dashedRect(ctx, T, n[0], n[1], n[3], n[4], COLORS.noEntry, dpr);
  // The hoop's parts from above; the opening is a dark hole.
  hoopParts(ctx, T, g.hoop_parts, 1, COLORS.hoop, dpr);
  const o = g.opening;
  ctx.fillStyle = COLORS.opening;
  ctx.beginPath();
  rect(ctx, T, o[0], o[1], o[2], o[3]);
  ctx.fill();
  if (!s) return;
  trailPath(ctx, T, (opts.trail || []).map((t) => [t.gripper.position[0], t.gripper.position[1]]), dpr);
  const [x, y] = s.gripper.position;
  if (!s.ball_held) ball(ctx, T, s.ball[0], s.ball[1], g.ball_radius, dpr);
  gripperFromAbove(ctx, T, x, y, openness(g, s), dpr);
  if (s.ball_held) ball(ctx, T, s.ball[0], s.ball[1], g.ball_radius * 0.8, dpr);
  if (opts.action) arrow(ctx, T.x(x), T.y(y), clamp(opts.action[0]) * ARROW_PX * dpr, -clamp(opts.action[1]) * ARROW_PX * dpr, dpr);
}

export function drawPlacingSide(ctx, T, g, s, opts, dpr) {
  ctx.fillStyle = "#f4f3ef";
  ctx.fillRect(0, 0, ctx.canvas.width, ctx.canvas.height);
  const t = g.table;
  const top = t.center[2] + t.half_extents[2];
  ctx.fillStyle = COLORS.tableTop;
  ctx.fillRect(0, T.y(top), ctx.canvas.width, ctx.canvas.height - T.y(top));
  ctx.strokeStyle = COLORS.tableEdge;
  ctx.lineWidth = 2 * dpr;
  ctx.beginPath();
  ctx.moveTo(0, T.y(top));
  ctx.lineTo(ctx.canvas.width, T.y(top));
  ctx.stroke();
  const w = g.workspace;
  const n = g.no_entry;
  dashedRect(ctx, T, w[0], w[2], w[3], w[5], COLORS.workspace, dpr);
  dashedRect(ctx, T, n[0], n[2], n[3], n[5], COLORS.noEntry, dpr);
  hoopParts(ctx, T, g.hoop_parts, 2, "rgba(140, 150, 163, 0.55)", dpr);
  // The opening's rim.
  ctx.strokeStyle = COLORS.opening;
  ctx.lineWidth = 3 * dpr;
  ctx.beginPath();
  ctx.moveTo(T.x(g.opening[0]), T.y(g.hoop_top_z));
  ctx.lineTo(T.x(g.opening[2]), T.y(g.hoop_top_z));
  ctx.stroke();
  if (!s) return;
  trailPath(ctx, T, (opts.trail || []).map((f) => [f.gripper.position[0], f.gripper.position[2]]), dpr);
  const [x, , z] = s.gripper.position;
  const open = openness(g, s);
  gripperFromSide(ctx, T, x, z, open, dpr);
  ball(ctx, T, s.ball[0], s.ball[2], g.ball_radius, dpr);
  // How far the gripper has opened toward letting the ball go.
  ctx.fillStyle = COLORS.hoopEdge;
  ctx.font = `${11 * dpr}px system-ui, sans-serif`;
  const grip = s.ball_held ? (open > 0 ? `gripper ${Math.round(open * 100)} % open to release` : "gripper closed") : "ball released";
  ctx.fillText(grip, 6 * dpr, 14 * dpr);
  if (opts.action) arrow(ctx, T.x(x), T.y(z), clamp(opts.action[0]) * ARROW_PX * dpr, -clamp(opts.action[2]) * ARROW_PX * dpr, dpr);
}
