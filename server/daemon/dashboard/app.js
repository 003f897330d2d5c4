// The operator's page: sites, plans, robots, corrections, missions and coverage of one site, live.
//
// State comes from the API once per site (map, plans, robots, live points, coverage, corrections of active
// plans) and then from the site's event stream; the map is redrawn only when something changed. Actions
// (upload a map, new plan by clicking its start, assign, cancel) go through `act`, which shows the API's
// message on failure and asks for the token on 401/403, then retries.

import { ApiError, get, getToken, hideError, onTokenChange, seg, setToken, showError, toast } from "./api.js";
import {
  assignSelected,
  cancelSelected,
  cancelTokenDialog,
  createPlanAt,
  openUpload,
  showTokenState,
  startPick,
  stopPick,
  submitTokenDialog,
  submitUpload,
} from "./actions.js";
import { firstMapDrawn, installDebugHook } from "./debug.js";
import { $, el } from "./dom.js";
import { MapView } from "./map.js";
import {
  renderLegend,
  renderMissions,
  renderPlan,
  renderPlanSoon,
  renderPlans,
  renderPlansNow,
  renderRobots,
  renderRobotsNow,
  renderSite,
} from "./panels.js";
import { loadRobots, onRobots, pushDriven, refreshAllRobots, selectRobot } from "./robots.js";
import { SiteStream, planStream, throttle } from "./sse.js";
import { ACTIVE_DOCS_MAX, state } from "./store.js";

// --- small helpers ------------------------------------------------------------------------------------------

/** Loads something for the page (not an operator action): errors shown, not thrown. */
export async function load(what, f) {
  try {
    return await f();
  } catch (e) {
    if (e && e.name === "AbortError") return undefined;
    showError(e, what);
    return undefined;
  }
}

// --- sites --------------------------------------------------------------------------------------------------

export async function loadSites(prefer) {
  const list = await load("Load sites", () => get("/v1/sites"));
  if (!list) return;
  state.sites = list.items || [];
  const sel = $("site-select");
  sel.replaceChildren(...state.sites.map((s) => el("option", { value: s.site, text: s.site })));
  $("empty").hidden = state.sites.length > 0;
  const wanted = prefer || hashParam("site") || state.site;
  const pick = state.sites.find((s) => s.site === wanted) || state.sites[0];
  if (pick && pick.site !== state.site) await selectSite(pick.site);
  else if (pick) sel.value = pick.site;
}

function hashParam(k) {
  return new URLSearchParams(location.hash.slice(1)).get(k);
}

function setHash() {
  const p = new URLSearchParams();
  if (state.site) p.set("site", state.site);
  if (state.selected) p.set("plan", state.selected);
  history.replaceState(null, "", `#${p}`);
}

export async function selectSite(site) {
  const gen = ++state.gen;
  const wantedPlan = hashParam("site") === site ? hashParam("plan") : null;
  if (state.stream) state.stream.close();
  if (state.planStream) state.planStream.close();
  state.stream = null;
  state.planStream = null;
  state.site = site;
  state.summary = state.sites.find((s) => s.site === site) || null;
  state.plans.clear();
  state.order = [];
  state.docs.clear();
  state.corrections.clear();
  state.streaming.clear();
  state.robots.clear();
  state.missions.clear();
  state.live = { count: 0, points: [], truncated: false };
  state.selected = null;
  state.selectedRobot = null;
  state.view.clearSite();
  $("site-select").value = site;
  renderSite();
  renderPlans();
  renderPlan();
  renderRobotsNow();
  renderMissions();
  setHash();

  const grid = await load(`Load the map of ${site}`, () => get(`/v1/sites/${seg(site)}/map`));
  if (gen !== state.gen || !grid) return;
  state.grid = grid;
  state.view.setGrid(grid);
  firstMapDrawn();
  state.stream = new SiteStream(site, streamHandlers(gen));
  await Promise.all([loadPlans(gen), loadLive(gen), loadCoverage(gen), loadRobots(gen)]);
  if (gen !== state.gen) return;
  if (wantedPlan && state.plans.has(wantedPlan)) selectPlan(wantedPlan);
  await loadMissions(gen);
}

// --- plans --------------------------------------------------------------------------------------------------

async function loadPlans(gen) {
  const page = await load("Load plans", () => get(`/v1/plans?site=${seg(state.site)}&limit=200`));
  if (!page || gen !== state.gen) return;
  // The stream may have told newer news than this page already: the newer of the two wins per plan, and
  // plans only the stream knows (newer than the listing) stay on top.
  for (const p of page.items) {
    const had = state.plans.get(p.plan_id);
    if (!had || !(had.updated_ms > p.updated_ms)) state.plans.set(p.plan_id, p);
  }
  const listed = new Set(page.items.map((p) => p.plan_id));
  state.order = [...state.order.filter((id) => !listed.has(id)), ...page.items.map((p) => p.plan_id)];
  renderPlans();
  // Active plans: their paths (faint) and corrections.
  const active = page.items.filter((p) => p.status === "active").slice(0, ACTIVE_DOCS_MAX);
  await Promise.all(active.map((p) => loadDoc(p.plan_id, gen, true)));
  refreshOverlays();
}

