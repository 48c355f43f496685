// A benchmark's report: its result JSON as tables (one per group of rows) and the distributions
// it carries (arrays of samples) as histograms.
import { makePlot, color } from "./plots.js";
import { fmt } from "./series.js";

function isRecord(v) {
  return v !== null && typeof v === "object" && !Array.isArray(v);
}

function scalarEntries(obj) {
  return Object.entries(obj).filter(([, v]) => v === null || typeof v !== "object");
}

/** A table of `rows` (name -> flat object), columns the union of their scalar keys. */
function table(parent, rows) {
  const names = Object.keys(rows);
  const columns = [];
  for (const n of names) for (const [k] of scalarEntries(rows[n])) if (!columns.includes(k)) columns.push(k);
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
      td.textContent = typeof c === "number" ? fmt(c, 4) : c === undefined ? "" : String(c);
      tr.appendChild(td);
    }
    t.appendChild(tr);
  }
  parent.appendChild(t);
}

function histogram(parent, title, samples, clock) {
  const finite = samples.filter((v) => typeof v === "number" && Number.isFinite(v));
  if (finite.length < 2) return;
  const lo = Math.min(...finite);
  const hi = Math.max(...finite);
  const bins = Math.min(40, Math.max(5, Math.ceil(Math.sqrt(finite.length))));
  const width = hi > lo ? (hi - lo) / bins : 1;
  const counts = new Array(bins).fill(0);
  for (const v of finite) counts[Math.min(bins - 1, Math.floor((v - lo) / width))] += 1;
  const centres = counts.map((_, i) => lo + (i + 0.5) * width);
  makePlot(parent, { title: `${title} (${finite.length} samples)`, x: centres, yLabel: "count", series: [{ label: "count", values: counts, color: color(0) }] }, clock);
}

function walk(parent, name, value, clock, depth) {
  if (!isRecord(value)) return;
  const heading = document.createElement(depth === 0 ? "h2" : "h3");
  heading.textContent = name;
  const scalars = scalarEntries(value);
  const children = Object.entries(value).filter(([, v]) => isRecord(v));
  const arrays = Object.entries(value).filter(([, v]) => Array.isArray(v));
  parent.appendChild(heading);
  // A group whose members are all records of scalars is one table (methods x metrics).
  if (children.length > 0 && children.every(([, v]) => scalarEntries(v).length > 0)) {
    table(parent, Object.fromEntries(children));
  }
  if (scalars.length > 0) table(parent, { [name]: Object.fromEntries(scalars) });
  const plots = document.createElement("div");
  plots.className = "plots";
  parent.appendChild(plots);
  for (const [k, v] of arrays) {
    if (v.length > 1 && v.every((x) => typeof x === "number")) histogram(plots, `${name}: ${k}`, v, clock);
    else if (v.length > 0 && v.every(isRecord)) {
      table(parent, Object.fromEntries(v.map((row, i) => [String(row.name ?? row.method ?? i), row])));
    }
  }
  for (const [k, v] of children) {
    if (Object.values(v).some((x) => x !== null && typeof x === "object")) walk(parent, `${name} / ${k}`, v, clock, depth + 1);
  }
}

export function renderBench(app, data) {
  const h1 = document.createElement("h1");
  h1.textContent = `rotorguard · ${data.title}`;
  app.appendChild(h1);
  const sub = document.createElement("div");
  sub.className = "sub";
  sub.textContent = "The tables and distributions of `rotorguard " + data.title + " --json`.";
  app.appendChild(sub);
  const clock = { time: () => NaN, set: () => {}, onChange: () => {} };
  walk(app, data.bench, data.result, clock, 0);
  return { kind: "bench" };
}
