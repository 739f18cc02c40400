// gyrochar live page: draws what the decoder pushes on /events (one JSON snapshot per refresh:
// host_tools/decode/live_feed.hpp). The plots are Chart.js (/chart.js: Debian's libjs-chart.js,
// compiled into the decoder at build time); nothing is fetched from elsewhere.
// Every value shown comes from the snapshot; the tau table's cells carry the exact number in
// data-value, so a test can compare the page with the decoder's CSV.
"use strict";

const TERM_COLOURS = { Q: "#9467bd", N: "#2ca02c", B: "#d62728", K: "#17becf", R: "#bcbd22" };
// The model's lines as the PNG/SVG plot draws them: the fit solid, each term dashed in its colour,
// Markov terms dotted, the simulated gyro's true model in long dashes.
const LINE_STYLES = {
  model: { borderColor: "#000", borderWidth: 2 },
  truth: { borderColor: "#777", borderWidth: 2, borderDash: [10, 4] },
  markov: { borderColor: "#8c564b", borderWidth: 2, borderDash: [1, 3] },
};
Chart.defaults.font.family = "system-ui, sans-serif";
Chart.defaults.font.size = 11;
Chart.defaults.color = "#222";

function make(tag, attrs, text) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) if (v !== undefined && v !== null) e.setAttribute(k, v);
  if (text !== undefined && text !== null) e.textContent = String(text);
  return e;
}
const add = (parent, child) => (parent.appendChild(child), child);
const exp = (v, digits = 4) => (typeof v === "number" && isFinite(v) ? v.toExponential(digits) : "-");
const short = (v) => (typeof v === "number" && isFinite(v) ? Number(v.toPrecision(4)).toString() : "-");

// The charts live from one snapshot to the next (key: node and plot), updated in place; render()
// destroys those it did not use (a node gone, a heat map with no window yet).
const charts = new Map();
let chartsUsed = new Set();
function chart(key, width, height, label, config) {
  chartsUsed.add(key);
  config.options = Object.assign({ responsive: false, animation: false }, config.options);
  let c = charts.get(key);
  if (c) {
    c.data = config.data;
    c.options = config.options;
    c.update();
  } else {
    c = new Chart(make("canvas", { width, height, role: "img" }), config);
    charts.set(key, c);
  }
  c.canvas.setAttribute("aria-label", label);
  return c.canvas;
}

// A log axis labelled at each decade (1eN), and at 2 and 5 between them when it spans under two.
function logTicks(title) {
  return { type: "logarithmic", title: { display: true, text: title }, ticks: { autoSkip: false, maxRotation: 0, callback(value) {
    const d = Math.floor(Math.log10(value) + 1e-9), m = value / 10 ** d;
    if (Math.abs(m - Math.round(m)) > 1e-6) return "";
    return m < 1.5 || ((Math.round(m) === 2 || Math.round(m) === 5) && this.max / this.min < 100) ? `${Math.round(m)}e${d}` : "";
  } } };
}

// ---------------------------------------------------------------------------------------------
// Log-log plot of ADEV and MDEV with their intervals, the model's lines and the truth's.

// Each point's confidence interval as a bar with caps: one line dataset running from the point's
// low to its high, broken (null) before the next point's.
const intervalBars = (points) => points.filter((p) => p.low > 0 && p.high > 0)
  .flatMap((p) => [{ x: p.tau, y: p.low }, { x: p.tau, y: p.high }, { x: p.tau, y: null }]);

