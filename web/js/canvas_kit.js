// What every view is drawn with: the palette, world-to-canvas transform, rectangles, the action
// arrow, the clip's trail and a view's label (render.js and the per-task drawings share them).

export const COLORS = {
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

export function transform(canvas, bounds) {
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

export function rect(ctx, T, x0, y0, x1, y1) {
  ctx.rect(T.x(Math.min(x0, x1)), T.y(Math.max(y0, y1)), Math.abs(x1 - x0) * T.s, Math.abs(y1 - y0) * T.s);
}

export function dashedRect(ctx, T, x0, y0, x1, y1, color, dpr) {
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
export function arrow(ctx, x, y, dx, dy, dpr, color = COLORS.arrow) {
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

export function label(ctx, text, dpr) {
  if (!text) return;
  ctx.save();
  ctx.font = `${12 * dpr}px system-ui, sans-serif`;
  ctx.fillStyle = "rgba(31, 35, 40, 0.65)";
  ctx.fillText(text, 8 * dpr, 16 * dpr);
  ctx.restore();
}

export function trailPath(ctx, T, points, dpr) {
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

export const ARROW_PX = 80; // a full action's arrow length (CSS pixels)

export function clamp(v) {
  return Math.max(-1, Math.min(1, Number(v) || 0));
}
