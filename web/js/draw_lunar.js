// Lunar Lander from the side (core/src/sim/env.rs's `Geometry` and `RenderState`): terrain,
// flags, the hull and legs, and the engines' flames.

import { ARROW_PX, COLORS, arrow, clamp, trailPath } from "./canvas_kit.js";

function bodyPoint(pose, bx, by) {
  const c = Math.cos(pose.angle);
  const s = Math.sin(pose.angle);
  return [pose.x + c * bx - s * by, pose.y + s * bx + c * by];
}

function flame(ctx, T, pose, base, dir, length, width, dpr) {
  if (length <= 0) return;
  const [bx, by] = base;
  const tip = bodyPoint(pose, bx + dir[0] * length, by + dir[1] * length);
  const l = bodyPoint(pose, bx - dir[1] * width, by + dir[0] * width);
  const r = bodyPoint(pose, bx + dir[1] * width, by - dir[0] * width);
  const grad = ctx.createLinearGradient(T.x((l[0] + r[0]) / 2), T.y((l[1] + r[1]) / 2), T.x(tip[0]), T.y(tip[1]));
  grad.addColorStop(0, "rgba(255, 236, 160, 0.95)");
  grad.addColorStop(0.5, "rgba(255, 150, 50, 0.85)");
  grad.addColorStop(1, "rgba(220, 60, 30, 0)");
  ctx.fillStyle = grad;
  ctx.beginPath();
  ctx.moveTo(T.x(l[0]), T.y(l[1]));
  ctx.lineTo(T.x(tip[0]), T.y(tip[1]));
  ctx.lineTo(T.x(r[0]), T.y(r[1]));
  ctx.closePath();
  ctx.fill();
}

export function drawLunar(ctx, T, g, s, opts, dpr) {
  ctx.fillStyle = COLORS.sky;
  ctx.fillRect(0, 0, ctx.canvas.width, ctx.canvas.height);
  const [W] = g.world;
  // Terrain: the polyline closed down to the bottom of the world.
  ctx.fillStyle = COLORS.ground;
  ctx.strokeStyle = COLORS.groundEdge;
  ctx.lineWidth = 2 * dpr;
  ctx.beginPath();
  ctx.moveTo(T.x(0), T.y(0));
  for (const [x, y] of g.terrain) ctx.lineTo(T.x(x), T.y(y));
  ctx.lineTo(T.x(W), T.y(0));
  ctx.closePath();
  ctx.fill();
  ctx.beginPath();
  g.terrain.forEach(([x, y], i) => (i ? ctx.lineTo(T.x(x), T.y(y)) : ctx.moveTo(T.x(x), T.y(y))));
  ctx.stroke();
  for (const [fx, fy] of g.flags) {
    ctx.strokeStyle = COLORS.pole;
    ctx.lineWidth = 2 * dpr;
    ctx.beginPath();
    ctx.moveTo(T.x(fx), T.y(fy));
    ctx.lineTo(T.x(fx), T.y(fy + g.flag_height));
    ctx.stroke();
    ctx.fillStyle = COLORS.flag;
    ctx.beginPath();
    ctx.moveTo(T.x(fx), T.y(fy + g.flag_height));
    ctx.lineTo(T.x(fx), T.y(fy + g.flag_height * 0.7));
    ctx.lineTo(T.x(fx + g.flag_height * 0.45), T.y(fy + g.flag_height * 0.85));
    ctx.closePath();
    ctx.fill();
  }
  if (!s) return;
  trailPath(ctx, T, (opts.trail || []).map((f) => [f.hull.x, f.hull.y]), dpr);
  const hull = s.hull;
  const minY = Math.min(...g.hull.map((p) => p[1]));
  const maxX = Math.max(...g.hull.map((p) => p[0]));
  // Flames first, so the body covers their roots.
  flame(ctx, T, hull, [0, minY], [0, -1], s.main_engine * 1.1, 0.22, dpr);
  if (s.side_engine < 0) flame(ctx, T, hull, [-maxX, 0.1], [-1, 0], -s.side_engine * 0.6, 0.1, dpr);
  if (s.side_engine > 0) flame(ctx, T, hull, [maxX, 0.1], [1, 0], s.side_engine * 0.6, 0.1, dpr);
  const [lw, lh] = g.leg_half_extents;
  s.legs.forEach((leg, i) => {
    const corners = [[-lw, -lh], [lw, -lh], [lw, lh], [-lw, lh]].map(([x, y]) => bodyPoint(leg, x, y));
    ctx.fillStyle = s.leg_contact[i] ? COLORS.legContact : COLORS.lander;
    ctx.strokeStyle = COLORS.landerEdge;
    ctx.lineWidth = 1 * dpr;
    ctx.beginPath();
    corners.forEach(([x, y], j) => (j ? ctx.lineTo(T.x(x), T.y(y)) : ctx.moveTo(T.x(x), T.y(y))));
    ctx.closePath();
    ctx.fill();
    ctx.stroke();
  });
  ctx.fillStyle = COLORS.lander;
  ctx.strokeStyle = COLORS.landerEdge;
  ctx.lineWidth = 1.5 * dpr;
  ctx.beginPath();
  g.hull.forEach(([bx, by], i) => {
    const [x, y] = bodyPoint(hull, bx, by);
    if (i) ctx.lineTo(T.x(x), T.y(y));
    else ctx.moveTo(T.x(x), T.y(y));
  });
  ctx.closePath();
  ctx.fill();
  ctx.stroke();
  if (opts.action) {
    // The commanded push: main engine up (body frame), a side engine sideways (the left engine
    // pushes right). Engines below their thresholds push nothing.
    const a0 = clamp(opts.action[0]);
    const a1 = clamp(opts.action[1]);
    const main = a0 > 0 ? (a0 + 1) / 2 : 0;
    const side = Math.abs(a1) > 0.5 ? -Math.sign(a1) * Math.abs(a1) : 0;
    const c = Math.cos(hull.angle);
    const sn = Math.sin(hull.angle);
    const dx = c * side - sn * main;
    const dy = sn * side + c * main;
    arrow(ctx, T.x(hull.x), T.y(hull.y), dx * ARROW_PX * dpr, -dy * ARROW_PX * dpr, dpr, "#ffb347");
  }
}