function devChart(node, level) {
  const plot = node.plot;
  const points = (key) => node.rows.filter((r) => r[key].status === "ok" && r.tau_s > 0)
    .map((r) => ({ tau: r.tau_s, dev: r[key].value, low: r[key].low, high: r[key].high }));
  const datasets = [];  // drawn last to first: the points on top
  for (const [key, label, colour, style] of [["adev", "ADEV", "#1f77b4", "circle"], ["mdev", "MDEV", "#ff7f0e", "rect"]]) {
    const pts = points(key);
    datasets.push({ label, data: pts.map((p) => ({ x: p.tau, y: p.dev })), pointStyle: style, pointRadius: 3,
      borderColor: colour, backgroundColor: colour });
    datasets.push({ label: `${label} ${short(100 * level)} % interval`, interval: true, data: intervalBars(pts),
      showLine: true, borderColor: colour, borderWidth: 1.2, pointStyle: "line", pointRadius: 3 });
  }
  datasets.push({ label: "read-off points", data: plot.read_offs.filter((r) => r.dev > 0).map((r) => ({ x: r.tau_s, y: r.dev })),
    pointRadius: 5, borderColor: "#000", backgroundColor: "transparent" });
  for (const l of plot.lines) {
    const data = l.tau_s.map((t, i) => ({ x: t, y: l.dev[i] })).filter((p) => p.x > 0 && p.y > 0);
    if (data.length < 2) continue;
    const style = LINE_STYLES[l.kind] || { borderColor: TERM_COLOURS[l.kind], borderWidth: 1.5, borderDash: [4, 3] };
    datasets.push(Object.assign({ label: l.label, data, showLine: true, pointRadius: 0, pointStyle: "line" }, style));
  }
  if (!datasets.some((d) => d.data.length)) return make("p", { class: "empty" }, `${plot.title}: no values yet`);
  const x = logTicks("averaging time tau [s]");
  if (plot.tau_max_s > 0) Object.assign(x, { min: plot.tau_min_s, max: plot.tau_max_s });
  return chart(`${node.node}/dev`, 600, 460, `${plot.title}: ADEV and MDEV`, { type: "scatter", data: { datasets }, options: {
    scales: { x, y: logTicks(`deviation [${plot.rate_unit}]`) },
    // The legend: each point's symbol, each line's dash (Chart.js's own legend takes the points').
    plugins: { legend: { position: "bottom", labels: { usePointStyle: true, filter: (item) => !datasets[item.datasetIndex].interval,
      generateLabels: (c) => Chart.defaults.plugins.legend.labels.generateLabels(c)
        .map((item) => Object.assign(item, { lineDash: datasets[item.datasetIndex].borderDash || [] })) } } },
  } });
}

// ---------------------------------------------------------------------------------------------
// The dynamic Allan deviation: tau (one row per tau) against the window's time, log10 ADEV in
// colour. Each cell is a floating horizontal bar from the window's start to its end; the legend is
// the colour key.

const VIRIDIS = [[68, 1, 84], [72, 40, 120], [62, 74, 137], [49, 104, 142], [38, 130, 142], [31, 158, 137],
  [53, 183, 121], [109, 205, 89], [180, 222, 44], [253, 231, 37]];
function viridis(f) {
  const t = Math.min(1, Math.max(0, f)) * (VIRIDIS.length - 1), i = Math.min(Math.floor(t), VIRIDIS.length - 2), u = t - i;
  const c = VIRIDIS[i].map((a, k) => Math.round(a + (VIRIDIS[i + 1][k] - a) * u));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}

function heatChart(node) {
  const heat = node.plot.heat;
  const values = heat.columns.flatMap((c) => c.value).filter((v) => v > 0);
  if (values.length === 0 || heat.tau_s.length === 0) return make("p", { class: "empty" }, `${heat.title}: no window complete yet`);
  const lo = Math.log10(Math.min(...values)), hi = Math.max(Math.log10(Math.max(...values)), lo + 1e-9);
  const colour = (v) => viridis((Math.log10(v) - lo) / (hi - lo));
  const labels = heat.tau_s.map(String);
  const cells = heat.columns.flatMap((c) => c.value.map((v, i) => ({ y: labels[i], x: [c.start_s / 3600, c.end_s / 3600], v })))
    .filter((p) => p.v > 0);
  const key = [0, 1, 2, 3, 4].map((k) => ({ text: exp(10 ** (hi - ((hi - lo) * k) / 4), 1), fillStyle: viridis(1 - k / 4), lineWidth: 0 }));
  return chart(`${node.node}/heat`, 420, 460, heat.title, { type: "bar", data: { labels, datasets: [{ label: heat.title, data: cells,
    backgroundColor: (ctx) => (ctx.raw ? colour(ctx.raw.v) : "#888"), barPercentage: 1, categoryPercentage: 1 }] }, options: {
    indexAxis: "y",
    scales: {
      y: { reverse: true, grid: { display: false }, title: { display: true, text: "tau [s]" }, ticks: { callback: (i) => short(heat.tau_s[i]) } },
      x: { type: "linear", min: heat.columns[0].start_s / 3600, max: heat.columns[heat.columns.length - 1].end_s / 3600,
        title: { display: true, text: "time in the run [h]" }, ticks: { callback: short } },
    },
    plugins: {
      title: { display: true, text: heat.title },
      legend: { position: "right", onClick: null, title: { display: true, text: heat.unit }, labels: { generateLabels: () => key } },
      tooltip: { callbacks: { title: (items) => `tau ${items[0].label} s`, label: (ctx) => `${short(ctx.raw.x[0])} to ${short(ctx.raw.x[1])} h: ${exp(ctx.raw.v)} ${heat.unit}` } },
    },
  } });
}

