// Small line plots as inline SVG: the trainer's live return curve, the dashboard's cumulative
// reward and alignment, the review page's returns.

const NS = "http://www.w3.org/2000/svg";
const PALETTE = ["#2f6f8f", "#d9480f", "#2e7d4f", "#7048e8", "#b3413b"];

function el(name, attrs = {}, text) {
  const e = document.createElementNS(NS, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, String(v));
  if (text !== undefined) e.textContent = text;
  return e;
}

function niceTicks(lo, hi, count = 4) {
  if (!Number.isFinite(lo) || !Number.isFinite(hi)) return [];
  if (hi === lo) return [lo];
  const step0 = (hi - lo) / count;
  const mag = 10 ** Math.floor(Math.log10(step0));
  const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= step0) ?? step0;
  const ticks = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) ticks.push(Number(v.toPrecision(10)));
  return ticks;
}

function fmt(v) {
  const a = Math.abs(v);
  if (a >= 10000) return `${(v / 1000).toFixed(0)}k`;
  if (a >= 1000) return `${(v / 1000).toFixed(1)}k`;
  if (a >= 10 || v === 0) return v.toFixed(0);
  return v.toFixed(a >= 1 ? 1 : 2);
}

/**
 * Render `series` (`[{label, points: [[x, y]...], color?, band?}]`) into `container` as an SVG;
 * `band` (`[[x, low, high]...]`) is shaded behind its line (e.g. mean ± s.e.).
 * `opts`: `{width, height, xLabel, yLabel, yMin, yMax, empty}`.
 */
export function linePlot(container, series, opts = {}) {
  const width = opts.width ?? 320;
  const height = opts.height ?? 140;
  const pad = { l: 40, r: 8, t: series.some((s) => s.label) ? 18 : 8, b: opts.xLabel ? 30 : 18 };
  const svg = el("svg", { viewBox: `0 0 ${width} ${height}`, role: "img", "aria-label": opts.title ?? opts.yLabel ?? "plot" });
  const bands = series.flatMap((s) => (s.band ?? []).flatMap(([x, lo, hi]) => [[x, lo], [x, hi]]));
  const all = series.flatMap((s) => s.points).concat(bands).filter(([x, y]) => Number.isFinite(x) && Number.isFinite(y));
  container.replaceChildren(svg);
  container.classList.add("plot");
  if (all.length === 0) {
    svg.append(el("text", { x: width / 2, y: height / 2, "text-anchor": "middle", class: "tick" }, opts.empty ?? "no data yet"));
    return svg;
  }
  let [x0, x1] = [Math.min(...all.map((p) => p[0])), Math.max(...all.map((p) => p[0]))];
  let [y0, y1] = [opts.yMin ?? Math.min(...all.map((p) => p[1])), opts.yMax ?? Math.max(...all.map((p) => p[1]))];
  if (x1 === x0) x1 = x0 + 1;
  if (y1 === y0) {
    y0 -= 1;
    y1 += 1;
  }
  const X = (x) => pad.l + ((x - x0) / (x1 - x0)) * (width - pad.l - pad.r);
  const Y = (y) => height - pad.b - ((y - y0) / (y1 - y0)) * (height - pad.t - pad.b);
  svg.append(el("line", { x1: pad.l, y1: height - pad.b, x2: width - pad.r, y2: height - pad.b, class: "axis" }));
  svg.append(el("line", { x1: pad.l, y1: pad.t, x2: pad.l, y2: height - pad.b, class: "axis" }));
  for (const t of niceTicks(y0, y1, 3)) {
    svg.append(el("line", { x1: pad.l - 3, y1: Y(t), x2: width - pad.r, y2: Y(t), class: "axis", opacity: 0.35 }));
    svg.append(el("text", { x: pad.l - 5, y: Y(t) + 3, "text-anchor": "end", class: "tick" }, fmt(t)));
  }
  for (const t of niceTicks(x0, x1, 4)) {
    svg.append(el("text", { x: X(t), y: height - pad.b + 12, "text-anchor": "middle", class: "tick" }, fmt(t)));
  }
  if (opts.xLabel) svg.append(el("text", { x: (pad.l + width - pad.r) / 2, y: height - 3, "text-anchor": "middle", class: "tick" }, opts.xLabel));
  if (opts.yLabel) svg.append(el("text", { x: 4, y: pad.t - 6 > 6 ? pad.t - 6 : 10, class: "tick" }, opts.yLabel));
  let legendX = pad.l + 4;
  series.forEach((s, i) => {
    const color = s.color ?? PALETTE[i % PALETTE.length];
    const pts = s.points.filter(([x, y]) => Number.isFinite(x) && Number.isFinite(y));
    const band = (s.band ?? []).filter((p) => p.every(Number.isFinite));
    if (band.length > 1) {
      const edge = band.map(([x, , hi]) => [x, hi]).concat(band.map(([x, lo]) => [x, lo]).reverse());
      svg.append(el("path", { d: `${edge.map(([x, y], j) => `${j ? "L" : "M"}${X(x).toFixed(1)},${Y(y).toFixed(1)}`).join("")}Z`, class: "band", fill: color }));
    }
    if (pts.length === 1) {
      svg.append(el("circle", { cx: X(pts[0][0]), cy: Y(pts[0][1]), r: 3, fill: color }));
    } else if (pts.length > 1) {
      svg.append(el("path", { d: pts.map(([x, y], j) => `${j ? "L" : "M"}${X(x).toFixed(1)},${Y(y).toFixed(1)}`).join(""), class: "line", stroke: color }));
    }
    if (s.label) {
      svg.append(el("rect", { x: legendX, y: 4, width: 10, height: 3, fill: color }));
      const text = el("text", { x: legendX + 14, y: 10, class: "legend" }, s.label);
      svg.append(text);
      legendX += 24 + s.label.length * 6;
    }
  });
  return svg;
}
