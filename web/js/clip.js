// Loops clips of render states on canvases. Several clips started together stay in sync (the
// shorter one holds its last frame), which is what a preference query needs; the last frame
// holds for a moment, with the action arrow, before the loop starts again.

import { drawScene } from "./render.js";

export class ClipLoop {
  /**
   * `panes`: `[{clip: {geometry, frames}, canvases: [{canvas, view}], action?}]`.
   * `fps`: playback rate. `holdMs`: pause on the last frame.
   */
  constructor(panes, { fps = 20, holdMs = 900 } = {}) {
    this.panes = panes;
    this.fps = fps;
    this.holdMs = holdMs;
    this.length = Math.max(1, ...panes.map((p) => p.clip.frames.length));
    this.start = performance.now();
    this.raf = 0;
    this.running = false;
    this.lastIndex = -1;
  }

  play() {
    this.running = true;
    const tick = (now) => {
      if (!this.running) return;
      this.drawAt(now);
      this.raf = requestAnimationFrame(tick);
    };
    this.raf = requestAnimationFrame(tick);
  }

  stop() {
    this.running = false;
    cancelAnimationFrame(this.raf);
  }

  /** Redraw now (after a resize). */
  redraw() {
    this.lastIndex = -1;
    this.drawAt(performance.now());
  }

  drawAt(now) {
    const period = (this.length / this.fps) * 1000 + this.holdMs;
    const t = (now - this.start) % period;
    const index = Math.min(this.length - 1, Math.floor((t / 1000) * this.fps));
    if (index === this.lastIndex) return;
    this.lastIndex = index;
    for (const pane of this.panes) {
      const frames = pane.clip.frames;
      const i = Math.min(index, frames.length - 1);
      const last = i === frames.length - 1;
      for (const { canvas, view } of pane.canvases) {
        drawScene(canvas, pane.clip.geometry, frames[i] ?? null, view, {
          trail: frames.slice(0, i + 1),
          action: last ? pane.action : null,
        });
      }
    }
  }
}
