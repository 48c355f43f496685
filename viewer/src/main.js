// Entry point of the report page: reads the JSON the report writer inlined and lays out a flight
// (header, 3D replay, plots) or a benchmark (tables and distributions).
import uplotCss from "uplot/dist/uPlot.min.css";
import viewerCss from "./style.css";
import { renderFlight } from "./flight.js";
import { renderBench } from "./bench.js";

function injectCss(text) {
  const style = document.createElement("style");
  style.textContent = text;
  document.head.appendChild(style);
}

function start() {
  injectCss(uplotCss);
  injectCss(viewerCss);
  const app = document.getElementById("app");
  const element = document.getElementById("rotorguard-data");
  if (!app || !element) throw new Error("report page without #app or #rotorguard-data");
  const data = JSON.parse(element.textContent);
  if (data.kind === "flight") {
    window.rotorguardReport = renderFlight(app, data);
  } else if (data.kind === "bench") {
    window.rotorguardReport = renderBench(app, data);
  } else {
    throw new Error(`unknown report kind '${data.kind}'`);
  }
  // Milliseconds from the start of navigation until the page is drawn (bench/report_open.mjs).
  window.rotorguardReport.readyMs = performance.now();
  window.rotorguardReport.ready = true;
}

if (document.readyState === "loading") {
  document.addEventListener("DOMContentLoaded", start);
} else {
  start();
}
