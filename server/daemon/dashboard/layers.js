// What MapView paints: the cached layers (grid, coverage, paths, regions, corrections, live points, fixed-size
// markers), repainted only when data or the view changed, and per frame the robots and the start being picked.

import {
  COLORS,
  correctionMarker,
  cross,
  dockMarker,
  finishMarker,
  label,
  robotMarker,
} from "./marks.js";

export function renderLayers(v) {
  const ctx = v.lctx;
  const s = v.view.scale;
  v.stats.layerRenders += 1;
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.fillStyle = COLORS.background;
  ctx.fillRect(0, 0, v.layers.width, v.layers.height);
  const g = v.grid;
  if (!g) return;
  const res = g.resolution;
  const [ox, oy] = g.origin;

  // The grid, then the measured coverage over it.
  v.worldTransform(ctx);
  ctx.imageSmoothingEnabled = s * res * v.dpr < 1.5;
  ctx.drawImage(v.gridImg, ox, oy, g.width * res, g.height * res);
  if (v.show.coverage && v.coverageImg && v.coverage) {
    const c = v.coverage;
    ctx.drawImage(v.coverageImg, c.origin[0], c.origin[1], c.width * c.resolution, c.height * c.resolution);
  }
  ctx.imageSmoothingEnabled = true;
  const px = 1 / s; // one CSS pixel in metres
  ctx.lineJoin = "round";
  ctx.lineCap = "round";

  // Other active plans of the site, faint.
  if (v.show.others && v.others.length) {
    ctx.strokeStyle = COLORS.other;
    ctx.lineWidth = 1.5 * px;
    ctx.setLineDash([]);
    for (const o of v.others) ctx.stroke(o.path);
  }

  const plan = v.plan;
  // Regions of the selected plan, outlined.
  if (plan && v.show.regions && plan.regions.length) {
    ctx.strokeStyle = COLORS.region;
    ctx.lineWidth = 1.25 * px;
    ctx.setLineDash([5 * px, 4 * px]);
    for (const r of plan.regions) ctx.stroke(r.path);
    ctx.setLineDash([]);
  }
  // Regions streamed by a plan being computed: outline, light fill and their cover paths.
  if (v.streaming.length) {
    ctx.setLineDash([]);
    for (const r of v.streaming) {
      ctx.fillStyle = "rgba(99, 102, 241, 0.10)";
      ctx.fill(r.outline);
      ctx.strokeStyle = COLORS.streaming;
      ctx.lineWidth = 1.5 * px;
      ctx.stroke(r.outline);
      ctx.lineWidth = 1 * px;
      ctx.strokeStyle = "rgba(79, 70, 229, 0.75)";
      ctx.stroke(r.path);
    }
  }

  // Missed stretches (corrections had to leave them out): a wide translucent red band.
  if (v.show.corrections && v.missed.length) {
    ctx.strokeStyle = "rgba(220, 38, 38, 0.28)";
    ctx.lineWidth = 10 * px;
    for (const m of v.missed) ctx.stroke(m);
  }

  // The selected plan, coloured by speed: cover solid, transit dashed and thinner.
  if (plan && v.show.path) {
    const lw = Math.min(Math.max(s * 0.05, 1.6), 4);
    for (const p of plan.paths) {
      ctx.strokeStyle = p.color;
      if (p.kind === "transit") {
        ctx.lineWidth = Math.max(lw * 0.7, 1.4) * px;
        ctx.setLineDash([7 * px, 5 * px]);
      } else {
        ctx.lineWidth = lw * px;
        ctx.setLineDash([]);
      }
      ctx.stroke(p.path);
    }
    ctx.setLineDash([]);
    // What is driven already, washed out.
    if (v.driven) {
      ctx.strokeStyle = "rgba(236, 239, 242, 0.62)";
      ctx.lineWidth = (lw + 2) * px;
      ctx.stroke(v.driven);
    }
  }

  // Corrections: the replacing waypoints highlighted; skipped stretches red dashed.
  let markers = 0;
  let skipped = 0;
  if (v.show.corrections) {
    for (const c of v.corrections) {
      if (c.patch) {
        ctx.strokeStyle = "rgba(255, 255, 255, 0.9)";
        ctx.lineWidth = 7 * px;
        ctx.stroke(c.patch);
        ctx.strokeStyle = COLORS.correction;
        ctx.lineWidth = 3.5 * px;
        ctx.stroke(c.patch);
      }
      if (c.skipped) {
        ctx.strokeStyle = COLORS.skipped;
        ctx.lineWidth = 3 * px;
        ctx.setLineDash([6 * px, 4 * px]);
        ctx.stroke(c.skipped);
        ctx.setLineDash([]);
        skipped += 1;
      }
    }
  }

  // Live obstacle points: one square each (a cell, at least 3 px).
  v.screenTransform(ctx);
  if (v.show.live && v.live.length) {
    const side = Math.max(res * s, 3);
    const h = side / 2;
    const p = new Path2D();
    const x0 = v.cssW / 2 - v.view.cx * s;
    const y0 = v.cssH / 2 + v.view.cy * s;
    for (const q of v.live) {
      const x = x0 + q[0] * s;
      const y = y0 - q[1] * s;
      if (x < -side || y < -side || x > v.cssW + side || y > v.cssH + side) continue;
      p.rect(x - h, y - h, side, side);
    }
    ctx.fillStyle = COLORS.live;
    ctx.fill(p);
  }

  // Markers in screen space (constant size): streamed region ids, plan start/end, correction markers.
  ctx.font = "600 11px system-ui, sans-serif";
  ctx.textAlign = "center";
  ctx.textBaseline = "middle";
  for (const r of v.streaming) {
    const [x, y] = v.toScreen(r.c[0], r.c[1]);
    label(ctx, x, y, `R${r.id}`, "#312e81", "#e0e7ff");
  }
  if (plan && v.show.regions && plan.regions.length > 1) {
    for (const r of plan.regions) {
      const [x, y] = v.toScreen(r.c[0], r.c[1]);
      label(ctx, x, y, `R${r.id}`, "rgba(30, 41, 59, 0.75)", "#f8fafc");
    }
  }
  if (plan && plan.start && v.show.path) {
    const [sx, sy] = v.toScreen(plan.start[0], plan.start[1]);
    const [ex, ey] = v.toScreen(plan.end[0], plan.end[1]);
    if (Math.hypot(ex - sx, ey - sy) > 14) finishMarker(ctx, ex, ey);
    dockMarker(ctx, sx, sy);
  }
  if (v.show.corrections) {
    for (const c of v.corrections) {
      for (const e of c.skippedEnds) {
        const [x, y] = v.toScreen(e[0], e[1]);
        cross(ctx, x, y);
      }
      if (c.marker) {
        const [x, y] = v.toScreen(c.marker[0], c.marker[1]);
        const color = c.doc.reason === "skipped" ? COLORS.skipped : COLORS.correction;
        correctionMarker(ctx, x, y, color, `v${c.doc.version}`);
        markers += 1;
      }
    }
  }
  v.stats.correctionMarkers = markers;
  v.stats.skipped = skipped;
}

