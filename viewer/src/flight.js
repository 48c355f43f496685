// A flight's report: the outcome and key metrics, the 3D replay with its time controls, and the
// plots of paper 000's Figs. 7 and 10 (rotor thrusts and speeds, FDD indices, tracking), and, when
// the stack localised itself with its LiDAR-inertial odometry, its estimate and health.
import { Replay } from "./replay.js";
import { makePlot, color } from "./plots.js";
import { eulerFromQuaternion, fmt, indexAt, rotorCount, unwrap } from "./series.js";

function el(tag, attrs = {}, children = []) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "text") e.textContent = v;
    else e.setAttribute(k, v);
  }
  for (const c of children) e.appendChild(c);
  return e;
}

/** Two decimals, without a "-0.00". */
const fixed2 = (v) => (Math.abs(v) < 0.005 ? 0 : v).toFixed(2);

function header(app, data) {
  const s = data.summary;
  app.appendChild(el("h1", { text: `rotorguard · ${data.title}` }));
  const outcome = el("div", { class: "sub" });
  if (data.truthless) {
    // A replayed bag: no truth to judge the flight by; the replay against its recording instead.
    const agrees = s.replay && s.replay.compared > 0 ? s.replay.diagnosis_equal && s.replay.position_max_diff_m <= 1e-3 : null;
    outcome.appendChild(el("span", { class: `badge ${agrees === false ? "bad" : "ok"}`, text: "replay" }));
    outcome.appendChild(document.createTextNode(agrees === null ? "of a bag without recorded cycles · no truth"
      : `${agrees ? "agrees with" : "differs from"} the recording · no truth: the vehicle drawn is the stack's estimate`));
  } else {
    outcome.appendChild(el("span", { class: `badge ${s.success ? "ok" : "bad"}`, text: s.success ? "success" : "failed" }));
    outcome.appendChild(document.createTextNode(s.success ? `seed ${s.seed}` : `${s.failure_reason} · seed ${s.seed}`));
  }
  app.appendChild(outcome);
  const cards = el("div", { class: "cards" });
  const card = (k, v) => cards.appendChild(el("div", { class: "card" }, [el("div", { class: "k", text: k }), el("div", { class: "v", text: v })]));
  card(data.truthless ? "replayed" : "simulated", `${fmt(s.sim_time_s, 2)} s`);
  if (!data.truthless) {
    card("tracking RMSE", `${fmt(s.tracking_rmse_m)} m`);
    card("max error", `${fmt(s.max_position_error_m)} m`);
    card("max spin", `${fmt(s.max_spin_rad_s, 2)} rad/s`);
    card("min altitude", `${fmt(s.min_altitude_m, 2)} m`);
  }
  for (const f of s.faults || []) card(`fault rotor ${f.rotor}`, `${f.kind} @ ${fmt(f.onset_s, 2)} s`);
  if (s.fdd) {
    card("FDD", s.fdd.detected ? `rotor ${s.fdd.rotor} ${s.fdd.kind} @ ${fmt(s.fdd.detection_s, 3)} s` : "no detection");
    if (s.fdd.latency_s !== null && s.fdd.latency_s !== undefined) card("FDD latency", `${fmt(1000 * s.fdd.latency_s, 1)} ms`);
  }
  if (s.tilt_recovery_s !== null && s.tilt_recovery_s !== undefined) card("tilt recovered", `${fmt(s.tilt_recovery_s, 2)} s`);
  if (s.navigation) card("waypoints", `${s.navigation.waypoints_reached} / ${s.navigation.waypoints_total}`);
  if (s.map_voxels_occupied !== null && s.map_voxels_occupied !== undefined) card("map voxels", String(s.map_voxels_occupied));
  if (s.supervisor && s.supervisor.transitions.length > 0) card("flight mode at the end", s.supervisor.final_mode.replace("_", " "));
  if (s.odometry) {
    if (!data.truthless) {
      card("estimate RMSE", `${fmt(s.estimate_position_rmse_m)} m`);
      card("estimate max error", `${fmt(s.estimate_position_max_m)} m · ${fmt((s.estimate_attitude_max_rad * 180) / Math.PI, 2)}°`);
    }
    card("LIO frames", `${s.odometry.frames_used} / ${s.odometry.frames} used · ${s.odometry.frames_degenerate} degenerate`);
  }
  card("real-time factor", `${fmt(s.realtime_factor, 0)}×`);
  if (data.truthless && s.replay && s.replay.compared > 0) {
    card("replay vs recording", `${fmt(s.replay.position_max_diff_m)} m over ${s.replay.compared} cycles`);
  }
  app.appendChild(cards);
}

