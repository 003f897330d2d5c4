// The side panel: the site's facts, the plans list, the selected plan (metrics, corrections, actions), the robots
// table and the missions. Rendering is throttled and rows are updated in place: 30 robots at 10 Hz stay cheap.

import { $, bar, chip, el, fmt, plural, setText } from "./dom.js";
import { paletteGradient } from "./map.js";
import { throttle } from "./sse.js";
import { state } from "./store.js";
import { selectPlan } from "./app.js";
import { selectRobot } from "./robots.js";

export function renderSite() {
  const s = state.summary;
  $("site-name").textContent = s ? s.site : "No site";
  $("site-updated").textContent = s ? `map ${fmt.time(s.updated_ms)}` : "";
  const facts = $("site-facts");
  if (!s) {
    facts.replaceChildren();
    return;
  }
  const area = s.free_cells * s.resolution * s.resolution;
  const rows = [
    ["Size", `${fmt.num(s.width * s.resolution, 1)} × ${fmt.num(s.height * s.resolution, 1)} m`],
    ["Free", `${fmt.num(area, 0)} m²`],
    ["Grid", `${s.width} × ${s.height}`],
    ["Cell", `${s.resolution} m`],
    ["Live pts", `${s.points_in_tree}${state.live.truncated ? ` (${state.live.points.length} drawn)` : ""}`],
    ["Clouds/s", fmt.num(s.updates_per_s || 0, 1)],
    ["Dropped", `${s.dropped_clouds || 0}`],
  ];
  facts.replaceChildren(...rows.flatMap(([k, v]) => [el("dt", { text: k }), el("dd", { text: v })]));
}

export function renderLegend(doc) {
  const lg = $("legend");
  const m = state.view.plan;
  if (!doc || !m || !m.paths.length) {
    lg.hidden = true;
    return;
  }
  lg.hidden = false;
  $("legend-bar").style.background = paletteGradient();
  $("legend-min").textContent = `${m.vmin.toFixed(2)} m/s`;
  $("legend-max").textContent = `${m.vmax.toFixed(2)} m/s`;
}

export const renderPlans = throttle(renderPlansNow, 200);

export function renderPlansNow() {
  const list = $("plans-list");
  $("plans-count").textContent = state.order.length ? `${state.order.length}` : "";
  if (!state.order.length) {
    const hint = "No plan yet: set the robot above, press New plan, click the start on the map.";
    list.replaceChildren(el("p", { class: "empty-note", text: state.site ? hint : "" }));
    return;
  }
  const rows = state.order.slice(0, 200).map((id) => {
    const p = state.plans.get(id);
    const computing = p.status === "queued" || p.status === "planning";
    const frac = computing ? p.progress : p.driven_fraction;
    const row = el(
      "div",
      {
        class: `plan-row${id === state.selected ? " selected" : ""}`,
        role: "option",
        tabindex: "0",
        "aria-selected": id === state.selected ? "true" : "false",
        dataset: { testid: "plan-row", plan: id, status: p.status },
        onclick: () => selectPlan(id),
        onkeydown: (e) => {
          if (e.key === "Enter" || e.key === " ") {
            e.preventDefault();
            selectPlan(id);
          }
        },
      },
      el("span", { class: "plan-id", text: id }),
      chip(p.status),
      el("span", { class: "plan-robot muted", text: p.robot ? `▸ ${p.robot}` : p.mission ? `${p.mission}` : "" }),
      el("span", { class: "plan-ver muted", text: p.version ? `v${p.version}` : "" }),
      bar(frac, computing ? "computing" : "driven"),
    );
    row.title = computing
      ? `computing ${fmt.pct(p.progress)}`
      : p.driven_fraction !== undefined
        ? `driven ${fmt.pct(p.driven_fraction)}`
        : p.status;
    return row;
  });
  list.replaceChildren(...rows);
}

