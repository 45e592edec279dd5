// Canvas drawing of the three tasks from the server's `Geometry` and `RenderState`
// (core/src/sim/env.rs): Reaching from above; Placing from above and from the side; Lunar Lander
// from the side with terrain, flags, legs and engine flames. Plus the action as an arrow and a
// faded trail of the clip so far.

const COLORS = {
  tableTop: "#e8e0cc",
  tableEdge: "#cbbf9f",
  workspace: "#8b8f96",
  goal: "rgba(46, 125, 79, 0.22)",
  goalEdge: "#2e7d4f",
  gripper: "#33475b",
  finger: "#1f2d3a",
  hoop: "#8c96a3",
  hoopEdge: "#5f6b78",
  opening: "#2c333b",
  noEntry: "#b3413b",
  ball: "#e07a2f",
  arrow: "#d9480f",
  trail: "rgba(51, 71, 91, 0.35)",
  sky: "#1d2535",
  ground: "#c9cdd4",
  groundEdge: "#f3f4f6",
  lander: "#8a6fd6",
  landerEdge: "#e9e4fb",
  legContact: "#5cc98a",
  flag: "#f1c84b",
  pole: "#f3f4f6",
};

/** The views a task is drawn in. */
export function viewsFor(task) {
  if (task === "remote") return ["frame"];
  if (task === "placing") return ["top", "side"];
  if (task === "lunar-lander") return ["side"];
  return ["top"];
}

export function viewLabel(task, view) {
  if (task === "lunar-lander" || task === "remote") return "";
  return view === "top" ? "from above" : "from the side";
}

/** World rectangle `[x0, y0, x1, y1]` a view shows (y is up; for side views y is z). */
export function viewBounds(geometry, view) {
  const m = 0.04;
  switch (geometry.task) {
    case "reaching": {
      const t = geometry.table;
      return [t.center[0] - t.half_extents[0] - m, t.center[1] - t.half_extents[1] - m, t.center[0] + t.half_extents[0] + m, t.center[1] + t.half_extents[1] + m];
    }
    case "placing": {
      const w = geometry.workspace;
      const parts = geometry.hoop_parts;
      const xs = [w[0], w[3], ...parts.flatMap((p) => [p.center[0] - p.half_extents[0], p.center[0] + p.half_extents[0]])];
      if (view === "top") {
        const ys = [w[1], w[4], ...parts.flatMap((p) => [p.center[1] - p.half_extents[1], p.center[1] + p.half_extents[1]])];
        return [Math.min(...xs) - m, Math.min(...ys) - m, Math.max(...xs) + m, Math.max(...ys) + m];
      }
      const t = geometry.table;
      const tableTop = t.center[2] + t.half_extents[2];
      return [Math.min(...xs) - m, tableTop - 0.06, Math.max(...xs) + m, w[5] + m];
    }
    case "remote": {
      // An env in another process draws itself: its frames' size (Gymnasium's 600 x 400 until
      // one arrives).
      const [w, h] = geometry.frame_size ?? [600, 400];
      return [0, 0, w, h];
    }
    case "lunar-lander":
      // The lander starts at the world's top edge (Gymnasium's y = H), so a unit of headroom
      // keeps its hull (0.57 above its centre) and a first upward drift in view.
      return [0, 0, geometry.world[0], geometry.world[1] + 1];
    default:
      throw new Error(`unknown task ${geometry.task}`);
  }
}

/** Width / height of a view, for the canvas's CSS aspect ratio. */
export function viewAspect(geometry, view) {
  const b = viewBounds(geometry, view);
  return (b[2] - b[0]) / (b[3] - b[1]);
}

/** Size the canvas's backing store to its CSS box times the device pixel ratio. */
export function fitCanvas(canvas) {
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
  const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) {
    canvas.width = w;
    canvas.height = h;
  }
  return dpr;
}

function transform(canvas, bounds) {
  const [x0, y0, x1, y1] = bounds;
  const s = Math.min(canvas.width / (x1 - x0), canvas.height / (y1 - y0));
  const ox = (canvas.width - (x1 - x0) * s) / 2;
  const oy = (canvas.height - (y1 - y0) * s) / 2;
  return {
    s,
    x: (x) => ox + (x - x0) * s,
    y: (y) => oy + (y1 - y) * s,
  };
}

function rect(ctx, T, x0, y0, x1, y1) {
  ctx.rect(T.x(Math.min(x0, x1)), T.y(Math.max(y0, y1)), Math.abs(x1 - x0) * T.s, Math.abs(y1 - y0) * T.s);
}

