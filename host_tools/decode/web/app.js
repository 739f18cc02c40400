// gyrochar live page: draws what the decoder pushes on /events (one JSON snapshot per refresh:
// host_tools/decode/live_feed.hpp). Hand-written SVG, no library, nothing fetched from elsewhere.
// Every value shown comes from the snapshot; the tau table's cells carry the exact number in
// data-value, so a test can compare the page with the decoder's CSV.
"use strict";

const SVG = "http://www.w3.org/2000/svg";
const TERM_COLOURS = { Q: "#9467bd", N: "#2ca02c", B: "#d62728", K: "#17becf", R: "#bcbd22" };

function make(tag, attrs, text, ns) {
  const e = ns ? document.createElementNS(ns, tag) : document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) if (v !== undefined && v !== null) e.setAttribute(k, v);
  if (text !== undefined && text !== null) e.textContent = String(text);
  return e;
}
const svg = (tag, attrs, text) => make(tag, attrs, text, SVG);
const add = (parent, child) => (parent.appendChild(child), child);
const exp = (v, digits = 4) => (typeof v === "number" && isFinite(v) ? v.toExponential(digits) : "-");
const short = (v) => (typeof v === "number" && isFinite(v) ? Number(v.toPrecision(4)).toString() : "-");

// ---------------------------------------------------------------------------------------------
// Log-log plot of ADEV and MDEV with their intervals, the model's lines and the truth's.

function logRange(values) {
  const ok = values.filter((v) => typeof v === "number" && isFinite(v) && v > 0);
  if (ok.length === 0) return null;
  let lo = Math.floor(Math.log10(Math.min(...ok)) * 2) / 2, hi = Math.ceil(Math.log10(Math.max(...ok)) * 2) / 2;
  if (hi - lo < 1) { lo -= 0.5; hi += 0.5; }
  return [lo, hi];
}

function devPlot(node) {
  const W = 600, H = 380, L = 64, R = 12, T = 10, B = 40;
  const plot = node.plot, rows = node.rows;
  const points = (key) => rows.filter((r) => r[key].status === "ok" && r.tau_s > 0)
    .map((r) => ({ tau: r.tau_s, dev: r[key].value, low: r[key].low, high: r[key].high }));
  const adev = points("adev"), mdev = points("mdev");
  const taus = adev.concat(mdev).map((p) => p.tau);
  const xr = plot.tau_max_s > 0 ? [Math.log10(plot.tau_min_s), Math.log10(plot.tau_max_s)] : logRange(taus);
  const ys = [];
  for (const p of adev.concat(mdev)) ys.push(p.dev, p.low, p.high);
  for (const l of plot.lines) l.dev.forEach((d, i) => { if (l.tau_s[i] > 0) ys.push(d); });
  const yr = logRange(ys);
  const root = svg("svg", { width: W, height: H, viewBox: `0 0 ${W} ${H}`, class: "deviation", role: "img",
    "aria-label": `${plot.title}: ADEV and MDEV` });
  if (!xr || !yr) { add(root, svg("text", { x: W / 2, y: H / 2, "text-anchor": "middle" }, "no values yet")); return root; }
  const x = (tau) => L + ((Math.log10(tau) - xr[0]) / (xr[1] - xr[0])) * (W - L - R);
  const y = (dev) => T + ((yr[1] - Math.log10(dev)) / (yr[1] - yr[0])) * (H - T - B);
  const clip = `clip-${node.node}`;
  const defs = add(root, svg("defs"));
  add(add(defs, svg("clipPath", { id: clip })), svg("rect", { x: L, y: T, width: W - L - R, height: H - T - B }));
  for (let d = Math.ceil(xr[0]); d <= Math.floor(xr[1]); ++d) {
    add(root, svg("line", { class: "grid", x1: x(10 ** d), x2: x(10 ** d), y1: T, y2: H - B }));
    add(root, svg("text", { x: x(10 ** d), y: H - B + 14, "text-anchor": "middle" }, `1e${d}`));
  }
  for (let d = Math.ceil(yr[0]); d <= Math.floor(yr[1]); ++d) {
    add(root, svg("line", { class: "grid", x1: L, x2: W - R, y1: y(10 ** d), y2: y(10 ** d) }));
    add(root, svg("text", { x: L - 4, y: y(10 ** d) + 4, "text-anchor": "end" }, `1e${d}`));
  }
  add(root, svg("rect", { class: "frame", x: L, y: T, width: W - L - R, height: H - T - B }));
  add(root, svg("text", { x: (L + W - R) / 2, y: H - 6, "text-anchor": "middle" }, "averaging time tau [s]"));
  add(root, svg("text", { x: 12, y: (T + H - B) / 2, "text-anchor": "middle",
    transform: `rotate(-90 12 ${(T + H - B) / 2})` }, `deviation [${plot.rate_unit}]`));
  const inside = add(root, svg("g", { "clip-path": `url(#${clip})` }));
  for (const l of plot.lines) {
    const pts = l.tau_s.map((t, i) => [t, l.dev[i]]).filter(([t, d]) => t > 0 && d > 0);
    if (pts.length < 2) continue;
    const kind = l.kind === "model" || l.kind === "truth" || l.kind === "markov" ? l.kind : "term";
    add(inside, svg("polyline", { class: `line ${kind}`, stroke: kind === "term" ? TERM_COLOURS[l.kind] : null,
      points: pts.map(([t, d]) => `${x(t).toFixed(1)},${y(d).toFixed(1)}`).join(" ") }));
  }
  for (const r of plot.read_offs) if (r.dev > 0) add(inside, svg("circle", { class: "readoff", cx: x(r.tau_s), cy: y(r.dev), r: 5 }));
  for (const [key, pts] of [["adev", adev], ["mdev", mdev]]) {
    for (const p of pts) {
      if (p.low > 0 && p.high > 0)
        add(inside, svg("line", { class: `${key} bar`, x1: x(p.tau), x2: x(p.tau), y1: y(p.low), y2: y(p.high) }));
      if (key === "adev") add(inside, svg("circle", { class: key, cx: x(p.tau), cy: y(p.dev), r: 3 }));
      else add(inside, svg("rect", { class: key, x: x(p.tau) - 3, y: y(p.dev) - 3, width: 6, height: 6 }));
    }
  }
  return root;
}