/** The replay's clock: the time every view shows, with listeners. */
function makeClock(t0, t1) {
  let t = t0;
  const listeners = [];
  return {
    t0,
    t1,
    time: () => t,
    set(value) {
      t = Math.min(t1, Math.max(t0, value));
      for (const fn of listeners) fn(t);
    },
    onChange(fn) {
      listeners.push(fn);
    },
  };
}

function replaySection(app, data, clock) {
  app.appendChild(el("h2", { text: "Replay" }));
  const viewport = el("div", { class: "viewport", id: "replay-viewport" });
  const side = el("div", { class: "side", id: "replay-state" });
  app.appendChild(el("div", { class: "replay" }, [viewport, side]));

  const play = el("button", { id: "play", text: "▶ play" });
  const slider = el("input", { id: "time-slider", type: "range", min: String(clock.t0), max: String(clock.t1), step: "0.01", value: String(clock.t0) });
  const label = el("span", { class: "time", id: "time-label" });
  const speed = el("select", { id: "speed" });
  for (const v of [0.25, 0.5, 1, 2, 4, 8]) {
    const o = el("option", { value: String(v), text: `${v}×` });
    if (v === 1) o.selected = true;
    speed.appendChild(o);
  }
  const follow = el("input", { type: "checkbox", id: "follow" });
  follow.checked = true;
  const showMap = el("input", { type: "checkbox", id: "show-map" });
  showMap.checked = true;
  const controls = el("div", { class: "controls" }, [play, slider, label, speed,
    el("label", {}, [follow, document.createTextNode(" follow")]),
    el("label", {}, [showMap, document.createTextNode(" map")])]);
  app.appendChild(controls);
  const legend = el("div", { class: "legend note" });
  legend.innerHTML =
    '<span><i style="background:#d62728"></i>${data.truthless ? "estimate" : "flown"}</span><span><i style="background:#1f77b4"></i>reference</span>' +
    '<span><i style="background:#00a0e0"></i>plan</span><span><i style="background:#4060c0"></i>LiDAR map</span>' +
    '<span><i style="background:#2ca02c"></i>rotor healthy</span><span><i style="background:#d62728"></i>rotor failed (injected)</span>' +
    '<span><i style="background:#ff7f0e"></i>ring: FDD diagnosis</span> · drag to orbit, wheel to zoom';
  app.appendChild(legend);

  const replay = new Replay(viewport, data);
  const s = data.series;
  const n = rotorCount(s);
  const update = (t) => {
    slider.value = String(t);
    label.textContent = `t = ${t.toFixed(2)} / ${clock.t1.toFixed(2)} s`;
    replay.setTime(t);
    const i = indexAt(s.t, t);
    const [roll, pitch] = eulerFromQuaternion(s.q_w[i], s.q_x[i], s.q_y[i], s.q_z[i]);
    const err = Math.hypot(s.p_x[i] - s.ref_p_x[i], s.p_y[i] - s.ref_p_y[i], s.p_z[i] - s.ref_p_z[i]);
    let rows = `<tr><td>position</td><td class="num">${fmt(s.p_x[i], 2)}, ${fmt(s.p_y[i], 2)}, ${fmt(s.p_z[i], 2)} m</td></tr>`;
    rows += `<tr><td>error</td><td class="num">${fmt(err)} m</td></tr>`;
    rows += `<tr><td>roll / pitch</td><td class="num">${fmt((roll * 180) / Math.PI, 1)}° / ${fmt((pitch * 180) / Math.PI, 1)}°</td></tr>`;
    rows += `<tr><td>yaw rate</td><td class="num">${fmt(s.w_z[i], 2)} rad/s</td></tr>`;
    for (let r = 0; r < n; r += 1) {
      if (data.truthless) {
        rows += `<tr><td>rotor ${r}</td><td class="num">${fmt(s[`cmd_${r}`][i], 2)} N commanded</td></tr>`;
        continue;
      }
      const fault = s[`fault_${r}`][i] > 0 ? " ✗" : "";
      rows += `<tr><td>rotor ${r}${fault}</td><td class="num">${fmt(s[`thrust_${r}`][i], 2)} N · ${fmt(s[`rpm_${r}`][i], 0)} rpm</td></tr>`;
    }
    if (s.mi_0) {
      const names = ["ok", "motor failed", "propeller failed", "degraded", "failed"];
      rows += `<tr><td colspan="2"><b>FDD</b></td></tr>`;
      for (let r = 0; r < n; r += 1) {
        rows += `<tr><td>M_${r} · P_${r}</td><td class="num">${fixed2(s[`mi_${r}`][i])} · ${fixed2(s[`pi_${r}`][i])} · ${names[s[`health_${r}`][i]] ?? "?"}</td></tr>`;
      }
    }
    if (s.nmpc_ms) rows += `<tr><td>NMPC solve</td><td class="num">${fmt(s.nmpc_ms[i], 2)} ms</td></tr>`;
    if (s.lio_matched) {
      const state = s.lio_used[i] ? (s.lio_degenerate[i] ? " · degenerate" : "") : " · not used";
      if (!data.truthless) rows += `<tr><td>estimate error</td><td class="num">${fmt(estimateError(s, i))} m</td></tr>`;
      rows += `<tr><td>LIO frame</td><td class="num">${fmt(s.lio_matched[i], 0)} matched${state}</td></tr>`;
    }
    side.innerHTML = `<table>${rows}</table>`;
  };
  clock.onChange(update);
  slider.addEventListener("input", () => clock.set(Number(slider.value)));
  showMap.addEventListener("change", () => replay.setMapVisible(showMap.checked));
  follow.addEventListener("change", () => {
    replay.follow = follow.checked;
    replay.setTime(clock.time());
  });

  let playing = false;
  let last = 0;
  const step = (now) => {
    if (!playing) return;
    const dt = Math.min(0.1, (now - last) / 1000);
    last = now;
    const next = clock.time() + dt * Number(speed.value);
    clock.set(next >= clock.t1 ? clock.t1 : next);
    if (next >= clock.t1) {
      playing = false;
      play.textContent = "▶ play";
      return;
    }
    requestAnimationFrame(step);
  };
  play.addEventListener("click", () => {
    playing = !playing;
    play.textContent = playing ? "❚❚ pause" : "▶ play";
    if (playing) {
      if (clock.time() >= clock.t1) clock.set(clock.t0);
      last = performance.now();
      requestAnimationFrame(step);
    }
  });
  update(clock.time());
  return replay;
}