// ---------------------------------------------------------------------------------------------
// Tables: the IEEE-952 terms, the latest report's rows.

function fitTable(node) {
  const rep = node.report, fit = rep.ieee952_fit, truth = node.truth;
  const div = make("div", { class: "fit" });
  let head = "IEEE-952 (node's fit)";
  if (fit) head = fit.status === "ok" || fit.status === "rejected"
    ? `IEEE-952 (node's fit of both curves, chi2/dof ${short(fit.chi2_per_dof)} on ${fit.points} points): ${fit.status}`
    : `IEEE-952: no fit: ${fit.status.replace(/_/g, " ")} (${fit.points} points)`;
  add(div, make("p", { class: "model", "data-fit-status": fit ? fit.status : "" }, head));
  if (fit && fit.status === "rejected") add(div, make("p", { class: "notes" }, "MODEL REJECTED: the IEEE-952 terms do not describe this curve"));
  const table = add(div, make("table", { class: "fit" }));
  const hr = add(table, make("tr"));
  for (const h of ["term", "value", "unit", "uncertainty", "status"].concat(truth ? ["simulated"] : [])) add(hr, make("th", {}, h));
  for (const letter of ["Q", "N", "B", "K", "R"]) {
    const t = rep.ieee952[letter];
    const tr = add(table, make("tr", { "data-term": letter }));
    add(tr, make("td", {}, letter));
    const status = !t ? "not received" : !t.fitted ? "not fitted" : t.resolved ? "resolved" : "not resolved";
    add(tr, make("td", { "data-value": t && t.fitted ? t.value : null, class: status === "resolved" ? "" : "not-resolved" },
      t && t.fitted ? Number(t.value.toPrecision(4)) : "-"));
    add(tr, make("td", {}, t ? t.unit : ""));
    add(tr, make("td", {}, t && t.fitted ? `±${(100 * t.rel_uncertainty).toFixed(1)}%` : ""));
    add(tr, make("td", {}, status));
    if (truth) add(tr, make("td", { "data-value": truth[letter] }, short(truth[letter])));
  }
  if (fit && fit.model) {
    const parts = [];
    for (const [j, m] of (fit.markov || []).entries())
      parts.push(`Markov ${j + 1}: sigma ${short(m.sigma.value)} ${m.sigma.unit}${m.sigma.resolved ? "" : " (not resolved)"}, Tc ${short(m.tc.value)} s`);
    if (fit.bandwidth) parts.push(`sensor filter Tf ${short(fit.bandwidth.tf.value)} s`);
    for (const [j, s] of (fit.sinusoids || []).entries()) parts.push(`sinusoid ${j + 1}: ${short(s.amplitude.value)} at ${short(s.frequency.value)} Hz`);
    add(div, make("p", { class: "model" }, `model: ${parts.length ? parts.join("; ") : "the five terms"}`));
  } else if (fit && fit.model_status && fit.model_status !== "shown") {
    add(div, make("p", { class: "model" }, `model: ${fit.model_status}`));
  }
  if (truth && truth.markov.length)
    add(div, make("p", { class: "model" }, "simulated: " + truth.markov.map((m, j) => `Markov ${j + 1} sigma ${short(m.sigma)}, Tc ${short(m.tc_s)} s`).join("; ")));
  return div;
}

function devCells(tr, node, r, key) {
  const c = r[key];
  const attrs = { class: `${key} status-${c.status}`, "data-node": node.node, "data-tau-index": r.tau_index, "data-stat": key };
  if (c.status !== "ok") { add(tr, make("td", attrs, c.status)); add(tr, make("td")); return; }
  add(tr, make("td", Object.assign(attrs, { "data-value": c.value }), exp(c.value)));
  add(tr, make("td", {}, c.low !== null ? `[${exp(c.low, 3)}, ${exp(c.high, 3)}]` : "(no EDF)"));
}