function dashedRect(ctx, T, x0, y0, x1, y1, color, dpr) {
  ctx.save();
  ctx.setLineDash([6 * dpr, 5 * dpr]);
  ctx.strokeStyle = color;
  ctx.lineWidth = 1.2 * dpr;
  ctx.beginPath();
  rect(ctx, T, x0, y0, x1, y1);
  ctx.stroke();
  ctx.restore();
}

/** An arrow from screen point (x, y) along screen vector (dx, dy). */
function arrow(ctx, x, y, dx, dy, dpr, color = COLORS.arrow) {
  const len = Math.hypot(dx, dy);
  if (len < 2 * dpr) {
    // A (near) zero action: a ring says "stay".
    ctx.save();
    ctx.strokeStyle = color;
    ctx.lineWidth = 2.5 * dpr;
    ctx.beginPath();
    ctx.arc(x, y, 14 * dpr, 0, Math.PI * 2);
    ctx.stroke();
    ctx.restore();
    return;
  }
  const ux = dx / len;
  const uy = dy / len;
  const head = Math.min(14 * dpr, len * 0.5);
  ctx.save();
  ctx.strokeStyle = color;
  ctx.fillStyle = color;
  ctx.lineWidth = 4 * dpr;
  ctx.lineCap = "round";
  ctx.beginPath();
  ctx.moveTo(x, y);
  ctx.lineTo(x + dx - ux * head * 0.8, y + dy - uy * head * 0.8);
  ctx.stroke();
  ctx.beginPath();
  ctx.moveTo(x + dx, y + dy);
  ctx.lineTo(x + dx - ux * head - uy * head * 0.55, y + dy - uy * head + ux * head * 0.55);
  ctx.lineTo(x + dx - ux * head + uy * head * 0.55, y + dy - uy * head - ux * head * 0.55);
  ctx.closePath();
  ctx.fill();
  ctx.restore();
}

function label(ctx, text, dpr) {
  if (!text) return;
  ctx.save();
  ctx.font = `${12 * dpr}px system-ui, sans-serif`;
  ctx.fillStyle = "rgba(31, 35, 40, 0.65)";
  ctx.fillText(text, 8 * dpr, 16 * dpr);
  ctx.restore();
}

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

function trailPath(ctx, T, points, dpr) {
  if (points.length < 2) return;
  ctx.save();
  ctx.strokeStyle = COLORS.trail;
  ctx.lineWidth = 2.5 * dpr;
  ctx.lineJoin = "round";
  ctx.setLineDash([2 * dpr, 4 * dpr]);
  ctx.beginPath();
  points.forEach(([x, y], i) => (i ? ctx.lineTo(T.x(x), T.y(y)) : ctx.moveTo(T.x(x), T.y(y))));
  ctx.stroke();
  ctx.restore();
}

const ARROW_PX = 80; // a full action's arrow length (CSS pixels)