export function upsertPlan(p) {
  if (p.site && state.site && p.site !== state.site) return false;
  // A status is a whole snapshot (absent fields are absent): it replaces what was known.
  const had = state.plans.get(p.plan_id);
  state.plans.set(p.plan_id, p);
  if (!had) state.order.unshift(p.plan_id);
  return !had;
}

async function loadDoc(id, gen, withCorrections) {
  const [doc, corr] = await Promise.all([
    get(`/v1/plans/${seg(id)}/path`).catch((e) => {
      if (!(e instanceof ApiError && (e.status === 404 || e.status === 409))) showError(e, `Load the path of ${id}`);
      return null;
    }),
    withCorrections
      ? get(`/v1/plans/${seg(id)}/corrections`).catch((e) => {
          if (!(e instanceof ApiError && e.status === 404)) showError(e, `Load the corrections of ${id}`);
          return null;
        })
      : Promise.resolve(null),
  ]);
  if (gen !== state.gen) return;
  if (doc) {
    const have = state.docs.get(id);
    if (!have || have.version <= doc.version) state.docs.set(id, doc);
  }
  if (corr) {
    const known = state.corrections.get(id) || [];
    const byVersion = new Map([...corr, ...known].map((c) => [c.version, c]));
    state.corrections.set(id, [...byVersion.values()].sort((a, b) => a.version - b.version));
  }
}

const refetchDoc = new Map(); // id -> throttled refetch
function docStale(id) {
  let f = refetchDoc.get(id);
  if (!f) {
    f = throttle(async () => {
      const gen = state.gen;
      await loadDoc(id, gen, false);
      if (gen === state.gen) refreshOverlays();
    }, 500);
    refetchDoc.set(id, f);
  }
  f();
}

function planShown(id) {
  const p = state.plans.get(id);
  return id === state.selected || (p && p.status === "active");
}

/** Pushes plans, corrections and streamed regions to the map (after any change of them). */
function refreshOverlays() {
  const sel = state.selected ? state.docs.get(state.selected) : null;
  state.view.setPlan(sel || null);
  pushDriven();
  const others = [];
  for (const id of state.order) {
    if (id === state.selected) continue;
    const p = state.plans.get(id);
    const doc = state.docs.get(id);
    if (p && p.status === "active" && doc) others.push({ planId: id, doc });
  }
  state.view.setOthers(others);
  const corr = [];
  const missed = [];
  for (const id of state.order) {
    if (!planShown(id)) continue;
    for (const c of state.corrections.get(id) || []) corr.push(c);
    const p = state.plans.get(id);
    if (p && p.missed) missed.push(...p.missed);
  }
  state.view.setCorrections(corr, missed);
  const streaming = [];
  for (const [id, regions] of state.streaming) {
    const p = state.plans.get(id);
    if (p && (p.status === "planning" || p.status === "queued")) streaming.push(...regions.values());
  }
  state.view.setStreaming(streaming);
  renderLegend(sel);
}

export async function selectPlan(id) {
  if (state.planStream) {
    state.planStream.close();
    state.planStream = null;
  }
  state.selected = id;
  setHash();
  renderPlansNow();
  renderPlan();
  refreshOverlays();
  const p = state.plans.get(id);
  if (!p) return;
  const gen = state.gen;
  if (["ready", "active", "done"].includes(p.status)) {
    await loadDoc(id, gen, true);
    if (gen !== state.gen || state.selected !== id) return;
    refreshOverlays();
    renderPlan();
  } else if (p.status === "planning" || p.status === "queued") {
    // The plan's own stream replays the regions streamed so far; the site stream brings the rest.
    state.planStream = planStream(id, {
      "region-ready": (e) => onRegionReady(e),
      status: (s) => onStatus(s),
    });
  }
}

