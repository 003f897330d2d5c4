// Colours, the speed palette and the drawing primitives of the map (grids as images, polylines, markers).

export const PALETTE = ["#4338ca", "#0284c7", "#059669", "#ca8a04", "#ea580c"];
const PALETTE_RGB = PALETTE.map((h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16)));
export const SPEED_BUCKETS = 24;

export const COLORS = {
  background: "#1a212b",
  free: [236, 239, 242],
  occupied: [16, 20, 27],
  unknown: [150, 158, 170],
  coverage: [22, 163, 74, 105],
  live: "#f43f5e",
  correction: "#c026d3",
  skipped: "#dc2626",
  region: "#475569",
  streaming: "#6366f1",
  robot: "#0f172a",
  robotRing: "#ffffff",
  heading: "#22d3ee",
  trail: "rgba(30, 41, 59, 0.5)",
  lost: "#94a3b8",
  dock: "#16a34a",
  other: "rgba(71, 85, 105, 0.45)",
};

/** The palette colour at t in [0, 1], as [r, g, b]. */
export function paletteAt(t) {
  const x = Math.min(Math.max(t, 0), 1) * (PALETTE_RGB.length - 1);
  const i = Math.min(Math.floor(x), PALETTE_RGB.length - 2);
  const f = x - i;
  const a = PALETTE_RGB[i];
  const b = PALETTE_RGB[i + 1];
  return [0, 1, 2].map((k) => Math.round(a[k] + (b[k] - a[k]) * f));
}

export const rgb = (c) => `rgb(${c[0]}, ${c[1]}, ${c[2]})`;

/** A CSS linear-gradient of the palette (the legend's bar). */
export function paletteGradient() {
  return `linear-gradient(90deg, ${PALETTE.join(", ")})`;
}

/** Speed range of a plan document's waypoints: [min, max] m/s. */
export function speedRange(doc) {
  let lo = Infinity;
  let hi = -Infinity;
  for (const w of doc.waypoints) {
    if (w.v < lo) lo = w.v;
    if (w.v > hi) hi = w.v;
  }
  if (!Number.isFinite(lo)) return [0, 1];
  return [lo, hi];
}

export function gridCanvas(doc, colorOf) {
  const { width, height, cells } = doc;
  const c = document.createElement("canvas");
  c.width = Math.max(1, width);
  c.height = Math.max(1, height);
  const ctx = c.getContext("2d");
  const img = ctx.createImageData(c.width, c.height);
  const px = img.data;
  // Canvas row i = grid row i (row 0 at the origin): the view's transform flips y.
  for (let i = 0, n = Math.min(cells.length, width * height); i < n; i++) {
    const col = colorOf(cells[i]);
    if (!col) continue;
    const o = i * 4;
    px[o] = col[0];
    px[o + 1] = col[1];
    px[o + 2] = col[2];
    px[o + 3] = col.length > 3 ? col[3] : 255;
  }
  ctx.putImageData(img, 0, 0);
  return c;
}

export function polyPath(points, get) {
  const p = new Path2D();
  let first = true;
  for (const q of points) {
    const [x, y] = get(q);
    if (first) p.moveTo(x, y);
    else p.lineTo(x, y);
    first = false;
  }
  return p;
}

export const xyOf = (q) => [q[0], q[1]];
export const wpOf = (w) => [w.x, w.y];

export function closed(polygon) {
  const p = new Path2D();
  polygon.forEach((q, i) => (i === 0 ? p.moveTo(q[0], q[1]) : p.lineTo(q[0], q[1])));
  p.closePath();
  return p;
}

export function centroid(polygon) {
  let x = 0;
  let y = 0;
  for (const q of polygon) {
    x += q[0];
    y += q[1];
  }
  const n = polygon.length || 1;
  return [x / n, y / n];
}

export function label(ctx, x, y, text, bg, fg, align = "center") {
  const w = ctx.measureText(text).width + 8;
  const left = align === "left" ? x : x - w / 2;
  ctx.fillStyle = bg;
  roundRect(ctx, left, y - 8, w, 16, 4);
  ctx.fill();
  ctx.fillStyle = fg;
  ctx.textAlign = "left";
  ctx.fillText(text, left + 4, y + 0.5);
}