function plotsSection(app, data, clock) {
  const s = data.series;
  const t = s.t;
  const n = rotorCount(s);
  const summary = data.summary;
  const markers = [];
  for (const f of summary.faults || []) markers.push({ t: f.onset_s, color: "#d62728", label: `fault r${f.rotor}` });
  if (summary.fdd && summary.fdd.detected) markers.push({ t: summary.fdd.detection_s, color: "#ff7f0e", label: "detected" });
  for (const m of (summary.supervisor && summary.supervisor.transitions) || []) {
    if (m.to === "emergency_landing" || m.to === "landed" || m.to === "flight_termination") {
      markers.push({ t: m.t, color: "#7f3fbf", label: m.to.replace("_", " ") });
    }
  }

  app.appendChild(el("h2", { text: "Rotors (paper 000, Fig. 7)" }));
  const rotorPlots = el("div", { class: "plots" });
  app.appendChild(rotorPlots);
  for (let r = 0; r < n; r += 1) {
    const series = [{ label: "commanded", values: s[`cmd_${r}`], color: "#1f77b4", dash: [5, 3] }];
    if (!data.truthless) series.push({ label: "actual", values: s[`thrust_${r}`], color: "#d62728" });
    makePlot(rotorPlots, {
      title: `Rotor ${r}: ${data.truthless ? "commanded thrust" : "commanded vs actual thrust"}`, x: t, yLabel: "thrust [N]",
      markers, height: 180, series,
    }, clock);
  }
  // Commanded speeds from the commanded thrusts (T = k_n w^2), dashed beside the actual ones.
  const kn = data.scene.vehicle.thrust_coefficient_n_s2;
  const rpmSeries = [];
  for (let r = 0; r < n; r += 1) {
    if (!data.truthless) rpmSeries.push({ label: `rotor ${r}`, values: s[`rpm_${r}`], color: color(r) });
    if (kn > 0) {
      const commanded = s[`cmd_${r}`].map((c) => (Math.sqrt(Math.max(0, c) / kn) * 60) / (2 * Math.PI));
      rpmSeries.push({ label: `rotor ${r} commanded`, values: commanded, color: color(r), dash: [5, 3], width: 1 });
    }
  }
  makePlot(rotorPlots, { title: data.truthless ? "Rotor speeds: commanded" : "Rotor speeds: actual and commanded", x: t, yLabel: "rpm", markers, series: rpmSeries }, clock);

  if (s.mi_0) {
    const fdd = summary.composite_fdd || {};
    app.appendChild(el("h2", { text: "Fault detection (paper 000, Sec. V-B)" }));
    const fddPlots = el("div", { class: "plots" });
    app.appendChild(fddPlots);
    makePlot(fddPlots, {
      title: "Motor index M_i (eq. 13)", x: t, yLabel: "M_i", markers,
      thresholds: fdd.motor_index_threshold !== undefined ? [{ y: fdd.motor_index_threshold, color: "#555", label: "γ_M" }] : [],
      series: Array.from({ length: n }, (_, r) => ({ label: `M_${r}`, values: s[`mi_${r}`], color: color(r) })),
    }, clock);
    makePlot(fddPlots, {
      title: "Propeller index P_i (eq. 17)", x: t, yLabel: "P_i", markers,
      thresholds: fdd.propeller_index_threshold !== undefined ? [{ y: fdd.propeller_index_threshold, color: "#555", label: "γ_P" }] : [],
      series: Array.from({ length: n }, (_, r) => ({ label: `P_${r}`, values: s[`pi_${r}`], color: color(r) })),
    }, clock);
  }

  app.appendChild(el("h2", { text: "Tracking (paper 000, Fig. 10)" }));
  const trackPlots = el("div", { class: "plots" });
  app.appendChild(trackPlots);
  for (const axis of ["x", "y", "z"]) {
    makePlot(trackPlots, {
      title: `Position ${axis}`, x: t, yLabel: `${axis} [m]`, markers,
      series: [
        { label: "reference", values: s[`ref_p_${axis}`], color: "#1f77b4", dash: [5, 3] },
        { label: data.truthless ? "estimate" : "flown", values: s[`p_${axis}`], color: "#d62728" },
      ],
    }, clock);
  }
  const euler = t.map((_, i) => eulerFromQuaternion(s.q_w[i], s.q_x[i], s.q_y[i], s.q_z[i]));
  const deg = 180 / Math.PI;
  makePlot(trackPlots, {
    title: "Attitude: roll and pitch", x: t, yLabel: "deg", markers,
    series: [
      { label: "roll", values: euler.map((e) => e[0] * deg), color: color(0) },
      { label: "pitch", values: euler.map((e) => e[1] * deg), color: color(1) },
    ],
  }, clock);
  makePlot(trackPlots, {
    title: "Yaw (unwrapped) against the reference heading", x: t, yLabel: "rad", markers,
    series: [
      { label: "reference yaw", values: s.ref_yaw, color: "#1f77b4", dash: [5, 3] },
      { label: "yaw", values: unwrap(euler.map((e) => e[2])), color: "#d62728" },
    ],
  }, clock);
  makePlot(trackPlots, {
    title: "Yaw rate", x: t, yLabel: "rad/s", markers,
    series: [{ label: "r (body z rate)", values: s.w_z, color: "#9467bd" }],
  }, clock);
  makePlot(trackPlots, {
    title: "Tracking error |p − p_ref|", x: t, yLabel: "m", markers,
    series: [{ label: "error", values: t.map((_, i) => Math.hypot(s.p_x[i] - s.ref_p_x[i], s.p_y[i] - s.ref_p_y[i], s.p_z[i] - s.ref_p_z[i])), color: "#d62728" }],
  }, clock);
  if (s.nmpc_ms) {
    makePlot(trackPlots, {
      title: "NMPC solve time", x: t, yLabel: "ms", markers,
      series: [{ label: "solve", values: s.nmpc_ms, color: "#2ca02c" }],
    }, clock);
  }
  if (s.lio_matched && s.est_p_x) localisationSection(app, data, clock, markers);
}

