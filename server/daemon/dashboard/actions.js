// What the operator does: upload a map, create a plan by clicking its start, assign it, cancel it. Every action
// goes through `act`: a failure shows the API's message in the banner; a 401/403 asks for the token and retries.

import {
  ApiError,
  api,
  del,
  errorsShown,
  get,
  getToken,
  hideError,
  post,
  seg,
  setToken,
  showError,
  toast,
} from "./api.js";
import { $ } from "./dom.js";
import { renderPlans } from "./panels.js";
import { state } from "./store.js";
import { loadSites, onStatus, selectPlan, upsertPlan } from "./app.js";
import { refreshAllRobots } from "./robots.js";

let retryAfterToken = null;

export function askToken(message, retry) {
  retryAfterToken = retry;
  $("token-dialog-msg").textContent = message;
  $("token-dialog-input").value = "";
  const d = $("token-dialog");
  if (!d.open) d.showModal();
  $("token-dialog-input").focus();
}

/** The token typed in the dialog: kept, and the refused action retried with it. */
export function submitTokenDialog() {
  setToken($("token-dialog-input").value);
  $("token-dialog").close();
  const retry = retryAfterToken;
  retryAfterToken = null;
  if (retry && getToken()) retry();
}

export function cancelTokenDialog() {
  retryAfterToken = null;
  $("token-dialog").close();
}

export function showTokenState(t) {
  const s = $("token-state");
  s.textContent = t ? "token set" : "no token";
  s.classList.toggle("on", !!t);
  $("token-input").value = "";
  $("token-input").placeholder = t ? "•••••• (replace)" : "API token";
}

/**
 * Runs an operator action: `call` makes the API request, `then` uses its answer. A failure goes to the banner with
 * the API's message; a 401/403 asks for the token and, once it is typed, runs the whole action again.
 */
export async function act(what, call, then) {
  try {
    const out = await call();
    hideError();
    if (then) await then(out);
    return out;
  } catch (e) {
    showError(e, what);
    if (e instanceof ApiError && e.isAuth) askToken(e.message, () => act(what, call, then));
    return undefined;
  }
}

export function startPick() {
  if (!state.grid) {
    showError(new Error("upload or choose a site first"), "New plan");
    return;
  }
  const radius = Number($("np-radius").value);
  const tool = Number($("np-tool").value);
  state.pick = true;
  state.view.setPick({ radius, toolWidth: tool });
  $("pick-hint").hidden = false;
  $("new-plan").classList.add("active");
  $("new-plan").textContent = "Click the start…";
}

export function stopPick() {
  state.pick = false;
  state.view.setPick(null);
  $("pick-hint").hidden = true;
  $("new-plan").classList.remove("active");
  $("new-plan").textContent = "New plan";
}

export async function createPlanAt(x, y) {
  stopPick();
  const radius = Number($("np-radius").value);
  const toolWidth = Number($("np-tool").value);
  const vmax = Number($("np-vmax").value);
  const req = {
    site: state.site,
    start: [Math.round(x * 1000) / 1000, Math.round(y * 1000) / 1000],
    robot: { radius, tool_width: toolWidth, v_max: vmax, v_min: Math.min(0.1, vmax) },
  };
  if ($("np-snap").checked) req.snap_start_m = 0.5;
  const site = state.site;
  await act(
    "New plan",
    () => post("/v1/plans", req),
    async (accepted) => {
      toast(`${accepted.plan_id} queued from (${req.start[0].toFixed(2)}, ${req.start[1].toFixed(2)})`);
      if (site !== state.site) return;
      const now = Date.now();
      if (!state.plans.has(accepted.plan_id)) {
        upsertPlan({
          plan_id: accepted.plan_id,
          site,
          status: accepted.status,
          progress: 0,
          version: 0,
          regions_ready: 0,
          corrections: 0,
          created_ms: now,
          updated_ms: now,
        });
      }
      renderPlans();
      await selectPlan(accepted.plan_id);
      // The status may have moved on before the stream told us: read it once.
      const st = await get(`/v1/plans/${seg(accepted.plan_id)}`).catch(() => null);
      if (st) onStatus(st);
    },
  );
}

export async function assignSelected() {
  const id = state.selected;
  const robot = $("assign-robot").value;
  if (!id) return;
  if (!robot) {
    showError(new Error("no robot to assign: none has been seen by the daemon yet"), `Assign ${id}`);
    return;
  }
  await act(
    `Assign ${id} to ${robot}`,
    () => post(`/v1/plans/${seg(id)}/assign`, { robot }),
    (st) => {
      toast(`${id} assigned to ${robot}`);
      onStatus(st);
      refreshAllRobots();
    },
  );
}

let cancelArmed = 0;

export async function cancelSelected() {
  const id = state.selected;
  if (!id) return;
  const btn = $("cancel-plan");
  if (!cancelArmed) {
    // Two clicks, no native dialog: the first arms it for 3 s.
    btn.textContent = "Sure? Click again";
    btn.classList.add("armed");
    cancelArmed = setTimeout(() => {
      cancelArmed = 0;
      btn.textContent = "Cancel";
      btn.classList.remove("armed");
    }, 3000);
    return;
  }
  clearTimeout(cancelArmed);
  cancelArmed = 0;
  btn.textContent = "Cancel";
  btn.classList.remove("armed");
  await act(
    `Cancel ${id}`,
    () => del(`/v1/plans/${seg(id)}`),
    (st) => {
      toast(`${id} cancelled`);
      onStatus(st);
    },
  );
}

export function openUpload() {
  $("up-error").textContent = "";
  $("upload-dialog").showModal();
  $("up-site").focus();
}

export async function submitUpload(ev) {
  ev.preventDefault();
  const site = $("up-site").value.trim();
  const yaml = $("up-yaml").files[0];
  const image = $("up-image").files[0];
  const json = $("up-json").files[0];
  const err = $("up-error");
  err.textContent = "";
  if (!/^[A-Za-z0-9_-]{1,64}$/.test(site)) {
    err.textContent = "Site name: 1–64 letters, digits, '-' or '_'.";
    return;
  }
  let body;
  if (json) {
    body = await json.text();
  } else if (yaml && image) {
    body = new FormData();
    body.append("yaml", yaml, yaml.name);
    body.append("image", image, image.name);
  } else {
    err.textContent = "Choose a YAML and its image, or a JSON grid.";
    return;
  }
  $("up-submit").disabled = true;
  const summary = await act(
    `Upload the map of ${site}`,
    () => api("POST", `/v1/sites/${seg(site)}/map`, body),
    async (summary) => {
      $("upload-dialog").close();
      $("upload-form").reset();
      $("up-yaml").disabled = false;
      $("up-image").disabled = false;
      err.textContent = "";
      toast(`Map of ${site} uploaded: ${summary.width} × ${summary.height} cells`);
      if (site === state.site) state.site = null; // read it again
      await loadSites(site);
    },
  );
  $("up-submit").disabled = false;
  if (!summary) {
    // The dialog hides the banner: the API's message goes in the dialog too.
    const last = errorsShown().pop();
    if (last) err.textContent = last.message;
  }
}