function tauTable(node, level) {
  const table = make("table", { class: "taus" });
  const hr = add(table, make("tr"));
  const ci = `${(100 * level).toFixed(1)}% CI`;
  for (const h of ["tau [s]", "n", "ADEV", ci, "MDEV", ci, "EDF MDEV", "noise"]) add(hr, make("th", {}, h));
  for (const r of node.rows) {
    const tr = add(table, make("tr", { "data-tau-index": r.tau_index }));
    add(tr, make("td", { "data-tau-s": r.tau_s }, r.tau_s !== null ? short(r.tau_s) : `#${r.tau_index}`));
    add(tr, make("td", {}, r.n !== null ? r.n : "-"));
    devCells(tr, node, r, "adev");
    devCells(tr, node, r, "mdev");
    add(tr, make("td", {}, r.mdev.edf !== null ? short(r.mdev.edf) : "-"));
    const noise = r.adev.noise === r.mdev.noise || r.mdev.noise === null ? r.adev.noise : `${r.adev.noise} / ${r.mdev.noise} (MDEV)`;
    add(tr, make("td", {}, noise || "-"));
  }
  return table;
}

// The node's verdicts under the decoder's --limits (its JSON lines "acceptance" record as of now).
function acceptanceTable(acc) {
  const div = make("div", { class: "acceptance" });
  add(div, make("p", { class: "model", "data-verdict": acc.verdict },
    `acceptance (${short(100 * acc.confidence)} % intervals; ${acc.rule}): ${acc.verdict.toUpperCase()}`));
  const table = add(div, make("table", { class: "fit" }));
  const hr = add(table, make("tr"));
  for (const h of ["limit", "estimate", "lower", "upper", "verdict", "decides at", "why"]) add(hr, make("th", {}, h));
  for (const l of acc.limits) {
    const tr = add(table, make("tr", { "data-limit": l.quantity, "data-verdict": l.verdict }));
    add(tr, make("td", {}, `${l.quantity} <= ${short(l.limit)} ${l.unit}`));
    for (const v of [l.estimate, l.lower, l.upper]) add(tr, make("td", { "data-value": v }, v === null ? "-" : short(v)));
    add(tr, make("td", { class: l.verdict === "pass" ? "" : "not-resolved" }, l.verdict));
    add(tr, make("td", {}, l.decides_at_s !== null ? `about ${duration(l.decides_at_s)}` : l.decides_never ? "never at this estimate" : "-"));
    add(tr, make("td", {}, l.why));
  }
  return div;
}

function healthText(h) {
  const rejected = Object.values(h.rejected || {}).reduce((a, b) => a + b, 0);
  return `link: frames ${h.frames}; reports ${h.reports_complete} complete, ${h.reports_incomplete} incomplete, ` +
    `${h.reports_lost} lost; frames missing ${h.frames_missing}; restarts ${h.restarts}; offline ${h.offline_events}; ` +
    `duplicates ${h.duplicates}; rejected ${rejected}`;
}

// The node's next tau to get its first estimate: the shortest whose ADEV is not yet valid. An
// overlapping ADEV at m = tau / tau0 needs 2m samples, so at the node's sample rate it comes after
// 2m less the samples so far (node time: the gyro's own clock). Null when every tau has one.
function nextTau(node) {
  const rep = node.report, tau0 = rep.metadata.tau0_s;
  const next = node.rows.find((r) => r.adev.status === "invalid" && r.tau_s > 0);
  if (!next || !(tau0 > 0) || typeof rep.sample_count !== "number") return null;
  const m = Math.round(next.tau_s / tau0);
  return { tau: next.tau_s, wait: Math.max(0, (2 * m - rep.sample_count) * tau0) };
}

function duration(s) {
  return s >= 7200 ? `${short(s / 3600)} h` : s >= 120 ? `${short(s / 60)} min` : `${short(s)} s`;
}

// ---------------------------------------------------------------------------------------------
// One node's card, redrawn at every snapshot.