/** |p_est − p| at row i of the series [m]: the stack's position estimate against the truth. */
function estimateError(s, i) {
  return Math.hypot(s.est_p_x[i] - s.p_x[i], s.est_p_y[i] - s.p_y[i], s.est_p_z[i] - s.p_z[i]);
}

/**
 * Angle [rad] of the rotation between two quaternions (w, x, y, z): 2 atan2(|v|, |w|) of
 * conj(a) b. Not 2 acos |a · b|: near 1 the arc cosine turns the 4-decimal rounding of the
 * report's data (1e-4 in the dot product) into a degree and a half of error.
 */
function quaternionAngle(a, b) {
  const [aw, ax, ay, az] = a;
  const [bw, bx, by, bz] = b;
  const w = aw * bw + ax * bx + ay * by + az * bz;
  const x = aw * bx - ax * bw - ay * bz + az * by;
  const y = aw * by + ax * bz - ay * bw - az * bx;
  const z = aw * bz - ax * by + ay * bx - az * bw;
  return 2 * Math.atan2(Math.hypot(x, y, z), Math.abs(w));
}

/**
 * The LiDAR-inertial odometry (the log's lio_* columns, written only when it was the stack's
 * estimator): its estimate against the truth (when there is one), and each frame's health as the
 * filter judged it.
 */
