// DOM helpers: element builder, number formats, status chips and progress bars.

export const $ = (id) => document.getElementById(id);

export function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k === "class") e.className = v;
    else if (k === "text") e.textContent = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else if (k === "dataset") Object.assign(e.dataset, v);
    else e.setAttribute(k, v === true ? "" : v);
  }
  for (const c of children) if (c !== null && c !== undefined) e.append(c);
  return e;
}

export const fmt = {
  pct: (f) => (f === undefined || f === null ? "—" : `${(f * 100).toFixed(f < 0.1 ? 1 : 0)} %`),
  num: (v, d = 1) => (v === undefined || v === null || !Number.isFinite(v) ? "—" : v.toFixed(d)),
  dur(s) {
    if (s === undefined || s === null || !Number.isFinite(s)) return "—";
    const m = Math.floor(s / 60);
    const r = Math.round(s - m * 60);
    return m >= 60 ? `${Math.floor(m / 60)} h ${m % 60} min` : m ? `${m} min ${r} s` : `${r} s`;
  },
  age(ms) {
    if (!ms) return "—";
    const s = Math.max(0, (Date.now() - ms) / 1000);
    if (s < 10) return `${s.toFixed(1)} s`;
    if (s < 120) return `${Math.round(s)} s`;
    return s < 7200 ? `${Math.round(s / 60)} min` : `${Math.round(s / 3600)} h`;
  },
  time: (ms) => (ms ? new Date(ms).toLocaleTimeString() : "—"),
};

export function chip(status) {
  return el("span", { class: `chip s-${status}`, text: status });
}

export function bar(fraction, kind = "") {
  const f = Math.min(Math.max(fraction || 0, 0), 1);
  const b = el("div", { class: `bar ${kind}` }, el("i"));
  b.firstChild.style.width = `${(f * 100).toFixed(1)}%`;
  return b;
}

export function setText(node, text) {
  if (node.textContent !== text) node.textContent = text;
}

/** "3 corrections", "1 stretch": `n` and the word, with `suffix` for more than one. */
export function plural(n, word, suffix = "s") {
  return `${n} ${word}${n === 1 ? "" : suffix}`;
}
