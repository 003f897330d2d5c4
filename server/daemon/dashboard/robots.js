// The site's robots: poses and trails for the map, views for the table, the robots offered for assignment.
// `robots` events carry the site's robots whose view changed; a robot assigned to another site's plan leaves
// this one (found by re-reading GET /v1/robots now and then).

import { get } from "./api.js";
import {
  fillRobotChoices,
  renderPlanSoon,
  renderPlans,
  renderRobots,
  renderRobotsNow,
  robotLabel,
} from "./panels.js";
import { throttle } from "./sse.js";
import { TRAIL_MAX, state } from "./store.js";
import { load, selectPlan } from "./app.js";

export async function loadRobots(gen) {
  const list = await load("Load robots", () => get("/v1/robots"));
  if (!list || gen !== state.gen) return;
  state.allRobots = list;
  const mine = list.filter((r) => r.site === state.site);
  onRobots({ robots: mine });
  fillRobotChoices();
}

export function onRobots(e) {
  let plansMoved = false;
  let selectedMoved = false;
  for (const v of e.robots || []) {
    if (v.site && state.site && v.site !== state.site) {
      // It left this site (assigned elsewhere): drop it.
      state.robots.delete(v.robot);
      continue;
    }
    let r = state.robots.get(v.robot);
    if (!r) {
      r = { view: v, draw: { x: 0, y: 0, yaw: 0, alive: v.alive, trail: [], label: v.robot, selected: false } };
      state.robots.set(v.robot, r);
    }
    r.view = v;
    const d = r.draw;
    d.alive = v.alive;
    if (v.pose) {
      const last = d.trail[d.trail.length - 1];
      if (!last || Math.hypot(v.pose.x - last[0], v.pose.y - last[1]) > 0.02) {
        d.trail.push([v.pose.x, v.pose.y]);
        if (d.trail.length > TRAIL_MAX) d.trail.splice(0, d.trail.length - TRAIL_MAX);
      }
      d.x = v.pose.x;
      d.y = v.pose.y;
      d.yaw = v.pose.yaw;
      d.hasPose = true;
    }
    d.label = robotLabel(v);
    d.selected = v.robot === state.selectedRobot;
    // The plan's progress moves with its robot (the plans list and the plan card show it too).
    const p = v.plan_id ? state.plans.get(v.plan_id) : null;
    if (p && v.driven_fraction !== undefined && p.driven_fraction !== v.driven_fraction) {
      p.driven_fraction = v.driven_fraction;
      plansMoved = true;
      if (p.plan_id === state.selected) selectedMoved = true;
    }
  }
  pushRobots();
  pushDriven();
  renderRobots();
  if (plansMoved) renderPlans();
  if (selectedMoved) renderPlanSoon();
}

/** The selected plan's driven part, from its robot's view (or the plan's status). */
export function pushDriven() {
  const p = state.selected ? state.plans.get(state.selected) : null;
  if (!p) return;
  let f = p.driven_fraction;
  for (const r of state.robots.values()) {
    if (r.view.plan_id === p.plan_id && r.view.driven_fraction !== undefined) f = r.view.driven_fraction;
  }
  state.view.setDriven(f);
}

export function pushRobots() {
  const m = new Map();
  for (const [id, r] of state.robots) if (r.draw.hasPose) m.set(id, r.draw);
  state.view.setRobots(m);
}

export function selectRobot(id) {
  state.selectedRobot = id === state.selectedRobot ? null : id;
  for (const [rid, r] of state.robots) r.draw.selected = rid === state.selectedRobot;
  const r = state.robots.get(id);
  if (state.selectedRobot && r) {
    if (r.draw.hasPose) state.view.centerOn(r.draw.x, r.draw.y);
    const plan = r.view.plan_id;
    if (plan && state.plans.has(plan) && plan !== state.selected) selectPlan(plan);
  }
  pushRobots();
  renderRobotsNow();
}

export const refreshAllRobots = throttle(async () => {
  const list = await get("/v1/robots").catch(() => null);
  if (!list) return;
  state.allRobots = list;
  // Robots assigned elsewhere since: no longer on this site.
  let gone = false;
  for (const r of list) {
    if (state.robots.has(r.robot) && r.site !== state.site) {
      state.robots.delete(r.robot);
      gone = true;
    }
  }
  if (gone) {
    pushRobots();
    renderRobots();
  }
  fillRobotChoices();
}, 1000);