/** Dwell CV with the planned speeds / with one constant speed (lower is more even). */
function dwell(m) {
  return `${fmt.num(m.dwell_cv, 2)} / ${fmt.num(m.dwell_cv_const_speed, 2)}`;
}

export function renderPlan() {
  const card = $("plan-card");
  const id = state.selected;
  const p = id ? state.plans.get(id) : null;
  if (!p) {
    card.hidden = true;
    return;
  }
  card.hidden = false;
  $("pd-title").textContent = id;
  const st = $("pd-status");
  st.textContent = p.status;
  st.className = `chip s-${p.status}`;
  const computing = p.status === "queued" || p.status === "planning";
  const prog = $("pd-progress");
  const frac = computing ? p.progress : p.driven_fraction || 0;
  prog.firstChild.style.width = `${(Math.min(Math.max(frac, 0), 1) * 100).toFixed(1)}%`;
  prog.className = `bar big ${computing ? "computing" : "driven"}`;
  prog.querySelector("b").textContent = computing
    ? `computing ${fmt.pct(p.progress)} · ${p.regions_ready || 0} regions`
    : p.driven_fraction !== undefined
      ? `driven ${fmt.pct(p.driven_fraction)}`
      : p.status === "ready"
        ? "ready to assign"
        : p.status;
  const doc = state.docs.get(id);
  const corr = state.corrections.get(id) || [];
  const facts = [
    ["Robot", p.robot || "—"],
    ["Version", `v${p.version}${p.corrections ? ` · ${plural(p.corrections, "correction")}` : ""}`],
    ["Watch", p.watch || "—"],
    ["Mission", p.mission || "—"],
    ["Waypoints", doc ? `${doc.waypoints.length}` : "—"],
    ["Created", fmt.time(p.created_ms)],
  ];
  $("pd-facts").replaceChildren(...facts.flatMap(([k, v]) => [el("dt", { text: k }), el("dd", { text: v })]));

  const m = p.metrics || (doc && doc.metrics);
  const table = $("pd-metrics");
  if (m) {
    const rows = [
      ["Coverage", `${fmt.num(m.coverage_pct, 1)} %`],
      ["Overlap", `${fmt.num(m.overlap_pct, 1)} %`],
      ["Length", `${fmt.num(m.length_m, 1)} m`],
      ["Duration", fmt.dur(m.duration_s)],
      ["Turns", `${m.turns}`],
      ["Collisions", `${m.collisions}`],
      ["Coverable", m.coverable_area_m2 !== undefined ? `${fmt.num(m.coverable_area_m2, 1)} m²` : "—"],
      ["Reachable", m.reachable_area_m2 !== undefined ? `${fmt.num(m.reachable_area_m2, 1)} m²` : "—"],
      ["Free", m.free_area_m2 !== undefined ? `${fmt.num(m.free_area_m2, 1)} m²` : "—"],
      ["Dwell CV", m.dwell_cv !== undefined ? dwell(m) : "—"],
      ["Compute", `${fmt.num(m.compute_ms, 0)} ms`],
    ];
    // Two figures a row: the table stays short enough to keep the robots in view.
    const shown = rows.filter(([, v]) => v !== "—");
    const trs = [];
    for (let i = 0; i < shown.length; i += 2) {
      const pair = shown.slice(i, i + 2).flatMap(([k, v]) => [el("th", { text: k }), el("td", { text: v })]);
      trs.push(el("tr", {}, ...pair));
    }
    table.replaceChildren(el("caption", { text: "Metrics" }), ...trs);
    table.hidden = false;
  } else {
    table.replaceChildren();
    table.hidden = true;
  }
  const warnings = [...(p.warnings || [])];
  if (p.error) warnings.unshift(`error: ${p.error}`);
  if (p.missed && p.missed.length) warnings.push(`${plural(p.missed.length, "stretch", "es")} missed (blocked)`);
  $("pd-warnings").replaceChildren(...warnings.map((w) => el("li", { text: w })));

  const cl = $("pd-corrections");
  if (corr.length) {
    cl.replaceChildren(
      el("div", { class: "sub-head", text: `Corrections (${corr.length})` }),
      ...corr
        .slice(-8)
        .reverse()
        .map((c) =>
          el(
            "div",
            { class: `corr-row r-${c.reason}`, dataset: { testid: "correction-row" } },
            el("span", { class: "corr-ver", text: `v${c.base_version}→v${c.version}` }),
            el("span", { class: `chip c-${c.reason}`, text: c.reason }),
            el("span", { class: "muted", text: `${c.waypoints.length} wp · ${(c.compute_us / 1000).toFixed(1)} ms` }),
          ),
        ),
    );
  } else {
    cl.replaceChildren();
  }

  $("assign").disabled = p.status !== "ready";
  $("assign-robot").disabled = p.status !== "ready";
  // The API cancels a plan while it is computed (409 after): offer it then only.
  const cancellable = p.status === "queued" || p.status === "planning";
  $("cancel-plan").disabled = !cancellable;
  $("cancel-plan").title = cancellable ? "Stop computing this plan" : "Only a plan being computed can be cancelled";
  fillRobotChoices();
}

