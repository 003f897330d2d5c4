// One site's event stream (GET /v1/sites/{site}/events, open to read: no token, nothing in the URL but the
// site). EventSource reconnects by itself; `onState` hears "connecting", "live" and "reconnecting", and
// `onResync` is called on every (re)open after the first so the page can re-read what it may have missed.

import { seg } from "./api.js";

const EVENTS = ["site", "robots", "status", "progress", "region-ready", "correction", "mission", "coverage", "live"];

export class SiteStream {
  /**
   * handlers: { [eventName]: (data) => void, onState?: (state) => void, onResync?: () => void }
   */
  constructor(site, handlers) {
    this.site = site;
    this.handlers = handlers;
    this.opened = 0;
    this.closed = false;
    this.counts = Object.create(null);
    this.source = new EventSource(`/v1/sites/${seg(site)}/events`);
    this.setState("connecting");
    this.source.onopen = () => {
      this.opened += 1;
      this.setState("live");
      if (this.opened > 1 && handlers.onResync) handlers.onResync();
    };
    this.source.onerror = () => {
      if (this.closed) return;
      // CLOSED: the server refused the stream (404 unknown site, …); EventSource will not retry.
      this.setState(this.source.readyState === EventSource.CLOSED ? "closed" : "reconnecting");
    };
    for (const name of EVENTS) {
      this.source.addEventListener(name, (ev) => {
        this.counts[name] = (this.counts[name] || 0) + 1;
        const f = handlers[name];
        if (!f) return;
        let data;
        try {
          data = JSON.parse(ev.data);
        } catch (e) {
          console.warn(`[shift] ${name} event is not JSON`, e);
          return;
        }
        try {
          f(data);
        } catch (e) {
          console.error(`[shift] ${name} handler`, e);
        }
      });
    }
  }

  setState(s) {
    this.state = s;
    if (this.handlers.onState) this.handlers.onState(s);
  }

  close() {
    this.closed = true;
    this.source.close();
  }
}

/** One plan's event stream (GET /v1/plans/{id}/events): replays the regions already streamed while planning. */
export function planStream(planId, handlers) {
  const source = new EventSource(`/v1/plans/${seg(planId)}/events`);
  for (const name of ["status", "progress", "region-ready", "correction"]) {
    source.addEventListener(name, (ev) => {
      try {
        const f = handlers[name];
        if (f) f(JSON.parse(ev.data));
      } catch (e) {
        console.error(`[shift] plan ${name} handler`, e);
      }
    });
  }
  source.onerror = () => {
    // The stream ends after a final status; do not reconnect to a finished plan.
    source.close();
  };
  return source;
}

/** Calls `f` at most once per `ms`, the last call always landing (leading and trailing). */
export function throttle(f, ms) {
  let last = 0;
  let timer = 0;
  let pendingArgs = null;
  return (...args) => {
    pendingArgs = args;
    const now = performance.now();
    const wait = last + ms - now;
    if (wait <= 0 && !timer) {
      last = now;
      f(...pendingArgs);
      pendingArgs = null;
      return;
    }
    if (!timer) {
      timer = setTimeout(() => {
        timer = 0;
        last = performance.now();
        const a = pendingArgs;
        pendingArgs = null;
        if (a) f(...a);
      }, Math.max(wait, 0));
    }
  };
}
