// `window.__shift`: a read-only snapshot of what the page draws, for tests and for operators' bug reports.

import { errorsShown, getToken } from "./api.js";
import { followedVersion } from "./panels.js";
import { state } from "./store.js";

let firstMapMs = null;

export function firstMapDrawn() {
  if (firstMapMs === null) requestAnimationFrame(() => (firstMapMs = performance.now()));
}

function paintMs() {
  const e = performance.getEntriesByType("paint");
  const fcp = e.find((x) => x.name === "first-contentful-paint");
  const fp = e.find((x) => x.name === "first-paint");
  return (fp || fcp) ? (fp || fcp).startTime : null;
}

function debugSnapshot() {
  const robots = {};
  for (const [id, r] of state.robots) {
    const v = r.view;
    robots[id] = Object.freeze({
      x: v.pose ? v.pose.x : null,
      y: v.pose ? v.pose.y : null,
      yaw: v.pose ? v.pose.yaw : null,
      alive: v.alive,
      plan: v.plan_id || null,
      version: v.plan_id ? followedVersion(v) : null,
      driven: v.driven_fraction ?? null,
      trail: r.draw.trail.length,
      drawn: !!r.draw.hasPose,
    });
  }
  const m = state.view.plan;
  let corrections = 0;
  for (const c of state.view.corrections) if (c.patch || c.skipped) corrections += 1;
  const fcp = performance.getEntriesByType("paint").find((x) => x.name === "first-contentful-paint");
  return Object.freeze({
    site: state.site,
    selectedPlan: state.selected,
    planStatus: state.selected && state.plans.has(state.selected) ? state.plans.get(state.selected).status : null,
    pathPlan: m ? m.doc.plan_id : null,
    pathVersion: m ? m.doc.version : null,
    pathPoints: m && state.view.show.path ? m.doc.waypoints.length : 0,
    pathSegments: m ? m.paths.length : 0,
    speedRange: m ? [m.vmin, m.vmax] : null,
    regions: m ? m.regions.length : 0,
    streamingRegions: state.view.streaming.length,
    otherPaths: state.view.others.length,
    robots: Object.freeze(robots),
    robotsDrawn: state.view.stats.robotsDrawn,
    corrections,
    correctionMarkers: state.view.stats.correctionMarkers,
    skipped: state.view.stats.skipped,
    missed: state.view.missed.length,
    liveCount: state.view.live.length,
    coverageCells: state.view.coverageCells,
    plans: state.order.length,
    missions: state.missions.size,
    frames: state.view.stats.frames,
    layerRenders: state.view.stats.layerRenders,
    lastFrameMs: state.view.stats.lastFrameMs,
    sse: state.stream ? state.stream.state : null,
    sseEvents: state.stream ? Object.freeze({ ...state.stream.counts }) : null,
    firstPaintMs: paintMs(),
    firstContentfulPaintMs: fcp ? fcp.startTime : null,
    mapDrawnMs: firstMapMs,
    errors: errorsShown().length,
    lastError: errorsShown().pop()?.message ?? null,
    tokenSet: !!getToken(),
    view: Object.freeze({ ...state.view.view, width: state.view.cssW, height: state.view.cssH }),
  });
}

export function installDebugHook() {
  const hook = Object.freeze({
    /** CSS pixel of a map point, relative to the map canvas's top-left corner. */
    toScreen: (x, y) => state.view.toScreen(x, y),
    toWorld: (sx, sy) => state.view.toWorld(sx, sy),
  });
  Object.defineProperty(window, "__shift", {
    configurable: false,
    enumerable: false,
    get: () => Object.freeze({ ...debugSnapshot(), ...hook }),
  });
}