function nodeCard(node, snap, now) {
  const rep = node.report, meta = rep.metadata;
  const card = make("section", { class: rep.online ? "node" : "node offline", id: `node-${node.node}`, "data-node": node.node });
  const title = add(card, make("h2", {}, `node ${node.label}  `));
  add(title, make("span", { class: rep.online ? "" : "offline-tag" }, rep.online ? "online" : "OFFLINE"));
  title.append(`  ${rep.state || "no status yet"}  session ${rep.session}  samples ${rep.sample_count}`);
  const first = node.rows.length ? node.rows[0] : null;
  const latency = node.rows_received_ms !== null ? Math.max(0, now - node.rows_received_ms) : null;
  add(card, make("p", { class: "meta report", "data-node": node.node, "data-seq": first ? first.seq : null,
    "data-time-s": first ? first.time_s : null, "data-latency-ms": latency !== null ? latency.toFixed(0) : null },
    `report seq ${first ? first.seq : "-"} at ${first ? first.time_s.toFixed(1) : "-"} s` +
    (meta.uptime_ms !== null ? `; uptime ${(meta.uptime_ms / 1000).toFixed(1)} s` : "") +
    (meta.protocol_version !== null ? `; protocol ${meta.protocol_version}` : "") +
    (meta.tau0_s !== null ? `; tau0 ${short(meta.tau0_s)} s` : "") +
    `; rates [${rep.rate_unit}]` + (latency !== null ? `; shown ${(latency / 1000).toFixed(2)} s after the report closed` : "")));
  const next = nextTau(node);
  if (next) add(card, make("p", { class: "meta next-tau", "data-node": node.node, "data-tau-s": next.tau, "data-wait-s": next.wait },
    `next tau ${short(next.tau)} s: its first estimate in about ${duration(next.wait)} of gyro time`));
  const figures = add(card, make("div", { class: "figures" }));
  add(figures, devChart(node, snap.ci_level));
  if (node.plot.heat) add(figures, heatChart(node));
  for (const n of node.plot.notes) add(card, make("p", { class: "notes" }, n));
  add(card, fitTable(node));
  if (node.acceptance) add(card, acceptanceTable(node.acceptance));
  add(card, make("p", { class: "link" }, healthText(rep.health)));
  const f = rep.faults;
  add(card, make("p", { class: "faults" }, `node faults: lost edges ${f.lost_edges}, sample gaps ${f.sample_gaps}, ` +
    `tx dropped frames ${f.tx_dropped_frames}, bus-off events ${f.bus_off_events}`));
  add(card, tauTable(node, snap.ci_level));
  return card;
}

function render(snap) {
  const now = Date.now();
  const input = snap.input;
  const elapsed = snap.elapsed_s !== null ? `${(snap.elapsed_s / 3600).toFixed(3)} h (${snap.elapsed_s.toFixed(0)} s)` : "-";
  const text = `${snap.source}: ${input.frames} frames, ${input.other_frames} other traffic, ` +
    `${input.rejected_frames} rejected` + (input.malformed_lines ? `, ${input.malformed_lines} malformed lines` : "") +
    `; elapsed ${elapsed}` + (input.bus ? `; ${input.bus}` : "");
  const inputLine = document.getElementById("input");
  inputLine.textContent = text;
  inputLine.setAttribute("data-frames", input.frames);
  inputLine.setAttribute("data-elapsed-s", snap.elapsed_s);
  const main = document.getElementById("nodes");
  chartsUsed = new Set();
  const cards = snap.nodes.map((n) => nodeCard(n, snap, now));
  if (cards.length === 0) main.replaceChildren(make("p", { class: "empty" }, "no gyrochar node seen yet"));
  else main.replaceChildren(...cards);
  for (const [key, c] of charts) if (!chartsUsed.has(key)) (c.destroy(), charts.delete(key));
}

let count = 0;  // snapshots received on the event stream
// "?updates=N" stops following after N snapshots (a headless browser's test: the page then goes idle).
const stopAfter = Number(new URLSearchParams(location.search).get("updates")) || Infinity;

function connect() {
  const status = document.getElementById("status");
  const events = new EventSource("events");
  events.onmessage = (e) => {
    const snap = JSON.parse(e.data);
    render(snap);
    ++count;
    status.setAttribute("data-state", "live");
    status.setAttribute("data-updates", count);
    status.setAttribute("data-sent-ms", snap.sent_ms);
    status.textContent = `live: ${snap.program}, ${count} updates, every ${snap.refresh_s} s`;
    if (count >= stopAfter) {
      events.close();
      status.textContent = `stopped after ${count} updates (?updates=${stopAfter}): reload to follow again`;
    }
  };
  events.onerror = () => {
    status.setAttribute("data-state", "lost");
    status.textContent = "connection lost: retrying (the values below are the last received)";
  };
}

// The latest snapshot at once, then every one as it comes.
fetch("data.json").then((r) => r.json()).then((snap) => { if (snap && count === 0) render(snap); }).catch(() => {});
connect();
