// A stage: one canvas per view of a task, each sized to its view's aspect ratio, redrawn when
// the page is resized.

import { viewAspect, viewsFor } from "./render.js";

/** Fill `container` with canvases for `geometry`'s views; returns `[{canvas, view}]`. */
export function buildStage(container, geometry, { maxHeight = "58vh" } = {}) {
  container.replaceChildren();
  if (!geometry) return [];
  return viewsFor(geometry.task).map((view) => {
    const wrap = document.createElement("div");
    wrap.className = "view";
    const canvas = document.createElement("canvas");
    canvas.dataset.view = view;
    const ratio = viewAspect(geometry, view);
    canvas.style.aspectRatio = String(ratio);
    // As wide as the column allows, but never taller than `maxHeight` (keeping the ratio).
    canvas.style.width = `min(100%, calc(${maxHeight} * ${ratio.toFixed(4)}))`;
    canvas.style.margin = "0 auto";
    canvas.setAttribute("role", "img");
    const what = geometry.task === "remote" ? `${geometry.env}` : `${geometry.task} ${view === "top" ? "from above" : "from the side"}`;
    canvas.setAttribute("aria-label", what);
    wrap.append(canvas);
    container.append(wrap);
    return { canvas, view };
  });
}

/** Call `fn` when any of `elements` changes size. */
export function onResize(elements, fn) {
  const ro = new ResizeObserver(() => fn());
  for (const e of elements) ro.observe(e);
  return ro;
}
