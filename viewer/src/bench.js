// A benchmark's report: its result JSON as tables (one per group of rows) and the distributions
// it carries (arrays of samples) as histograms; the FTC benchmark's FDD latencies are drawn per
// fault kind with one curve per method, as the paper compares them.
import { makePlot, color } from "./plots.js";
import { fmt } from "./series.js";

const NO_CLOCK = { time: () => NaN, set: () => {}, onChange: () => {} };

function isRecord(v) {
  return v !== null && typeof v === "object" && !Array.isArray(v);
}

function scalarEntries(obj) {
  return Object.entries(obj).filter(([, v]) => v === null || typeof v !== "object");
}

function isSamples(v) {
  return Array.isArray(v) && v.length > 0 && v.every((x) => typeof x === "number");
}

/** A table of `rows` (name -> record), columns the union of their scalar keys. */
function table(parent, rows) {
  const names = Object.keys(rows);
  const columns = [];
  for (const n of names) for (const [k] of scalarEntries(rows[n])) if (!columns.includes(k)) columns.push(k);
  if (columns.length === 0) return;
  const t = document.createElement("table");
  t.className = "data";
  const head = document.createElement("tr");
  for (const c of ["", ...columns]) {
    const th = document.createElement("th");
    th.textContent = c;
    head.appendChild(th);
  }
  t.appendChild(head);
  for (const n of names) {
    const tr = document.createElement("tr");
    for (const c of [n, ...columns.map((k) => rows[n][k])]) {
      const td = document.createElement("td");
      td.textContent = typeof c === "number" ? fmt(c, 4) : c === undefined || c === null ? "–" : String(c);
      tr.appendChild(td);
    }
    t.appendChild(tr);
  }
  const wrap = document.createElement("div");
  wrap.className = "table-wrap";
  wrap.appendChild(t);
  parent.appendChild(wrap);
}

/** Histograms of several sample sets on shared bins: one curve per set. */
function histograms(parent, title, sets, unit) {
  const all = sets.flatMap((s) => s.values).filter(Number.isFinite);
  if (all.length < 2) return;
  const lo = Math.min(...all);
  const hi = Math.max(...all);
  const bins = Math.min(40, Math.max(5, Math.ceil(Math.sqrt(all.length))));
  const width = hi > lo ? (hi - lo) / bins : 1;
  // Bin edges, the last count repeated at the right edge: a stepped line draws the bars' tops.
  const edges = Array.from({ length: bins + 1 }, (_, i) => lo + i * width);
  const series = sets.map((s, k) => {
    const counts = new Array(bins).fill(0);
    for (const v of s.values) if (Number.isFinite(v)) counts[Math.min(bins - 1, Math.floor((v - lo) / width))] += 1;
    counts.push(counts[bins - 1]);
    return { label: `${s.label} (${s.values.length})`, values: counts, color: color(k), steps: true };
  });
  makePlot(parent, { title, x: edges, xLabel: unit, yLabel: "count", series, height: 200 }, NO_CLOCK);
}

function plotsDiv(parent) {
  const d = document.createElement("div");
  d.className = "plots";
  parent.appendChild(d);
  return d;
}

/** Walks the result: records of records become tables, sample arrays histograms. */
function walk(parent, name, value, depth, tabulated) {
  const heading = document.createElement(depth === 0 ? "h2" : "h3");
  heading.textContent = name;
  parent.appendChild(heading);
  const children = Object.entries(value).filter(([, v]) => isRecord(v) && Object.keys(v).length > 0);
  const rowChildren = children.filter(([, v]) => scalarEntries(v).length > 0);
  if (rowChildren.length > 0) table(parent, Object.fromEntries(rowChildren));
  // Samples every row holds under the same key: one histogram, a curve per row.
  const shared = rowChildren.length > 1
    ? Object.keys(rowChildren[0][1]).filter((k) => rowChildren.every(([, v]) => isSamples(v[k])))
    : [];
  if (shared.length > 0) {
    const plots = plotsDiv(parent);
    for (const k of shared) histograms(plots, `${name}: ${k}`, rowChildren.map(([n, v]) => ({ label: n, values: v[k] })), k);
  }
  if (!tabulated) table(parent, { [name]: Object.fromEntries(scalarEntries(value)) });
  const samples = Object.entries(value).filter(([, v]) => isSamples(v));
  if (samples.length > 0) {
    const plots = plotsDiv(parent);
    for (const [k, v] of samples) histograms(plots, `${name}: ${k}`, [{ label: k, values: v }], k);
  }
  for (const [k, v] of Object.entries(value)) {
    if (Array.isArray(v) && v.length > 0 && v.every(isRecord)) {
      parent.appendChild(Object.assign(document.createElement("h3"), { textContent: `${name}: ${k}` }));
      table(parent, Object.fromEntries(v.map((row, i) => [String(i + 1), row])));
    }
  }
  for (const [k, v] of children) {
    const nested = Object.entries(v).some(([key, x]) => (isRecord(x) && Object.keys(x).length > 0) || (isSamples(x) && !shared.includes(key)));
    if (nested) walk(parent, `${name} / ${k}`, v, depth + 1, rowChildren.some(([rk]) => rk === k));
  }
}

/** The FTC benchmark: FDD latency distributions per fault kind, one curve per method. */
function ftcLatencies(parent, result) {
  const cells = (result.cells || []).filter((c) => Array.isArray(c.fdd_latencies_s));
  const faults = [...new Set(cells.map((c) => c.fault))].filter((f) => f !== "none");
  if (faults.length === 0) return;
  parent.appendChild(Object.assign(document.createElement("h2"), { textContent: "FDD latency per method" }));
  const plots = plotsDiv(parent);
  for (const fault of faults) {
    const methods = [...new Set(cells.filter((c) => c.fault === fault).map((c) => c.method))];
    const sets = methods
      .map((m) => ({ label: m, values: cells.filter((c) => c.fault === fault && c.method === m).flatMap((c) => c.fdd_latencies_s.map((s) => 1000 * s)) }))
      .filter((s) => s.values.length > 0);
    histograms(plots, `${fault}: detection latency [ms]`, sets, "ms");
  }
}

export function renderBench(app, data) {
  app.appendChild(Object.assign(document.createElement("h1"), { textContent: `rotorguard · ${data.title}` }));
  const sub = document.createElement("div");
  sub.className = "sub";
  sub.textContent = `The result of \`rotorguard ${data.title} --json\`: its tables, then the distributions it holds.`;
  app.appendChild(sub);
  if (data.bench === "ftc") ftcLatencies(app, data.result);
  walk(app, data.bench, data.result, 0, false);
  return { kind: "bench" };
}
