// Time-series plots with uPlot: every chart shares the replay's time cursor (a vertical line),
// and draws markers (fault onset, detection) and thresholds as the paper's figures do.
import uPlot from "uplot";

const PALETTE = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"];

export function color(i) {
  return PALETTE[i % PALETTE.length];
}

/**
 * A chart in `parent`.
 * spec: { title, x (times, or another abscissa named by xLabel), series: [{label, values, color, dash, width, steps,
 *         pointsOnly}], yLabel, markers: [{t, color, label}], thresholds: [{y, color, label}], yRange: [lo, hi],
 *         yLog (a base-10 y axis; values must be positive or null) }
 * A pointsOnly series draws a dot per sample and no line: samples picked out of another series
 * (null elsewhere).
 * clock: { time(), onChange(fn), set(t) } — the replay's time.
 */
export function makePlot(parent, spec, clock) {
  const box = document.createElement("div");
  box.className = "plot";
  const title = document.createElement("h3");
  title.textContent = spec.title;
  box.appendChild(title);
  parent.appendChild(box);

  const markers = spec.markers || [];
  const thresholds = spec.thresholds || [];
  const draw = (u) => {
    const ctx = u.ctx;
    const { left, top, width, height } = u.bbox;
    ctx.save();
    ctx.beginPath();
    ctx.rect(left, top, width, height);
    ctx.clip();
    ctx.lineWidth = 1.5 * devicePixelRatio;
    for (const th of thresholds) {
      const y = u.valToPos(th.y, "y", true);
      ctx.strokeStyle = th.color || "#555";
      ctx.setLineDash([6 * devicePixelRatio, 4 * devicePixelRatio]);
      ctx.beginPath();
      ctx.moveTo(left, y);
      ctx.lineTo(left + width, y);
      ctx.stroke();
    }
    for (const [k, m] of markers.entries()) {
      const x = u.valToPos(m.t, "x", true);
      ctx.strokeStyle = m.color || "#000";
      ctx.setLineDash([3 * devicePixelRatio, 3 * devicePixelRatio]);
      ctx.beginPath();
      ctx.moveTo(x, top);
      ctx.lineTo(x, top + height);
      ctx.stroke();
      ctx.setLineDash([]);
      ctx.fillStyle = m.color || "#000";
      ctx.font = `${11 * devicePixelRatio}px sans-serif`;
      ctx.fillText(m.label || "", x + 3 * devicePixelRatio, top + (12 + 12 * k) * devicePixelRatio);
    }
    // The replay's current time.
    const x = u.valToPos(clock.time(), "x", true);
    ctx.setLineDash([]);
    ctx.strokeStyle = "rgba(0,0,0,0.55)";
    ctx.beginPath();
    ctx.moveTo(x, top);
    ctx.lineTo(x, top + height);
    ctx.stroke();
    ctx.restore();
  };

  const series = [{ label: spec.xLabel || "t [s]" }];
  const data = [spec.x];
  for (const [i, s] of spec.series.entries()) {
    series.push({
      label: s.label,
      stroke: s.color || color(i),
      width: s.width || 1.5,
      dash: s.dash,
      points: s.pointsOnly ? { show: true, size: 6, fill: s.color || color(i) } : { show: false },
      paths: s.pointsOnly ? () => null : s.steps ? uPlot.paths.stepped({ align: 1 }) : undefined,
      fill: s.steps ? `${s.color || color(i)}22` : undefined,
      value: (u, v) => (v == null ? "–" : v.toFixed(3)),
    });
    data.push(s.values);
  }
  const width = () => Math.max(300, box.clientWidth - 12);
  const options = {
    width: width(),
    height: spec.height || 220,
    series,
    scales: { x: { time: false }, y: { ...(spec.yRange ? { range: spec.yRange } : {}), ...(spec.yLog ? { distr: 3 } : {}) } },
    axes: [{ label: spec.xLabel || "t [s]", size: 36 }, { label: spec.yLabel || "", size: 56 }],
    legend: { live: true },
    cursor: { sync: { key: "rotorguard-time" }, drag: { x: true, y: false } },
    hooks: { draw: [draw] },
  };
  const plot = new uPlot(options, data, box);
  // A click on the chart moves the replay to that time.
  plot.over.addEventListener("click", () => {
    const left = plot.cursor.left;
    if (left !== undefined && left >= 0) clock.set(plot.posToVal(left, "x"));
  });
  clock.onChange(() => plot.redraw(false, false));
  window.addEventListener("resize", () => plot.setSize({ width: width(), height: options.height }));
  return plot;
}
