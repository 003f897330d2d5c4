// The site map on a canvas, drawn to scale in the map frame (metres, y up).
//
// Three layers, so a fleet streaming poses costs little: the occupancy grid (and the coverage raster) are
// ImageData painted once per upload into offscreen canvases at one pixel per cell; everything that moves only
// when data or the view changes (live points, paths, regions, corrections) is painted into a cached canvas
// `layers`; each animation frame copies that cache and draws the robots on top. Frames are requested with
// requestAnimationFrame only when something changed.

import {
  COLORS,
  SPEED_BUCKETS,
  centroid,
  closed,
  gridCanvas,
  paletteAt,
  polyPath,
  rgb,
  speedRange,
  wpOf,
  xyOf,
} from "./marks.js";
import { drawPick, drawRobots, renderLayers } from "./layers.js";

export { PALETTE, paletteAt, paletteGradient, speedRange } from "./marks.js";

export class MapView {
  constructor(canvas, { scaleBar, scaleLabel, cursorReadout, onPick, onRobotClick, onViewChange } = {}) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.layers = document.createElement("canvas");
    this.lctx = this.layers.getContext("2d");
    this.scaleBar = scaleBar;
    this.scaleLabel = scaleLabel;
    this.cursorReadout = cursorReadout;
    this.onPick = onPick;
    this.onRobotClick = onRobotClick;
    this.onViewChange = onViewChange;

    this.view = { cx: 0, cy: 0, scale: 40 }; // px per metre
    this.cssW = 1;
    this.cssH = 1;
    this.dpr = 1;
    this.grid = null; // the site's OccupancyGridDoc
    this.gridImg = null;
    this.coverage = null;
    this.coverageImg = null;
    this.coverageCells = 0;
    this.live = [];
    this.plan = null; // { doc, paths: [{path, kind, color}], regions, start, end, vmin, vmax }
    this.others = []; // [{ planId, path: Path2D }]
    this.streaming = []; // RegionReady of plans being computed
    this.corrections = []; // CorrectionDoc
    this.missed = []; // [[x, y], ...] stretches
    this.robots = new Map(); // id -> { x, y, yaw, alive, trail: [[x,y]], label, sub, selected }
    this.show = {
      path: true,
      others: true,
      regions: true,
      live: true,
      coverage: true,
      corrections: true,
      trails: true,
    };
    this.pick = null; // { radius } while choosing a start
    this.cursor = null; // world point under the pointer
    this.hoverRobot = null;

    this.layersDirty = true;
    this.frameQueued = false;
    this.stats = { frames: 0, layerRenders: 0, lastFrameMs: 0, robotsDrawn: 0, correctionMarkers: 0, skipped: 0 };

