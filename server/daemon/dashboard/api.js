// The daemon's HTTP API from the page: one fetch wrapper, the bearer token, and the error banner.
//
// The token is typed by the operator; it lives in this module (and in sessionStorage, so a reload of the same
// tab keeps it; closing the tab forgets it). It goes out only as an `Authorization: Bearer` header on mutating
// calls, never in a URL. An API error is thrown as ApiError carrying the API's `error.message`; callers that
// act for the operator pass it to `showError`, which puts that message in the banner.

const TOKEN_KEY = "shift.token";

let token = "";
try {
  token = sessionStorage.getItem(TOKEN_KEY) || "";
} catch (_) {
  token = "";
}
const tokenListeners = new Set();

/** The bearer token typed by the operator ("" = none). */
export function getToken() {
  return token;
}

/** Sets (or clears with "") the token for mutating calls. */
export function setToken(value) {
  token = (value || "").trim();
  try {
    if (token) sessionStorage.setItem(TOKEN_KEY, token);
    else sessionStorage.removeItem(TOKEN_KEY);
  } catch (_) {
    /* storage off: memory only */
  }
  for (const f of tokenListeners) f(token);
}

export function onTokenChange(f) {
  tokenListeners.add(f);
}

/** An answer other than 2xx: status, the API's code and message. */
export class ApiError extends Error {
  constructor(status, code, message, method, path) {
    super(message);
    this.name = "ApiError";
    this.status = status;
    this.code = code;
    this.method = method;
    this.path = path;
  }
  get isAuth() {
    return this.status === 401 || this.status === 403;
  }
}

/** A path segment, percent-encoded. */
export function seg(s) {
  return encodeURIComponent(String(s));
}

/**
 * Calls the API. `body`: an object (sent as JSON), a FormData (multipart) or undefined. Mutating methods carry
 * the token when one is set. Returns the parsed JSON (or null for an empty body); throws ApiError.
 */
export async function api(method, path, body, { signal } = {}) {
  const headers = { accept: "application/json" };
  let payload;
  if (body instanceof FormData) {
    payload = body;
  } else if (body !== undefined) {
    headers["content-type"] = "application/json";
    payload = typeof body === "string" ? body : JSON.stringify(body);
  }
  if (method !== "GET" && token) headers.authorization = `Bearer ${token}`;
  let res;
  try {
    res = await fetch(path, { method, headers, body: payload, signal, cache: "no-store" });
  } catch (e) {
    if (e && e.name === "AbortError") throw e;
    throw new ApiError(0, "network", `cannot reach the daemon (${e && e.message ? e.message : e})`, method, path);
  }
  const text = await res.text();
  let data = null;
  if (text) {
    try {
      data = JSON.parse(text);
    } catch (_) {
      data = null;
    }
  }
  if (!res.ok) {
    const err = data && data.error ? data.error : null;
    const message = err && err.message ? err.message : `${res.status} ${res.statusText || "error"}`.trim();
    throw new ApiError(res.status, err && err.code ? err.code : `http_${res.status}`, message, method, path);
  }
  return data;
}

export const get = (path, opts) => api("GET", path, undefined, opts);
export const post = (path, body) => api("POST", path, body);
export const del = (path) => api("DELETE", path);

// --- the banner and toasts ----------------------------------------------------------------------------------

const errorLog = [];
let bannerTimer = 0;

/** Errors shown so far (newest last), for the debug hook. */
export function errorsShown() {
  return errorLog.slice();
}

/**
 * Shows an error in the banner: the API's message for an ApiError, the text otherwise. `what` names the action
 * ("Assign p-3"). The banner stays until dismissed or replaced (auth errors and network errors included).
 */
export function showError(e, what) {
  const banner = document.getElementById("error-banner");
  const msg = e instanceof ApiError ? e.message : e && e.message ? e.message : String(e);
  const detail =
    e instanceof ApiError
      ? `${e.status ? e.status + " " : ""}${e.code}${e.path ? " · " + e.method + " " + e.path : ""}`
      : "";
  errorLog.push({ what: what || "", message: msg, status: e instanceof ApiError ? e.status : 0, at: Date.now() });
  if (errorLog.length > 50) errorLog.shift();
  if (!banner) return;
  banner.querySelector(".banner-what").textContent = what ? `${what} failed:` : "Error:";
  banner.querySelector("[data-testid=error-message]").textContent = msg;
  banner.querySelector(".banner-detail").textContent = detail;
  banner.hidden = false;
  banner.classList.remove("flash");
  void banner.offsetWidth; // restart the flash animation
  banner.classList.add("flash");
  clearTimeout(bannerTimer);
  console.warn(`[shift] ${what || "error"}: ${msg}`, detail);
}

export function hideError() {
  const banner = document.getElementById("error-banner");
  if (banner) banner.hidden = true;
}

/** A short confirmation that fades away. */
export function toast(text, kind = "ok") {
  const box = document.getElementById("toasts");
  if (!box) return;
  const el = document.createElement("div");
  el.className = `toast ${kind}`;
  el.dataset.testid = "toast";
  el.textContent = text;
  box.appendChild(el);
  while (box.children.length > 4) box.firstChild.remove();
  setTimeout(() => el.classList.add("gone"), 3500);
  setTimeout(() => el.remove(), 4200);
}