export const renderPlanSoon = throttle(renderPlan, 250);

export function robotLabel(v) {
  if (!v.plan_id) return v.alive ? v.robot : `${v.robot} · lost`;
  const ver = followedVersion(v);
  const f = v.driven_fraction !== undefined ? ` ${Math.round(v.driven_fraction * 100)}%` : "";
  return `${v.robot} · ${v.plan_id}${ver ? ` v${ver}` : ""}${f}${v.alive ? "" : " · lost"}`;
}

export function followedVersion(v) {
  const p = state.plans.get(v.plan_id);
  let ver = p ? p.version : 0;
  if (v.last_correction && v.last_correction.plan_id === v.plan_id) ver = Math.max(ver, v.last_correction.version);
  return ver;
}

export const renderRobots = throttle(renderRobotsNow, 250);

export function renderRobotsNow() {
  const body = $("robots-body");
  const ids = [...state.robots.keys()].sort((a, b) => a.localeCompare(b, undefined, { numeric: true }));
  const alive = ids.filter((id) => state.robots.get(id).view.alive).length;
  $("robots-count").textContent = ids.length ? `${alive} alive / ${ids.length}` : "";
  if (!ids.length) {
    const note = el("td", { colspan: "4", class: "empty-note", text: "No robot on this site yet." });
    body.replaceChildren(el("tr", {}, note));
    return;
  }
  // Rows are kept and updated in place (30 robots at 10 Hz must stay cheap).
  const rows = new Map([...body.children].filter((tr) => tr.dataset.robot).map((tr) => [tr.dataset.robot, tr]));
  const out = [];
  for (const id of ids) {
    const v = state.robots.get(id).view;
    let tr = rows.get(id);
    if (!tr) {
      tr = el(
        "tr",
        { dataset: { robot: id, testid: "robot-row" }, onclick: () => selectRobot(id), tabindex: "0" },
        el("td", {}, el("span", { class: "dot" }), el("span", { class: "rid", text: id })),
        el("td", { class: "rplan" }),
        el("td", {}, el("div", { class: "rdriven" }, bar(0, "driven"), el("span", { class: "rpct" }))),
        el("td", { class: "num rseen" }),
      );
    }
    tr.classList.toggle("lost", !v.alive);
    tr.classList.toggle("selected", id === state.selectedRobot);
    tr.dataset.alive = v.alive ? "true" : "false";
    tr.querySelector(".dot").title = v.alive ? "alive" : "lost";
    const ver = v.plan_id ? followedVersion(v) : 0;
    setText(tr.querySelector(".rplan"), v.plan_id ? `${v.plan_id}${ver ? ` v${ver}` : ""}` : "—");
    const f = v.driven_fraction;
    tr.querySelector(".bar i").style.width = `${((f || 0) * 100).toFixed(1)}%`;
    setText(tr.querySelector(".rpct"), f !== undefined ? `${Math.round(f * 100)}%` : "");
    const lc = v.last_correction;
    tr.title = [
      `${id}: ${v.alive ? "alive" : "lost"}`,
      v.pose ? ` at (${v.pose.x.toFixed(2)}, ${v.pose.y.toFixed(2)})` : "",
      v.driven_m ? ` · ${v.driven_m.toFixed(1)} m driven` : "",
      lc ? ` · last correction v${lc.version} ${lc.reason}` : "",
    ].join("");
    setText(tr.querySelector(".rseen"), fmt.age(v.last_seen_ms));
    out.push(tr);
  }
  if (out.length !== body.children.length || out.some((tr, i) => body.children[i] !== tr)) body.replaceChildren(...out);
}