export function onStatus(s) {
  if (s.site && s.site !== state.site) return;
  const before = state.plans.get(s.plan_id);
  upsertPlan(s);
  const p = state.plans.get(s.plan_id);
  const statusChanged = !before || before.status !== p.status;
  const doc = state.docs.get(s.plan_id);
  if (planShown(s.plan_id) && ["ready", "active", "done"].includes(p.status) && (!doc || doc.version < p.version)) {
    // Ready now, assigned now, or a new version not made by a correction we saw (a replan's update).
    if (!doc || statusChanged) {
      loadDoc(s.plan_id, state.gen, true).then(() => {
        refreshOverlays();
        if (s.plan_id === state.selected) renderPlan();
      });
    }
    else docStale(s.plan_id);
  }
  if (statusChanged && p.status !== "planning" && p.status !== "queued") {
    state.streaming.delete(s.plan_id);
    if (state.planStream && s.plan_id === state.selected) {
      state.planStream.close();
      state.planStream = null;
    }
  }
  const missedBefore = before && before.missed ? before.missed.length : 0;
  if (statusChanged || (p.missed ? p.missed.length : 0) !== missedBefore) refreshOverlays();
  renderPlans();
  if (s.plan_id === state.selected) renderPlanSoon();
  renderRobots();
}

function onProgress(e) {
  const p = state.plans.get(e.plan_id);
  if (!p) return;
  p.progress = e.progress;
  renderPlans();
  if (e.plan_id === state.selected) renderPlanSoon();
}

function onRegionReady(e) {
  let m = state.streaming.get(e.plan_id);
  if (!m) {
    m = new Map();
    state.streaming.set(e.plan_id, m);
  }
  m.set(e.region.region, e.region);
  const p = state.plans.get(e.plan_id);
  if (p) p.regions_ready = Math.max(p.regions_ready || 0, m.size);
  refreshStreamingSoon();
  if (e.plan_id === state.selected) renderPlanSoon();
}
const refreshStreamingSoon = throttle(() => refreshOverlays(), 100);

function onCorrection(c) {
  const list = state.corrections.get(c.plan_id) || [];
  if (!list.some((k) => k.version === c.version)) {
    list.push(c);
    list.sort((a, b) => a.version - b.version);
    state.corrections.set(c.plan_id, list);
  }
  const p = state.plans.get(c.plan_id);
  if (p) {
    p.version = Math.max(p.version || 0, c.version);
    p.corrections = Math.max(p.corrections || 0, c.version - 1);
  }
  // Patch the drawn document in place when it is the correction's base; otherwise read it again.
  const doc = state.docs.get(c.plan_id);
  if (doc) {
    if (doc.version === c.base_version && c.from <= c.to && c.to <= doc.waypoints.length) {
      const after = doc.waypoints.slice(c.to).map((w) => ({ ...w, t: w.t + (c.dt_after_s || 0) }));
      const waypoints = [...doc.waypoints.slice(0, c.from), ...c.waypoints, ...after];
      state.docs.set(c.plan_id, { ...doc, version: c.version, waypoints });
    } else if (doc.version < c.version) {
      docStale(c.plan_id);
    }
  }
  refreshOverlaysSoon();
  renderPlans();
  if (c.plan_id === state.selected) renderPlanSoon();
  const kind = c.reason === "skipped" ? "warn" : "info";
  toast(`${c.robot}: ${c.reason} correction on ${c.plan_id} → v${c.version}`, kind);
}
const refreshOverlaysSoon = throttle(() => refreshOverlays(), 100);

/** The site's figures (clouds/s, dropped, points) move on: read them again now and then. */
async function refreshSummary() {
  if (!state.site || document.hidden) return;
  const gen = state.gen;
  const s = await get(`/v1/sites/${seg(state.site)}`).catch(() => null);
  if (!s || gen !== state.gen) return;
  state.summary = s;
  renderSite();
}

// --- missions, coverage, live -------------------------------------------------------------------------------

async function loadMissions(gen) {
  const ids = new Set();
  for (const id of state.order) {
    const m = state.plans.get(id).mission;
    if (m) ids.add(m);
  }
  const list = [...ids].slice(0, 20);
  const views = await Promise.all(list.map((id) => get(`/v1/missions/${seg(id)}`).catch(() => null)));
  if (gen !== state.gen) return;
  for (const v of views) if (v && !state.missions.has(v.mission_id)) state.missions.set(v.mission_id, v);
  renderMissions();
}

function onMission(v) {
  if (v.site && v.site !== state.site) return;
  state.missions.set(v.mission_id, v);
  renderMissions();
}

async function loadCoverage(gen) {
  const grid = await get(`/v1/sites/${seg(state.site)}/coverage`).catch((e) => {
    if (!(e instanceof ApiError && e.status === 404)) showError(e, "Load the measured coverage");
    return null;
  });
  if (gen !== state.gen) return;
  state.view.setCoverage(grid);
}

async function loadLive(gen) {
  const live = await get(`/v1/sites/${seg(state.site)}/live?max_points=50000`).catch((e) => {
    showError(e, "Load the live obstacle points");
    return null;
  });
  if (!live || gen !== state.gen) return;
  state.live = live;
  state.view.setLive(live.points);
  if (state.summary) state.summary.points_in_tree = live.count;
  renderSite();
}