function drawReaching(ctx, T, g, s, opts, dpr) {
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

function drawPlacingTop(ctx, T, g, s, opts, dpr) {
  ctx.fillStyle = "#f1efe9";
  ctx.fillRect(0, 0, ctx.canvas.width, ctx.canvas.height);
  tableTop(ctx, T, g.table);
  const w = g.workspace;
  const n = g.no_entry;
  dashedRect(ctx, T, w[0], w[1], w[3], w[4], COLORS.workspace, dpr);
  dashedRect(ctx, T, n[0], n[1], n[3], n[4], COLORS.noEntry, dpr);
  // The hoop's parts from above; the opening is a dark hole.
  ctx.fillStyle = COLORS.hoop;
  ctx.strokeStyle = COLORS.hoopEdge;
  ctx.lineWidth = 1 * dpr;
  for (const p of g.hoop_parts) {
    ctx.beginPath();
    rect(ctx, T, p.center[0] - p.half_extents[0], p.center[1] - p.half_extents[1], p.center[0] + p.half_extents[0], p.center[1] + p.half_extents[1]);
    ctx.fill();
    ctx.stroke();
  }
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

function drawPlacingSide(ctx, T, g, s, opts, dpr) {
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
  ctx.fillStyle = "rgba(140, 150, 163, 0.55)";
  ctx.strokeStyle = COLORS.hoopEdge;
  ctx.lineWidth = 1 * dpr;
  for (const p of g.hoop_parts) {
    ctx.beginPath();
    rect(ctx, T, p.center[0] - p.half_extents[0], p.center[2] - p.half_extents[2], p.center[0] + p.half_extents[0], p.center[2] + p.half_extents[2]);
    ctx.fill();
    ctx.stroke();
  }
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

function drawLunar(ctx, T, g, s, opts, dpr) {
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

function clamp(v) {
  return Math.max(-1, Math.min(1, Number(v) || 0));
}

/**
 * Draw one view of a scene. `state` may be null (the scene without the robot).
 * `opts`: `{action, trail: [state...], label}`.
 */
export function drawScene(canvas, geometry, state, view, opts = {}) {
  const dpr = fitCanvas(canvas);
  const ctx = canvas.getContext("2d");
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  if (!geometry) return;
  const T = transform(canvas, viewBounds(geometry, view));
  if (state && state.task !== geometry.task) state = null;
  switch (geometry.task) {
    case "reaching":
      drawReaching(ctx, T, geometry, state, opts, dpr);
      break;
    case "placing":
      if (view === "side") drawPlacingSide(ctx, T, geometry, state, opts, dpr);
      else drawPlacingTop(ctx, T, geometry, state, opts, dpr);
      break;
    case "lunar-lander":
      drawLunar(ctx, T, geometry, state, opts, dpr);
      break;
    case "remote":
      drawRemote(canvas, ctx, geometry, state, view, opts, dpr);
      break;
    default:
      break;
  }
  label(ctx, opts.label ?? viewLabel(geometry.task, view), dpr);
}

// ---- an env in another process: its own frames ---------------------------------------------

/** Decoded frames by their base64 data, the latest few (a clip loops over them). */
const FRAME_IMAGES = new Map();
const FRAME_IMAGES_KEPT = 240;

/** The frame's decoded image, or null while it decodes (`onReady` runs once it has). */
function frameImage(frame, onReady) {
  let img = FRAME_IMAGES.get(frame.data);
  if (!img) {
    img = new Image();
    img.src = `data:${frame.media_type};base64,${frame.data}`;
    FRAME_IMAGES.set(frame.data, img);
    if (FRAME_IMAGES.size > FRAME_IMAGES_KEPT) FRAME_IMAGES.delete(FRAME_IMAGES.keys().next().value);
  }
  if (img.complete && img.naturalWidth > 0) return img;
  img.addEventListener("load", onReady, { once: true });
  return null;
}

/** The env's frame scaled into the canvas; without one (the env does not render), its
 * observation as numbers. */
function drawRemote(canvas, ctx, geometry, state, view, opts, dpr) {
  canvas.dataset.drawn = state?.frame?.data?.slice(-16) ?? "";
  ctx.fillStyle = COLORS.sky;
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  if (!state) return;
  if (state.frame) {
    const img = frameImage(state.frame, () => {
      // Still the frame this canvas should show: draw it now that it has decoded.
      if (canvas.dataset.drawn === state.frame.data.slice(-16)) drawScene(canvas, geometry, state, view, opts);
    });
    if (img) ctx.drawImage(img, 0, 0, canvas.width, canvas.height);
    return;
  }
  ctx.fillStyle = "#f3f4f6";
  ctx.font = `${13 * dpr}px system-ui, sans-serif`;
  const values = (state.observation ?? []).map((v) => v.toFixed(3));
  ctx.fillText(`${geometry.env}: observation`, 10 * dpr, 22 * dpr);
  values.slice(0, 24).forEach((v, i) => ctx.fillText(`[${i}] ${v}`, 10 * dpr, (44 + 18 * i) * dpr));
}

/** Words for an action, next to its arrow. */
export function describeAction(task, action) {
  if (!action) return "";
  if (task === "remote") return `acts [${action.map((v) => clamp(v).toFixed(2)).join(", ")}] (scaled to its range)`;
  const a = action.map((v) => clamp(v));
  const pct = (v) => `${Math.round(Math.abs(v) * 100)}%`;
  if (task === "lunar-lander") {
    const parts = [];
    if (a[0] > 0) parts.push(`the main engine at ${pct((a[0] + 1) / 2)}`);
    if (a[1] < -0.5) parts.push(`the left engine at ${pct(a[1])}`);
    else if (a[1] > 0.5) parts.push(`the right engine at ${pct(a[1])}`);
    return parts.length ? `fires ${parts.join(" and ")}` : "fires no engine";
  }
  const dir = (v, pos, neg) => (Math.abs(v) < 0.05 ? "" : `${v > 0 ? pos : neg} ${pct(v)}`);
  const parts = [dir(a[0], "right", "left"), dir(a[1], "away", "toward you")];
  if (task === "placing") {
    parts.push(dir(a[2], "up", "down"));
    parts.push(a[3] < 0 ? "gripper opens" : "gripper stays closed");
  }
  const moves = parts.filter(Boolean);
  return moves.length ? `moves ${moves.join(", ")}` : "stays still";
}