function legend(node) {
  const ul = make("ul", { class: "legend" });
  add(ul, make("li", { class: "adev" }, "ADEV (bars: confidence interval)"));
  add(ul, make("li", { class: "mdev" }, "MDEV"));
  for (const l of node.plot.lines) add(ul, make("li", { class: l.kind }, l.label));
  return ul;
}

// ---------------------------------------------------------------------------------------------
// The dynamic Allan deviation: tau (log) against the window's time, log10 ADEV in colour.

const VIRIDIS = [[68, 1, 84], [72, 40, 120], [62, 74, 137], [49, 104, 142], [38, 130, 142], [31, 158, 137],
  [53, 183, 121], [109, 205, 89], [180, 222, 44], [253, 231, 37]];
function viridis(f) {
  const t = Math.min(1, Math.max(0, f)) * (VIRIDIS.length - 1), i = Math.min(Math.floor(t), VIRIDIS.length - 2), u = t - i;
  const c = VIRIDIS[i].map((a, k) => Math.round(a + (VIRIDIS[i + 1][k] - a) * u));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}

function heatMap(heat) {
  const W = 420, H = 380, L = 64, R = 70, T = 24, B = 40;
  const root = svg("svg", { width: W, height: H, viewBox: `0 0 ${W} ${H}`, class: "heat", role: "img", "aria-label": heat.title });
  add(root, svg("text", { x: L, y: 14 }, heat.title));
  const values = heat.columns.flatMap((c) => c.value).filter((v) => v > 0);
  if (values.length === 0 || heat.tau_s.length === 0) {
    add(root, svg("text", { x: W / 2, y: H / 2, "text-anchor": "middle" }, "no window complete yet"));
    return root;
  }
  const lo = Math.log10(Math.min(...values)), hi = Math.max(Math.log10(Math.max(...values)), lo + 1e-9);
  const t0 = heat.columns[0].start_s, t1 = heat.columns[heat.columns.length - 1].end_s;
  const n = heat.tau_s.length, cellH = (H - T - B) / n;
  const x = (t) => L + ((t - t0) / (t1 - t0 || 1)) * (W - L - R);
  for (const c of heat.columns) {
    c.value.forEach((v, i) => {
      if (!(v > 0)) return;
      add(root, svg("rect", { x: x(c.start_s), width: Math.max(1, x(c.end_s) - x(c.start_s)), y: H - B - (i + 1) * cellH,
        height: cellH, fill: viridis((Math.log10(v) - lo) / (hi - lo)) }));
    });
  }
  add(root, svg("rect", { class: "frame", x: L, y: T, width: W - L - R, height: H - T - B }));
  heat.tau_s.forEach((tau, i) => {
    if (i % Math.ceil(n / 8) === 0) add(root, svg("text", { x: L - 4, y: H - B - (i + 0.5) * cellH + 4, "text-anchor": "end" }, short(tau)));
  });
  add(root, svg("text", { x: 12, y: (T + H - B) / 2, "text-anchor": "middle", transform: `rotate(-90 12 ${(T + H - B) / 2})` }, "tau [s]"));
  add(root, svg("text", { x: L, y: H - B + 14 }, `${short(t0 / 3600)} h`));
  add(root, svg("text", { x: W - R, y: H - B + 14, "text-anchor": "end" }, `${short(t1 / 3600)} h`));
  add(root, svg("text", { x: (L + W - R) / 2, y: H - 6, "text-anchor": "middle" }, "time in the run"));
  for (let k = 0; k < 20; ++k)
    add(root, svg("rect", { x: W - R + 12, width: 14, y: T + ((19 - k) * (H - T - B)) / 20, height: (H - T - B) / 20 + 0.5, fill: viridis(k / 19) }));
  add(root, svg("text", { x: W - R + 30, y: T + 10 }, exp(10 ** hi, 1)));
  add(root, svg("text", { x: W - R + 30, y: H - B }, exp(10 ** lo, 1)));
  add(root, svg("text", { x: W - R + 8, y: H - 6 }, heat.unit));
  return root;
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
  const left = add(figures, make("div"));
  add(left, devPlot(node));
  add(left, legend(node));
  if (node.plot.heat) add(figures, heatMap(node.plot.heat));
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
  const cards = snap.nodes.map((n) => nodeCard(n, snap, now));
  if (cards.length === 0) main.replaceChildren(make("p", { class: "empty" }, "no gyrochar node seen yet"));
  else main.replaceChildren(...cards);
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