export function drawRobots(v, ctx) {
  let n = 0;
  if (!v.robots.size || !v.grid) {
    v.stats.robotsDrawn = 0;
    return;
  }
  const s = v.view.scale;
  // Trails, in world space.
  if (v.show.trails) {
    v.worldTransform(ctx);
    ctx.lineWidth = 2 / s;
    ctx.lineJoin = "round";
    ctx.lineCap = "round";
    ctx.setLineDash([]);
    for (const r of v.robots.values()) {
      if (r.trail.length < 2) continue;
      ctx.strokeStyle = r.alive ? COLORS.trail : "rgba(148, 163, 184, 0.6)";
      ctx.beginPath();
      ctx.moveTo(r.trail[0][0], r.trail[0][1]);
      for (let i = 1; i < r.trail.length; i++) ctx.lineTo(r.trail[i][0], r.trail[i][1]);
      ctx.stroke();
    }
  }
  v.screenTransform(ctx);
  const shown = [];
  for (const [id, r] of v.robots) {
    const [x, y] = v.toScreen(r.x, r.y);
    if (x < -40 || y < -40 || x > v.cssW + 40 || y > v.cssH + 40) continue;
    const focus = r.selected || id === v.hoverRobot;
    robotMarker(ctx, x, y, r.yaw, r.alive, focus);
    shown.push({ id, r, x, y, focus });
    n += 1;
  }
  // Labels over every marker; where they would overlap, the selected and hovered robots' win, then by id.
  ctx.font = "600 11px system-ui, sans-serif";
  ctx.textBaseline = "middle";
  const many = shown.length > 12;
  const byId = (a, b) => a.id.localeCompare(b.id, undefined, { numeric: true });
  shown.sort((a, b) => (a.focus === b.focus ? byId(a, b) : a.focus ? -1 : 1));
  const boxes = [];
  for (const { id, r, x, y, focus } of shown) {
    const text = many && !focus ? id : r.label || id;
    const w = ctx.measureText(text).width + 8;
    const box = [x + 13, y - 20, x + 13 + w, y - 4];
    if (!focus && boxes.some((b) => box[0] < b[2] && b[0] < box[2] && box[1] < b[3] && b[1] < box[3])) continue;
    boxes.push(box);
    const bg = r.alive ? "rgba(15, 23, 42, 0.85)" : "rgba(100, 116, 139, 0.85)";
    label(ctx, x + 13, y - 12, text, bg, "#f8fafc", "left");
  }
  v.stats.robotsDrawn = n;
}

export function drawPick(v, ctx) {
  if (!v.pick || !v.cursor || !v.grid) return;
  const [x, y] = v.cursor;
  const cell = v.cellAt(x, y);
  const ok = cell === 0;
  const [sx, sy] = v.toScreen(x, y);
  const r = Math.max(v.pick.radius * v.view.scale, 4);
  v.screenTransform(ctx);
  ctx.beginPath();
  ctx.arc(sx, sy, r, 0, Math.PI * 2);
  ctx.fillStyle = ok ? "rgba(22, 163, 74, 0.25)" : "rgba(220, 38, 38, 0.25)";
  ctx.fill();
  ctx.lineWidth = 2;
  ctx.strokeStyle = ok ? COLORS.dock : COLORS.skipped;
  ctx.stroke();
  if (v.pick.toolWidth) {
    const h = (v.pick.toolWidth * v.view.scale) / 2;
    ctx.beginPath();
    ctx.moveTo(sx - h, sy);
    ctx.lineTo(sx + h, sy);
    ctx.stroke();
  }
}