const liveSoon = throttle(() => loadLive(state.gen), 1000);
const coverageSoon = throttle(() => loadCoverage(state.gen), 1000);

const STREAM_STATES = {
  live: "live",
  connecting: "connecting",
  reconnecting: "reconnecting…",
  closed: "stream closed",
};

function streamHandlers(gen) {
  const only = (f) => (d) => {
    if (gen === state.gen) f(d);
  };
  return {
    site: only((s) => {
      state.summary = s;
      renderSite();
    }),
    robots: only(onRobots),
    status: only(onStatus),
    progress: only(onProgress),
    "region-ready": only(onRegionReady),
    correction: only(onCorrection),
    mission: only(onMission),
    coverage: only(() => coverageSoon()),
    live: only(() => liveSoon()),
    onState: (s) => {
      if (gen !== state.gen) return;
      const c = $("conn");
      c.textContent = STREAM_STATES[s] || s;
      c.className = `pill ${s === "live" ? "pill-ok" : s === "closed" ? "pill-bad" : "pill-wait"}`;
    },
    onResync: only(() => {
      loadPlans(gen);
      loadLive(gen);
      loadCoverage(gen);
      loadRobots(gen);
    }),
  };
}

// --- wiring -------------------------------------------------------------------------------------------------

function wire() {
  state.view = new MapView($("map"), {
    scaleBar: $("scale-bar"),
    scaleLabel: $("scale-label"),
    cursorReadout: $("cursor"),
    onPick: (x, y) => createPlanAt(x, y),
    onRobotClick: (id) => selectRobot(id),
  });
  installDebugHook();

  $("site-select").addEventListener("change", (e) => selectSite(e.target.value));
  $("upload-open").addEventListener("click", openUpload);
  $("empty-upload").addEventListener("click", openUpload);
  $("up-cancel").addEventListener("click", () => $("upload-dialog").close());
  $("upload-form").addEventListener("submit", submitUpload);
  $("up-json").addEventListener("change", () => {
    const j = !!$("up-json").files.length;
    $("up-yaml").disabled = j;
    $("up-image").disabled = j;
  });

  $("new-plan-form").addEventListener("submit", (e) => {
    e.preventDefault();
    if (state.pick) stopPick();
    else startPick();
  });
  $("assign").addEventListener("click", assignSelected);
  $("assign-robot").addEventListener("pointerdown", refreshAllRobots);
  $("assign-robot").addEventListener("focus", refreshAllRobots);
  $("cancel-plan").addEventListener("click", cancelSelected);

  $("token-form").addEventListener("submit", (e) => {
    e.preventDefault();
    const v = $("token-input").value;
    setToken(v);
    toast(v.trim() ? "Token set for this tab" : "Token cleared");
  });
  $("token-dialog-form").addEventListener("submit", (e) => {
    e.preventDefault();
    submitTokenDialog();
  });
  $("token-dialog-cancel").addEventListener("click", cancelTokenDialog);
  onTokenChange(showTokenState);
  showTokenState(getToken());

  $("error-banner").querySelector(".banner-close").addEventListener("click", hideError);
  $("fit").addEventListener("click", () => state.view.fit());
  $("zoom-in").addEventListener("click", () => state.view.zoomAt(state.view.cssW / 2, state.view.cssH / 2, 1.4));
  $("zoom-out").addEventListener("click", () => state.view.zoomAt(state.view.cssW / 2, state.view.cssH / 2, 1 / 1.4));
  for (const box of document.querySelectorAll("[data-layer]")) {
    box.addEventListener("change", () => state.view.setLayer(box.dataset.layer, box.checked));
  }
  window.addEventListener("keydown", (e) => {
    const t = e.target;
    if (t instanceof HTMLInputElement || t instanceof HTMLSelectElement || t instanceof HTMLTextAreaElement) return;
    if (e.key === "Escape" && state.pick) stopPick();
    else if (e.key === "f" || e.key === "F") state.view.fit();
    else if (e.key === "+" || e.key === "=") state.view.zoomAt(state.view.cssW / 2, state.view.cssH / 2, 1.4);
    else if (e.key === "-") state.view.zoomAt(state.view.cssW / 2, state.view.cssH / 2, 1 / 1.4);
  });
  // Ages in the robots table move on by themselves; the robots offered for assignment are re-read while a ready
  // plan is selected, and every 10 s anyway.
  let tick = 0;
  setInterval(() => {
    tick += 1;
    if (state.robots.size) renderRobots();
    const p = state.selected ? state.plans.get(state.selected) : null;
    if ((p && p.status === "ready" && tick % 2 === 0) || tick % 10 === 0) refreshAllRobots();
    if (tick % 5 === 0) refreshSummary();
  }, 1000);
}

wire();
loadSites();