export function roundRect(ctx, x, y, w, h, r) {
  ctx.beginPath();
  ctx.moveTo(x + r, y);
  ctx.arcTo(x + w, y, x + w, y + h, r);
  ctx.arcTo(x + w, y + h, x, y + h, r);
  ctx.arcTo(x, y + h, x, y, r);
  ctx.arcTo(x, y, x + w, y, r);
  ctx.closePath();
}

export function robotMarker(ctx, x, y, yaw, alive, highlight) {
  ctx.save();
  ctx.translate(x, y);
  if (highlight) {
    ctx.beginPath();
    ctx.arc(0, 0, 14, 0, Math.PI * 2);
    ctx.fillStyle = "rgba(34, 211, 238, 0.28)";
    ctx.fill();
  }
  ctx.beginPath();
  ctx.arc(0, 0, 9, 0, Math.PI * 2);
  ctx.fillStyle = alive ? COLORS.robot : COLORS.lost;
  ctx.fill();
  ctx.lineWidth = 2;
  ctx.strokeStyle = COLORS.robotRing;
  if (!alive) ctx.setLineDash([3, 2]);
  ctx.stroke();
  ctx.setLineDash([]);
  // Heading: an arrow from the centre out past the ring (screen y is down, map yaw counter-clockwise).
  ctx.rotate(-yaw);
  ctx.beginPath();
  ctx.moveTo(15, 0);
  ctx.lineTo(3, -6);
  ctx.lineTo(6, 0);
  ctx.lineTo(3, 6);
  ctx.closePath();
  ctx.fillStyle = alive ? COLORS.heading : "#e2e8f0";
  ctx.fill();
  ctx.lineWidth = 1;
  ctx.strokeStyle = COLORS.robot;
  ctx.stroke();
  ctx.restore();
}

export function dockMarker(ctx, x, y) {
  ctx.save();
  ctx.translate(x, y);
  ctx.beginPath();
  ctx.moveTo(0, -10);
  ctx.lineTo(9, -2);
  ctx.lineTo(9, 8);
  ctx.lineTo(-9, 8);
  ctx.lineTo(-9, -2);
  ctx.closePath();
  ctx.fillStyle = COLORS.dock;
  ctx.fill();
  ctx.lineWidth = 2;
  ctx.strokeStyle = "#ffffff";
  ctx.stroke();
  ctx.fillStyle = "#ffffff";
  ctx.fillRect(-2.5, 1, 5, 7);
  ctx.restore();
}

export function finishMarker(ctx, x, y) {
  ctx.save();
  ctx.translate(x, y);
  ctx.fillStyle = "#ffffff";
  ctx.fillRect(-7, -7, 14, 14);
  ctx.fillStyle = "#111827";
  ctx.fillRect(-7, -7, 7, 7);
  ctx.fillRect(0, 0, 7, 7);
  ctx.lineWidth = 1.5;
  ctx.strokeStyle = "#111827";
  ctx.strokeRect(-7, -7, 14, 14);
  ctx.restore();
}

export function correctionMarker(ctx, x, y, color, text) {
  ctx.save();
  ctx.translate(x, y);
  ctx.beginPath();
  ctx.moveTo(0, -10);
  ctx.lineTo(10, 0);
  ctx.lineTo(0, 10);
  ctx.lineTo(-10, 0);
  ctx.closePath();
  ctx.fillStyle = color;
  ctx.fill();
  ctx.lineWidth = 2;
  ctx.strokeStyle = "#ffffff";
  ctx.stroke();
  ctx.fillStyle = "#ffffff";
  ctx.font = "700 9px system-ui, sans-serif";
  ctx.textAlign = "center";
  ctx.textBaseline = "middle";
  ctx.fillText("C", 0, 0.5);
  ctx.restore();
  ctx.font = "600 11px system-ui, sans-serif";
  label(ctx, x + 14, y, text, "rgba(112, 26, 117, 0.9)", "#fdf4ff", "left");
}

export function cross(ctx, x, y) {
  ctx.save();
  ctx.translate(x, y);
  ctx.lineWidth = 3;
  ctx.strokeStyle = "#ffffff";
  ctx.beginPath();
  ctx.moveTo(-6, -6);
  ctx.lineTo(6, 6);
  ctx.moveTo(6, -6);
  ctx.lineTo(-6, 6);
  ctx.stroke();
  ctx.lineWidth = 2;
  ctx.strokeStyle = COLORS.skipped;
  ctx.stroke();
  ctx.restore();
}
