// Canvas drawing of a scene from the server's `Geometry` and `RenderState` (core/src/sim/env.rs):
// which views a task has and what each shows, the dispatch to the task's drawing (Reaching and
// Placing in draw_tabletop.js, Lunar Lander in draw_lunar.js), an env in another process by its
// own frames, and words for an action.

import { COLORS, clamp, label, transform } from "./canvas_kit.js";
import { drawLunar } from "./draw_lunar.js";
import { drawPlacingSide, drawPlacingTop, drawReaching } from "./draw_tabletop.js";

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