function localisationSection(app, data, clock, markers) {
  const o = data.summary.odometry || {};
  app.appendChild(el("h2", { text: "Localisation (LiDAR-inertial odometry)" }));
  if (data.summary.odometry) {
    const ms = o.frame_ms_mean !== undefined ? ` · ${fmt(o.frame_ms_mean, 2)} ms per frame (p99 ${fmt(o.frame_ms_p99, 2)})` : "";
    app.appendChild(el("div", {
      class: "note",
      text: `${o.frames} frames, ${o.frames_used} registered, ${o.frames_degenerate} degenerate · ` +
        `${fmt(o.matched_mean, 0)} of ${fmt(o.points_mean, 0)} points matched per frame (mean) · ` +
        `residual RMS ${fmt(1000 * o.residual_rms_m_mean, 1)} mm (mean)${ms} · ${o.map_points} map points at the end`,
    }));
  }
  const plots = el("div", { class: "plots" });
  app.appendChild(plots);
  if (!data.truthless) estimateAgainstTruth(plots, data, clock, markers);
  lioHealth(plots, data, clock, markers);
}

/** The estimate against the truth: position per axis, position and attitude errors. */
function estimateAgainstTruth(plots, data, clock, markers) {
  const s = data.series;
  const t = s.t;
  for (const axis of ["x", "y", "z"]) {
    makePlot(plots, {
      title: `Estimate vs truth: ${axis}`, x: t, yLabel: `${axis} [m]`, markers,
      series: [
        { label: "estimate", values: s[`est_p_${axis}`], color: "#1f77b4", dash: [5, 3] },
        { label: "truth", values: s[`p_${axis}`], color: "#d62728" },
      ],
    }, clock);
  }
  makePlot(plots, {
    title: "Estimate error: position |p_est − p|", x: t, yLabel: "m", markers,
    series: [{
      label: "position error",
      values: t.map((_, i) => estimateError(s, i)),
      color: "#d62728",
    }],
  }, clock);
  const deg = 180 / Math.PI;
  makePlot(plots, {
    title: "Estimate error: attitude angle", x: t, yLabel: "deg", markers,
    series: [{
      label: "attitude error",
      values: t.map((_, i) => deg * quaternionAngle([s.q_w[i], s.q_x[i], s.q_y[i], s.q_z[i]],
        [s.est_q_w[i], s.est_q_x[i], s.est_q_y[i], s.est_q_z[i]])),
      color: "#9467bd",
    }],
  }, clock);
}