    this.installInput();
    new ResizeObserver(() => this.resize()).observe(canvas.parentElement);
    this.resize();
  }

  // --- data -------------------------------------------------------------------------------------------------

  setGrid(doc) {
    const g = this.grid;
    const fresh =
      !g ||
      g.width !== doc.width ||
      g.height !== doc.height ||
      g.origin[0] !== doc.origin[0] ||
      g.origin[1] !== doc.origin[1] ||
      g.resolution !== doc.resolution;
    this.grid = doc;
    this.gridImg = gridCanvas(doc, (v) => (v === 0 ? COLORS.free : v === 100 ? COLORS.occupied : COLORS.unknown));
    if (fresh) this.fit();
    this.invalidate();
  }

  clearSite() {
    this.grid = null;
    this.gridImg = null;
    this.coverage = null;
    this.coverageImg = null;
    this.coverageCells = 0;
    this.live = [];
    this.plan = null;
    this.others = [];
    this.streaming = [];
    this.corrections = [];
    this.missed = [];
    this.robots.clear();
    this.invalidate();
  }

  setCoverage(doc) {
    this.coverage = doc;
    let n = 0;
    if (doc) {
      for (const v of doc.cells) if (v === 100) n++;
      this.coverageImg = n ? gridCanvas(doc, (v) => (v === 100 ? COLORS.coverage : null)) : null;
    } else {
      this.coverageImg = null;
    }
    this.coverageCells = n;
    this.invalidate();
  }

  setLive(points) {
    this.live = points || [];
    this.invalidate();
  }

  /** The selected plan's document (coloured by speed), or null. */
  setPlan(doc) {
    if (this.plan && doc && this.plan.doc === doc) return;
    if (!doc || !doc.waypoints || doc.waypoints.length === 0) {
      this.plan = doc ? { doc, paths: [], regions: [], vmin: 0, vmax: 0 } : null;
      this.invalidate();
      return;
    }
    const [vmin, vmax] = speedRange(doc);
    const span = vmax - vmin || 1;
    // One Path2D per (kind, speed bucket): a few strokes however long the path.
    const buckets = new Map();
    const w = doc.waypoints;
    for (let i = 0; i + 1 < w.length; i++) {
      const a = w[i];
      const b = w[i + 1];
      const kind = a.kind === "transit" || b.kind === "transit" ? "transit" : "cover";
      const t = ((a.v + b.v) / 2 - vmin) / span;
      const k = Math.min(SPEED_BUCKETS - 1, Math.max(0, Math.floor(t * SPEED_BUCKETS)));
      const key = `${kind}:${k}`;
      let entry = buckets.get(key);
      if (!entry) {
        entry = { kind, path: new Path2D(), color: rgb(paletteAt((k + 0.5) / SPEED_BUCKETS)), last: null };
        buckets.set(key, entry);
      }
      if (entry.last !== i) entry.path.moveTo(a.x, a.y);
      entry.path.lineTo(b.x, b.y);
      entry.last = i + 1;
    }
    const regions = (doc.regions || []).map((r) => ({ id: r.id, path: closed(r.polygon), c: centroid(r.polygon) }));
    const cum = new Float64Array(w.length);
    for (let i = 1; i < w.length; i++) cum[i] = cum[i - 1] + Math.hypot(w[i].x - w[i - 1].x, w[i].y - w[i - 1].y);
    const paths = [...buckets.values()].sort((a, b) => (a.kind === b.kind ? 0 : a.kind === "transit" ? -1 : 1));
    this.plan = {
      doc,
      paths,
      regions,
      vmin,
      vmax,
      start: [w[0].x, w[0].y],
      end: [w[w.length - 1].x, w[w.length - 1].y],
      cum,
    };
    this.driven = null;
    this.drivenFraction = -1;
    this.invalidate();
  }

  /** The driven fraction (by length) of the selected plan: that much of its path is washed out. */
  setDriven(fraction) {
    const plan = this.plan;
    const f = fraction === undefined || fraction === null ? 0 : Math.min(Math.max(fraction, 0), 1);
    // Steps under 0.2 % of the path wait (the layers are repainted for it).
    if (!plan || !plan.cum) return;
    if (Math.abs(f - this.drivenFraction) < 0.002 && !(f === 1 && this.drivenFraction !== 1)) return;
    this.drivenFraction = f;
    const w = plan.doc.waypoints;
    const target = f * plan.cum[w.length - 1];
    const p = new Path2D();
    p.moveTo(w[0].x, w[0].y);
    let i = 1;
    for (; i < w.length && plan.cum[i] <= target; i++) p.lineTo(w[i].x, w[i].y);
    if (i < w.length && target > plan.cum[i - 1]) {
      const k = (target - plan.cum[i - 1]) / (plan.cum[i] - plan.cum[i - 1] || 1);
      p.lineTo(w[i - 1].x + (w[i].x - w[i - 1].x) * k, w[i - 1].y + (w[i].y - w[i - 1].y) * k);
    }
    this.driven = f > 0 ? p : null;
    this.invalidate();
  }

  /** Other plans of the site drawn faintly (active ones): [{ planId, doc }]. */
  setOthers(list) {
    const had = new Map(this.others.map((o) => [o.planId, o]));
    const same = list.length === this.others.length && list.every(({ planId, doc }) => had.get(planId)?.doc === doc);
    if (same) return;
    this.others = list.map(({ planId, doc }) => {
      const o = had.get(planId);
      return o && o.doc === doc ? o : { planId, doc, path: polyPath(doc.waypoints, wpOf) };
    });
    this.invalidate();
  }

  setStreaming(regions) {
    this.streaming = regions.map((r) => ({
      id: r.region,
      outline: closed(r.polygon),
      path: polyPath(r.path, xyOf),
      c: centroid(r.polygon),
    }));
    this.invalidate();
  }

  setCorrections(list, missed) {
    this.corrections = list.map((c) => {
      const pts = c.waypoints || [];
      const mid = pts.length ? pts[Math.floor(pts.length / 2)] : null;
      return {
        doc: c,
        patch: pts.length > 1 ? polyPath(pts, wpOf) : null,
        marker: mid ? [mid.x, mid.y] : c.skipped && c.skipped.length ? c.skipped[0] : null,
        skipped: c.skipped && c.skipped.length > 1 ? polyPath(c.skipped, xyOf) : null,
        skippedEnds: c.skipped && c.skipped.length ? [c.skipped[0], c.skipped[c.skipped.length - 1]] : [],
      };
    });
    this.missed = (missed || []).filter((m) => m.length > 1).map((m) => polyPath(m, xyOf));
    this.invalidate();
  }

  /** Robots to draw: Map id -> { x, y, yaw, alive, trail, label, sub, selected }. Cheap: no layer repaint. */
  setRobots(robots) {
    this.robots = robots;
    this.requestFrame();
  }

  setLayer(name, on) {
    this.show[name] = on;
    this.invalidate();
  }

  setPick(pick) {
    this.pick = pick;
    this.canvas.classList.toggle("picking", !!pick);
    this.requestFrame();
  }

  // --- view -------------------------------------------------------------------------------------------------

  resize() {
    const box = this.canvas.parentElement.getBoundingClientRect();
    this.dpr = window.devicePixelRatio || 1;
    this.cssW = Math.max(1, Math.round(box.width));
    this.cssH = Math.max(1, Math.round(box.height));
    for (const c of [this.canvas, this.layers]) {
      c.width = Math.round(this.cssW * this.dpr);
      c.height = Math.round(this.cssH * this.dpr);
    }
    this.canvas.style.width = `${this.cssW}px`;
    this.canvas.style.height = `${this.cssH}px`;
    if (!this.fitted && this.grid) this.fit();
    this.invalidate();
  }

  fit() {
    if (!this.grid) return;
    const g = this.grid;
    const w = g.width * g.resolution;
    const h = g.height * g.resolution;
    // Room for the overlays: legend and tools above, scale bar and cursor below.
    const [top, bottom, side] = [58, 52, 24];
    const s = Math.max(1e-3, Math.min((this.cssW - 2 * side) / w, (this.cssH - top - bottom) / h));
    this.view.scale = s;
    this.view.cx = g.origin[0] + w / 2;
    this.view.cy = g.origin[1] + h / 2 - (bottom - top) / 2 / s;
    this.fitted = this.cssW > 1;
    this.viewChanged();
  }

  zoomAt(sx, sy, factor) {
    const [wx, wy] = this.toWorld(sx, sy);
    const s = Math.min(Math.max(this.view.scale * factor, 0.5), 2000);
    this.view.scale = s;
    // Keep (wx, wy) under the cursor.
    this.view.cx = wx - (sx - this.cssW / 2) / s;
    this.view.cy = wy + (sy - this.cssH / 2) / s;
    this.viewChanged();
  }

  centerOn(x, y) {
    this.view.cx = x;
    this.view.cy = y;
    this.viewChanged();
  }

  viewChanged() {
    this.invalidate();
    this.updateScaleBar();
    if (this.onViewChange) this.onViewChange(this.view);
  }

  /** CSS pixels (relative to the canvas) of a map point. */
  toScreen(x, y) {
    const v = this.view;
    return [(x - v.cx) * v.scale + this.cssW / 2, this.cssH / 2 - (y - v.cy) * v.scale];
  }

  toWorld(sx, sy) {
    const v = this.view;
    return [(sx - this.cssW / 2) / v.scale + v.cx, v.cy - (sy - this.cssH / 2) / v.scale];
  }

  /** The grid value under a map point (0, 100, -1), or null outside the map. */
  cellAt(x, y) {
    const g = this.grid;
    if (!g) return null;
    const c = Math.floor((x - g.origin[0]) / g.resolution);
    const r = Math.floor((y - g.origin[1]) / g.resolution);
    if (c < 0 || r < 0 || c >= g.width || r >= g.height) return null;
    return g.cells[r * g.width + c];
  }

  updateScaleBar() {
    if (!this.scaleBar) return;
    // The longest 1-2-5 length that fits in 140 px.
    const target = 140 / this.view.scale;
    const p = Math.pow(10, Math.floor(Math.log10(target)));
    let len = p;
    for (const m of [1, 2, 5, 10]) if (m * p <= target) len = m * p;
    this.scaleBar.style.width = `${Math.round(len * this.view.scale)}px`;
    const [n, unit] = len >= 1 ? [len, "m"] : len >= 0.01 ? [len * 100, "cm"] : [len * 1000, "mm"];
    this.scaleLabel.textContent = `${+n.toFixed(0)} ${unit}`;
  }

  // --- input ------------------------------------------------------------------------------------------------

  installInput() {
    const c = this.canvas;
    let drag = null;
    c.addEventListener("pointerdown", (e) => {
      if (e.button !== 0) return;
      c.setPointerCapture(e.pointerId);
      drag = { x: e.offsetX, y: e.offsetY, cx: this.view.cx, cy: this.view.cy, moved: false };
    });
    c.addEventListener("pointermove", (e) => {
      const sx = e.offsetX;
      const sy = e.offsetY;
      if (drag) {
        const dx = sx - drag.x;
        const dy = sy - drag.y;
        if (drag.moved || Math.hypot(dx, dy) > 4) {
          drag.moved = true;
          c.classList.add("dragging");
          this.view.cx = drag.cx - dx / this.view.scale;
          this.view.cy = drag.cy + dy / this.view.scale;
          this.viewChanged();
        }
      }
      this.setCursor(sx, sy);
    });
    const end = (e) => {
      if (!drag) return;
      const wasClick = !drag.moved;
      drag = null;
      c.classList.remove("dragging");
      if (wasClick && e.type === "pointerup") this.click(e.offsetX, e.offsetY);
    };
    c.addEventListener("pointerup", end);
    c.addEventListener("pointercancel", end);
    c.addEventListener("pointerleave", () => {
      this.cursor = null;
      if (this.cursorReadout) this.cursorReadout.textContent = "—";
      this.requestFrame();
    });
    c.addEventListener(
      "wheel",
      (e) => {
        e.preventDefault();
        const dy = e.deltaMode === 1 ? e.deltaY * 16 : e.deltaY;
        this.zoomAt(e.offsetX, e.offsetY, Math.exp(-dy * 0.0015));
        this.setCursor(e.offsetX, e.offsetY);
      },
      { passive: false },
    );
  }

  setCursor(sx, sy) {
    const [x, y] = this.toWorld(sx, sy);
    this.cursor = [x, y];
    this.cursorSx = [sx, sy];
    if (this.cursorReadout) {
      const cell = this.cellAt(x, y);
      const what = cell === null ? "outside" : cell === 0 ? "free" : cell === 100 ? "occupied" : "unknown";
      this.cursorReadout.textContent = `x ${x.toFixed(2)} m   y ${y.toFixed(2)} m   ${what}`;
    }
    const hit = this.robotAt(sx, sy);
    if (hit !== this.hoverRobot) {
      this.hoverRobot = hit;
      this.canvas.classList.toggle("over-robot", !!hit);
    }
    if (this.pick) this.requestFrame();
  }

  robotAt(sx, sy) {
    let best = null;
    let bd = 12;
    for (const [id, r] of this.robots) {
      const [x, y] = this.toScreen(r.x, r.y);
      const d = Math.hypot(x - sx, y - sy);
      if (d < bd) {
        bd = d;
        best = id;
      }
    }
    return best;
  }

  click(sx, sy) {
    const [x, y] = this.toWorld(sx, sy);
    if (this.pick) {
      if (this.onPick) this.onPick(x, y);
      return;
    }
    const id = this.robotAt(sx, sy);
    if (id && this.onRobotClick) this.onRobotClick(id);
  }

  // --- drawing ----------------------------------------------------------------------------------------------

  invalidate() {
    this.layersDirty = true;
    this.requestFrame();
  }

  requestFrame() {
    if (this.frameQueued) return;
    this.frameQueued = true;
    requestAnimationFrame(() => {
      this.frameQueued = false;
      this.frame();
    });
  }

  worldTransform(ctx) {
    const v = this.view;
    const k = this.dpr * v.scale;
    const ex = this.dpr * (this.cssW / 2 - v.cx * v.scale);
    const ey = this.dpr * (this.cssH / 2 + v.cy * v.scale);
    ctx.setTransform(k, 0, 0, -k, ex, ey);
  }

  screenTransform(ctx) {
    ctx.setTransform(this.dpr, 0, 0, this.dpr, 0, 0);
  }

  frame() {
    const t0 = performance.now();
    if (this.layersDirty) {
      renderLayers(this);
      this.layersDirty = false;
    }
    const ctx = this.ctx;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.drawImage(this.layers, 0, 0);
    drawRobots(this, ctx);
    drawPick(this, ctx);
    this.stats.frames += 1;
    this.stats.lastFrameMs = performance.now() - t0;
  }

}