export function fillRobotChoices() {
  const sel = $("assign-robot");
  const prev = sel.value;
  const seen = new Map();
  for (const r of state.allRobots) seen.set(r.robot, r);
  for (const [id, r] of state.robots) seen.set(id, r.view);
  const byId = (a, b) => a.robot.localeCompare(b.robot, undefined, { numeric: true });
  const list = [...seen.values()].sort((a, b) => (a.alive === b.alive ? byId(a, b) : a.alive ? -1 : 1));
  const opts = list.map((r) =>
    el("option", {
      value: r.robot,
      text: `${r.robot}${r.alive ? "" : " (lost)"}${r.plan_id ? ` (${r.plan_id})` : ""}`,
    }),
  );
  if (!opts.length) opts.push(el("option", { value: "", text: "no robot yet" }));
  const sig = opts.map((o) => o.value + o.textContent).join("|");
  if (sel.dataset.sig !== sig) {
    sel.replaceChildren(...opts);
    sel.dataset.sig = sig;
    if (prev && seen.has(prev)) sel.value = prev;
  }
}

export const renderMissions = throttle(() => {
  const box = $("missions-list");
  const list = [...state.missions.values()].sort((a, b) => b.created_ms - a.created_ms);
  $("missions-count").textContent = list.length ? `${list.length}` : "";
  if (!list.length) {
    box.replaceChildren(el("p", { class: "empty-note", text: "No mission on this site." }));
    return;
  }
  box.replaceChildren(...list.map(missionRow));
}, 300);

function missionRow(m) {
  const c = m.coverage;
  const pct = (v) => (v === undefined || v === null ? "—" : `${fmt.num(v, 1)} %`);
  const figures = `planned ${pct(c.planned_pct)} · measured ${pct(c.measured_pct)}`;
  const seams = c.seam_pct !== undefined ? ` · seams ${pct(c.seam_pct)}` : "";
  const planButton = (p) =>
    el(
      "button",
      {
        class: "link",
        type: "button",
        title: `${p.plan_id}: ${p.status}, driven ${fmt.pct(p.driven_fraction)}`,
        onclick: () => state.plans.has(p.plan_id) && selectPlan(p.plan_id),
      },
      `${p.robot} ▸ ${p.plan_id} ${Math.round((p.driven_fraction || 0) * 100)}%`,
    );
  return el(
    "div",
    { class: "mission", dataset: { testid: "mission-row", mission: m.mission_id, status: m.status } },
    el(
      "div",
      { class: "mission-head" },
      el("span", { class: "plan-id", text: m.mission_id }),
      chip(m.status),
      el("span", { class: "muted", text: m.eta_s !== undefined ? `ETA ${fmt.dur(m.eta_s)}` : "" }),
    ),
    bar(m.progress, m.status === "planning" ? "computing" : "driven"),
    el("div", { class: "mission-cov muted" }, figures + seams),
    el("div", { class: "mission-plans" }, ...m.plans.map(planButton)),
  );
}