/** Each frame's health as the filter judged it. */
function lioHealth(plots, data, clock, markers) {
  const s = data.series;
  const t = s.t;
  const o = data.summary.odometry || {};
  // The frames the filter did not take (the first, which starts the map, and those with too few
  // matches) and those it took with a direction left unconstrained, as dots on their values.
  const only = (flag, values, want) => values.map((v, i) => (flag[i] === want ? v : null));
  makePlot(plots, {
    title: "LiDAR odometry: matched points per frame", x: t, yLabel: "points", markers,
    series: [
      { label: "matched", values: s.lio_matched, color: "#2ca02c" },
      { label: "not used", values: only(s.lio_used, s.lio_matched, 0), color: "#7f7f7f", pointsOnly: true },
    ],
  }, clock);
  makePlot(plots, {
    title: "LiDAR odometry: point-to-plane residual RMS", x: t, yLabel: "m", markers,
    series: [{ label: "residual RMS", values: s.lio_residual_rms_m, color: "#ff7f0e" }],
  }, clock);
  // Log scale: a well-constrained frame's std is millimetres, an unconstrained one's is capped
  // at 100 m in the log; 0 (no frame registered yet) is left out.
  const weakest = s.lio_weakest_std_m.map((v) => (v > 0 ? v : null));
  const threshold = o.degenerate_std_m;
  makePlot(plots, {
    title: `LiDAR odometry: position std along the weakest direction${threshold !== undefined ? ` (degenerate above ${threshold} m, dashed)` : ""}`,
    x: t, yLabel: "m (log)", markers, yLog: true,
    thresholds: threshold !== undefined ? [{ y: threshold, color: "#555", label: "degenerate" }] : [],
    series: [
      { label: "weakest std", values: weakest, color: "#1f77b4" },
      { label: "degenerate", values: only(s.lio_degenerate, weakest, 1), color: "#d62728", pointsOnly: true },
    ],
  }, clock);
}

/**
 * A flight without a truth (a replayed bag: its log has the stack's estimate, not the simulator's
 * state): the vehicle is drawn, and the tracking plotted, at the estimate, and said to be.
 */
function withoutTruth(data) {
  const s = data.series;
  if ("p_x" in s || !("est_p_x" in s)) return data;
  const view = { ...s };
  for (const c of ["p_x", "p_y", "p_z", "q_w", "q_x", "q_y", "q_z", "v_x", "v_y", "v_z", "w_x", "w_y", "w_z"]) view[c] = s[`est_${c}`];
  return { ...data, series: view, truthless: true };
}

export function renderFlight(app, input) {
  const data = withoutTruth(input);
  const t = data.series.t;
  const clock = makeClock(t[0], t[t.length - 1]);
  header(app, data);
  const replay = replaySection(app, data, clock);
  plotsSection(app, data, clock);
  clock.set(clock.t0);
  return {
    kind: "flight",
    time: () => clock.time(),
    setTime: (value) => clock.set(value),
    /** The vehicle's position as drawn (for tests). */
    vehiclePosition: () => replay.vehicle.position.toArray(),
    duration: () => clock.t1 - clock.t0,
  };
}
