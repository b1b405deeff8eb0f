// propid's live page: every number drawn here comes from a line the daemon published
// (GET /events: one JSON line per server-sent event, the shapes of src/daemon/line.rs and
// src/daemon/live.rs). Nothing is computed here but the layout.
"use strict";

const SPAN_S = 10;
const $ = (id) => document.getElementById(id);
const fmt = (x, p = 4) =>
  x === null || x === undefined || Number.isNaN(x) ? "—" : Number(x).toPrecision(p);
const first = (g) => (Array.isArray(g) ? g[0] : g);
const W = Math.max(900, Math.min(1400, window.innerWidth || 1300));
const HALF = Math.floor(W / 2) - 50;

// ---- charts -------------------------------------------------------------------------------

function chart(id, width, height, series, opts = {}) {
  const o = Object.assign(
    {
      width,
      height,
      scales: { x: { time: false } },
      series: [{ label: opts.xlabel || "x" }].concat(series),
      axes: opts.axes || [{ label: opts.xlabel }, { label: opts.ylabel }],
      legend: { live: false },
      cursor: { show: false },
      hooks: opts.hooks || {},
    },
    opts.extra || {}
  );
  const data = [[]].concat(series.map(() => []));
  return new uPlot(o, data, $(id));
}

const samples = { t: [], thr: [], thrust: [], torque: [], rpm: [], volt: [], amp: [], pulses: [] };
const SERIES = [["thr", "throttle"], ["thrust", "thrust_N"], ["torque", "torque_Nm"],
  ["rpm", "rpm"], ["volt", "voltage_V"], ["amp", "current_A"]];

function pulseMarks(u) {
  const ctx = u.ctx;
  ctx.save();
  ctx.strokeStyle = "rgba(200,60,160,0.45)";
  ctx.lineWidth = 1;
  const [x0, x1] = [u.scales.x.min, u.scales.x.max];
  for (const t of samples.pulses) {
    if (t < x0 || t > x1) continue;
    const x = Math.round(u.valToPos(t, "x", true));
    ctx.beginPath();
    ctx.moveTo(x, u.bbox.top);
    ctx.lineTo(x, u.bbox.top + u.bbox.height);
    ctx.stroke();
  }
  ctx.restore();
}

const cThrust = chart(
  "chart-thrust",
  W - 40,
  220,
  [
    { label: "throttle", stroke: "#888", scale: "thr" },
    { label: "thrust N", stroke: "#1f77b4", scale: "N" },
  ],
  {
    xlabel: "device time s",
    axes: [{ label: "device time s" }, { scale: "N", label: "thrust N" },
      { scale: "thr", side: 1, label: "throttle", grid: { show: false } }],
    hooks: { draw: [pulseMarks] },
  }
);
const cOther = chart(
  "chart-other",
  W - 40,
  180,
  [
    { label: "torque N·m", stroke: "#2ca02c", scale: "Nm" },
    { label: "rpm", stroke: "#d62728", scale: "rpm" },
  ],
  {
    axes: [{ label: "device time s" }, { scale: "Nm", label: "torque N·m" },
      { scale: "rpm", side: 1, label: "rpm", grid: { show: false } }],
    hooks: { draw: [pulseMarks] },
  }
);
const cPower = chart(
  "chart-power",
  W - 40,
  160,
  [
    { label: "voltage V", stroke: "#8c564b", scale: "V" },
    { label: "current A", stroke: "#e377c2", scale: "A" },
  ],
  {
    axes: [{ label: "device time s" }, { scale: "V", label: "voltage V" },
      { scale: "A", side: 1, label: "current A", grid: { show: false } }],
    hooks: { draw: [pulseMarks] },
  }
);
const cResp = chart(
  "chart-response",
  HALF,
  260,
  [
    { label: "mean", stroke: "#1f77b4", width: 2 },
    { label: "mean + sd", stroke: "#9ecae1", dash: [4, 3] },
    { label: "mean − sd", stroke: "#9ecae1", dash: [4, 3] },
    { label: "model", stroke: "#d62728", width: 2 },
  ],
  { xlabel: "ms after the pulse start", ylabel: "per unit throttle" }
);

// bars drawn by hand stay inside the plot area
function clipToPlot(u) {
  const b = u.bbox;
  u.ctx.beginPath();
  u.ctx.rect(b.left, b.top, b.width, b.height);
  u.ctx.clip();
}

// schedule charts: value vs throttle with ± sd bars
const sched = { rows: [] };
function errorBars(key) {
  return (u) => {
    const ctx = u.ctx;
    ctx.save();
    clipToPlot(u);
    ctx.strokeStyle = "#444";
    for (const r of sched.rows) {
      const v = key === "dc_gain" ? first(r.dc_gain) : r[key];
      const sd = first(r.uncertainty ? r.uncertainty[key] : null);
      if (v === null || sd === null || sd === undefined) continue;
      const x = u.valToPos(r.operating_point, "x", true);
      const y0 = u.valToPos(v - sd, "y", true);
      const y1 = u.valToPos(v + sd, "y", true);
      ctx.beginPath();
      ctx.moveTo(x, y0); ctx.lineTo(x, y1);
      ctx.moveTo(x - 4, y0); ctx.lineTo(x + 4, y0);
      ctx.moveTo(x - 4, y1); ctx.lineTo(x + 4, y1);
      ctx.stroke();
    }
    ctx.restore();
  };
}
const SW = Math.floor((W - 60) / 4);
const pts = { show: true, size: 7 };
const withPad = { scales: { x: { time: false, range: (u, lo, hi) => [lo - 0.05, hi + 0.05] } } };
// the simulator's truth (propid demo's "truth" line), drawn as markers
const truthPts = { label: "truth", stroke: "#d62728", paths: () => null,
  points: { show: true, size: 9, width: 2, fill: "#fff" } };
const fitPts = { label: "exact linear fit", stroke: "#ff7f0e", paths: () => null,
  points: { show: true, size: 7, fill: "#fff" } };
const hide = { show: false };
function tauBars(u) {
  // the truth's τ between spin-up and spin-down, at each level
  const ctx = u.ctx;
  ctx.save();
  clipToPlot(u);
  ctx.strokeStyle = "#d62728";
  ctx.lineWidth = 2;
  for (const r of sched.rows) {
    const t = truthAt(r.operating_point);
    if (!t || t.tau_up_s === undefined) continue;
    const x = u.valToPos(r.operating_point, "x", true);
    const y0 = u.valToPos(t.tau_up_s, "y", true), y1 = u.valToPos(t.tau_down_s, "y", true);
    ctx.beginPath();
    ctx.moveTo(x + 6, y0); ctx.lineTo(x + 6, y1);
    ctx.moveTo(x + 2, y0); ctx.lineTo(x + 10, y0);
    ctx.moveTo(x + 2, y1); ctx.lineTo(x + 10, y1);
    ctx.stroke();
  }
  ctx.restore();
}
const cGain = chart("chart-gain", SW, 220, [{ label: "DC gain", stroke: "#2ca02c", width: 2, points: pts }, truthPts, fitPts],
  { xlabel: "throttle", ylabel: "DC gain", hooks: { draw: [errorBars("dc_gain")] }, extra: withPad });
const cTau = chart("chart-tau", SW, 220, [{ label: "τ s", stroke: "#9467bd", width: 2, points: pts },
  Object.assign({}, truthPts, { label: "truth up", points: hide }), Object.assign({}, truthPts, { label: "truth down", points: hide }), fitPts],
  { xlabel: "throttle", ylabel: "τ s (longest)", hooks: { draw: [tauBars] }, extra: withPad });
const cFn = chart("chart-fn", SW, 220, [{ label: "fn Hz", stroke: "#1f77b4", points: pts }, truthPts],
  { xlabel: "throttle", ylabel: "fn Hz", hooks: { draw: [errorBars("fn_hz")] }, extra: withPad });
const cZeta = chart("chart-zeta", SW, 220, [{ label: "ζ", stroke: "#ff7f0e", points: pts }, truthPts],
  { xlabel: "throttle", ylabel: "ζ", hooks: { draw: [errorBars("zeta")] }, extra: withPad });

// stabilization: frequency vs order, stable poles filled
const stab = { modelFn: null };
const cStab = chart(
  "chart-stab",
  HALF,
  260,
  [
    { label: "stable", stroke: "#2ca02c", fill: "#2ca02c", paths: () => null,
      points: { show: true, size: 8, fill: "#2ca02c" } },
    { label: "not stable", stroke: "#999", paths: () => null,
      points: { show: true, size: 7, fill: "#fff" } },
  ],
  {
    xlabel: "fn Hz", ylabel: "order",
    hooks: {
      draw: [(u) => {
        if (stab.modelFn === null) return;
        const ctx = u.ctx, x = u.valToPos(stab.modelFn, "x", true);
        ctx.save(); ctx.strokeStyle = "rgba(214,39,40,0.5)"; ctx.setLineDash([5, 4]);
        ctx.beginPath(); ctx.moveTo(x, u.bbox.top); ctx.lineTo(x, u.bbox.top + u.bbox.height);
        ctx.stroke(); ctx.restore();
      }],
    },
  }
);
const cSv = chart("chart-sv", HALF, 220,
  [{ label: "σ", stroke: "#1f77b4", points: pts }],
  { xlabel: "index", ylabel: "σ", extra: { scales: { x: { time: false }, y: { distr: 3 } } } });

// ---- lines ----------------------------------------------------------------------------------

function onSamples(l) {
  const s = samples;
  const n = l.t_s.length;
  s.t.push(...l.t_s); s.pulses.push(...l.pulses);
  for (const [k, key] of SERIES) {
    // a line without the channel (an older daemon): no values
    const v = Array.isArray(l[key]) ? l[key] : new Array(n).fill(null);
    s[k].push(...v);
    const dd = $("now-" + key);
    const last = v.length ? v[v.length - 1] : null;
    dd.dataset.value = String(last);
    dd.textContent = fmt(last, 4);
  }
  const tmax = s.t[s.t.length - 1];
  let cut = 0;
  while (cut < s.t.length && s.t[cut] < tmax - SPAN_S) cut++;
  if (cut > 0) for (const k of ["t"].concat(SERIES.map((x) => x[0]))) s[k].splice(0, cut);
  s.pulses = s.pulses.filter((t) => t >= tmax - SPAN_S);
  dirty.samples = true;
  if ($("link").dataset.state === "waiting") setLink("receiving");
}

function setDd(key, value, text) {
  const dd = $("model-" + key);
  dd.dataset.value = Array.isArray(value) ? value.map(String).join(",") : String(value);
  dd.textContent = text;
}

function onModel(m) {
  $("model").dataset.t_s = String(m.t_s);
  setDd("t_s", m.t_s, fmt(m.t_s, 5) + " s");
  setDd("operating_point", m.operating_point, fmt(m.operating_point, 3) + " (level " + m.level + ")");
  setDd("order", m.order, String(m.order));
  const u = m.uncertainty || {};
  const pm = (v, sd) => fmt(v) + (sd === null || sd === undefined ? "" : " ± " + fmt(sd, 2));
  setDd("fn_hz", m.fn_hz, pm(m.fn_hz, u.fn_hz));
  setDd("zeta", m.zeta, pm(m.zeta, u.zeta));
  setDd("dc_gain", m.dc_gain, pm(first(m.dc_gain), first(u.dc_gain)));
  setDd("time_constants_s", m.time_constants_s, (m.time_constants_s || []).map((x) => fmt(x, 3)).join(", ") || "—");
  setDd("pulses", m.pulses, String(m.pulses));
  document.body.dataset.models = String(Number(document.body.dataset.models || 0) + 1);
  stab.modelFn = m.fn_hz;
  sched.latest = m.operating_point;
  showTruthOfModel();
}

// ---- the simulator's truth (propid demo --http only) ----------------------------------------

const truth = { plant: null, rows: [] };
function truthAt(op) {
  let best = null;
  for (const t of truth.rows)
    if (Math.abs(t.operating_point - op) < 0.02 && (!best ||
      Math.abs(t.operating_point - op) < Math.abs(best.operating_point - op))) best = t;
  return best;
}
const ms = (s) => (s === null || s === undefined ? "—" : fmt(s * 1000, 3) + " ms");
function truthText(t) {
  if (!t) return "—";
  if (t.tau_up_s !== undefined)
    return "gain " + fmt(t.gain) + ", τ " + ms(t.tau_up_s) + " up / " + ms(t.tau_down_s) +
      " down, dead time " + ms(t.dead_time_s) + (t.within === undefined ? "" : t.within ? " (model within tolerance)" : " (model NOT within tolerance)");
  return "gain " + fmt(t.gain) + ", fn " + fmt(t.fn_hz) + " Hz, ζ " + fmt(t.zeta);
}
function showTruthOfModel() {
  if (sched.latest === undefined) return;
  const t = truthAt(sched.latest);
  const dd = $("model-truth");
  dd.textContent = truthText(t);
  dd.dataset.value = t ? String(t.gain) : "";
}
function onTruth(l) {
  truth.plant = l.plant;
  truth.rows = l.levels || [];
  document.body.dataset.truth = l.plant;
  showTruthOfModel();
  onSchedule(sched.rows);
}

function onResponse(r) {
  const x = r.mean.map((_, k) => k * r.dt_s * 1000);
  const hi = r.mean.map((m, k) => (m === null || r.spread[k] === null ? null : m + r.spread[k]));
  const lo = r.mean.map((m, k) => (m === null || r.spread[k] === null ? null : m - r.spread[k]));
  const model = x.map((_, k) => (k < r.model.length ? r.model[k] : null));
  cResp.setData([x, r.mean, hi, lo, model]);
}

const longest = (r) => (r.time_constants_s && r.time_constants_s.length ? Math.max(...r.time_constants_s) : null);
function onSchedule(rows) {
  sched.rows = rows;
  const x = rows.map((r) => r.operating_point);
  const tr_ = rows.map((r) => truthAt(r.operating_point));
  const tv = (f) => tr_.map((t) => (t && t[f] !== undefined ? t[f] : null));
  const fit = (f) => tr_.map((t) => (t && t.linear_fit ? t.linear_fit[f] : null));
  cGain.setData([x, rows.map((r) => first(r.dc_gain)), tv("gain"), fit("gain")]);
  cTau.setData([x, rows.map(longest), tv("tau_up_s"), tv("tau_down_s"), fit("tau_s")]);
  cFn.setData([x, rows.map((r) => r.fn_hz), tv("fn_hz")]);
  cZeta.setData([x, rows.map((r) => r.zeta), tv("zeta")]);
  $("realpoles").hidden = !(truth.plant === "motor" || rows.some((r) => r.zeta >= 1));
  const tb = $("schedule").tBodies[0];
  tb.replaceChildren();
  const cell = (tr, text, cls) => {
    const td = document.createElement("td");
    td.textContent = text;
    if (cls) td.className = cls;
    tr.appendChild(td);
  };
  rows.forEach((r, i) => {
    const tr = document.createElement("tr");
    for (const k of ["operating_point", "order", "fn_hz", "zeta", "dc_gain", "time_constants_s", "pulses"]) {
      const v = r[k];
      tr.dataset[k] = Array.isArray(v) ? v.map(String).join(",") : String(v);
    }
    const u = r.uncertainty || {};
    const pm = (v, sd) => fmt(v) + (sd === null || sd === undefined ? "" : " ± " + fmt(sd, 2));
    const t = tr_[i];
    if (t) tr.dataset.truth_gain = String(t.gain);
    cell(tr, String(r.operating_point));
    cell(tr, String(r.order));
    cell(tr, pm(first(r.dc_gain), first(u.dc_gain)));
    cell(tr, t ? fmt(t.gain) : "—", "truth");
    cell(tr, (r.time_constants_s || []).map((y) => fmt(y, 3)).join(", ") || "—");
    cell(tr, t && t.tau_up_s !== undefined ? fmt(t.tau_up_s, 3) + " / " + fmt(t.tau_down_s, 3) : "—", "truth");
    cell(tr, pm(r.fn_hz, u.fn_hz));
    cell(tr, pm(r.zeta, u.zeta));
    cell(tr, String(r.pulses));
    tb.appendChild(tr);
  });
}

function onStab(s) {
  const p = [];
  for (const o of s.orders) for (const q of o.poles) p.push([q.fn_hz, o.order, q.stable]);
  p.sort((a, b) => a[0] - b[0]);
  cStab.setData([p.map((q) => q[0]), p.map((q) => (q[2] ? q[1] : null)), p.map((q) => (q[2] ? null : q[1]))]);
  cSv.setData([s.singular_values.map((_, i) => i + 1), s.singular_values]);
}

const COUNTERS = ["wire", "frames_ok", "frames_dropped", "bytes", "samples", "samples_lost", "gaps",
  "overflows", "reconnects", "segments", "duplicates", "pulses", "models", "models_unreliable",
  "identify_errors", "dropped_clients", "clients_refused", "elapsed_s"];
function onStats(st, final) {
  const tb = $("counters").tBodies[0];
  tb.replaceChildren();
  for (const k of COUNTERS) {
    if (st[k] === undefined) continue;
    let v = st[k];
    if (k === "frames_dropped") {
      const kinds = Object.entries(v).filter(([, n]) => n > 0);
      v = kinds.length ? kinds.map(([a, b]) => a + " " + b).join(", ") : "0";
    } else if (k === "elapsed_s") v = fmt(v, 3) + " s";
    const tr = document.createElement("tr");
    tr.innerHTML = "<td></td><td></td>";
    tr.cells[0].textContent = k.replace(/_/g, " ");
    tr.cells[1].textContent = String(v);
    tr.dataset.key = k;
    tb.appendChild(tr);
  }
  if (final) {
    document.body.dataset.final = "1";
    setPhase("run over");
    if ($("link").dataset.state !== "disconnected") setLink("ended");
  }
}

function setLink(s) { const b = $("link"); b.dataset.state = s; b.textContent = s; }
function setPhase(s) { $("phase").textContent = s; }

function log(l) {
  const li = document.createElement("li");
  li.className = l.type;
  const { type, kind, ...rest } = l;
  const extra = Object.keys(rest).length ? " " + JSON.stringify(rest) : "";
  li.textContent = type + " " + kind + extra;
  const ol = $("log");
  ol.prepend(li);
  while (ol.children.length > 200) ol.lastChild.remove();
}

function onEvent(e) {
  if (e.kind === "http") return;
  log(e);
  switch (e.kind) {
    case "connected": setLink("connected"); setPhase("handshake done"); break;
    case "reconnected": setLink("connected"); break;
    case "csv_link": setPhase("CSV link"); break;
    case "arm_acknowledged": setPhase("armed"); break;
    case "level_reached": setPhase("level " + e.index + " (" + fmt(e.operating_point, 3) + "): pulses"); break;
    case "level_done": setPhase("level " + e.index + " done"); break;
    case "plan_finished": setPhase("plan finished"); break;
    case "stop_acknowledged": setPhase("stopped"); break;
  }
}

function onWarning(w) {
  log(w);
  if (w.kind === "disconnected") setLink("disconnected");
  if (["device_reset", "plan_halted_watchdog", "command_refused", "link_failed"].includes(w.kind))
    setPhase("halted: " + w.kind.replace(/_/g, " "));
}

// the experiment kinds' lines (staircase, ramp, chirp)
function showKinds(kind) {
  $("kinds").hidden = false;
  $("kinds-kind").textContent = "(" + kind + ")";
}
const kms = (v) => (v == null ? "—" : (v * 1e3).toFixed(1));
const fx = (v, d) => (v == null ? "—" : v.toFixed(d));
function onStep(s) {
  showKinds(s.kind);
  const r = $("steps").tBodies[0].insertRow();
  for (const v of [s.index, fx(s.t_s, 2), fx(s.from, 3), fx(s.to, 3), s.direction,
    kms(s.dead_time_s), kms(s.time_constant_s), kms(s.rise_10_90_s), kms(s.settling_90_s),
    fx(s.overshoot_pct, 1)]) r.insertCell().textContent = v;
}
function onStaticMap(m) {
  showKinds(m.kind);
  const tb = $("static-map").tBodies[0];
  for (const l of m.levels) {
    const r = tb.insertRow();
    for (const v of [m.output + " (" + m.unit + ")", m.leg || "", fx(l.throttle, 3),
      fx(l.mean, 4), fx(l.std, 4), l.samples]) r.insertCell().textContent = v;
  }
  const parts = [];
  if (m.expo) parts.push(m.output + ": expo a " + fx(m.expo.a, 3) + ", t_max " + fx(m.expo.t_max, 3));
  if (m.power) parts.push("power law k " + fx(m.power.k, 3) + ", u0 " + fx(m.power.u0, 3) +
    ", e " + fx(m.power.exponent, 2));
  if (m.hysteresis) parts.push("hysteresis " + fx(m.hysteresis.max_pct, 1) + " % at " +
    fx(m.hysteresis.at_throttle, 3));
  if (parts.length) $("map-fit").textContent += parts.join("; ") + ". ";
}
let cBode = null;
function onFrequencyResponse(f) {
  showKinds(f.kind);
  const m = f.model;
  $("freq-figures").textContent = "peak " + fx(f.peak_hz, 2) + " Hz, bandwidth " +
    fx(f.bandwidth_hz, 2) + " Hz, phase delay " + kms(f.phase_delay_s) + " ms" +
    (m ? "; model fn " + fx(m.natural_hz, 2) + " Hz, ζ " + fx(m.damping, 3) + ", K " +
      fx(m.gain, 3) + ", T " + kms(m.dead_time_s) + " ms" : "");
  const x = f.bins.map((b) => b.f_hz);
  const data = [x, f.bins.map((b) => 20 * Math.log10(b.gain)), f.bins.map((b) => b.coherence)];
  if (!cBode) {
    cBode = new uPlot({ width: 800, height: 260, scales: { x: { distr: 3 } },
      series: [{ label: "Hz" }, { label: "gain dB", stroke: "#1e5ac8" },
        { label: "coherence", stroke: "#888", scale: "c" }],
      axes: [{}, {}, { scale: "c", side: 1 }] }, data, $("chart-bode"));
  } else cBode.setData(data);
}

function handle(l) {
  switch (l.type) {
    case "step": onStep(l); break;
    case "static_map": onStaticMap(l); break;
    case "frequency_response": onFrequencyResponse(l); break;
    case "samples": onSamples(l); break;
    case "model": onModel(l); break;
    case "response": onResponse(l); break;
    case "schedule": onSchedule(l.models); break;
    case "truth": onTruth(l); break;
    case "stabilization": onStab(l); break;
    case "live_stats": onStats(l, false); break;
    case "stats": onStats(l, true); break;
    case "event": onEvent(l); break;
    case "warning": onWarning(l); break;
  }
}

// samples are drawn at most every 100 ms
const dirty = { samples: false };
setInterval(() => {
  if (!dirty.samples) return;
  dirty.samples = false;
  const s = samples;
  cThrust.setData([s.t, s.thr, s.thrust]);
  cOther.setData([s.t, s.torque, s.rpm]);
  cPower.setData([s.t, s.volt, s.amp]);
}, 100);

// served by `propid fleet` at /stand/NAME/: the stand's name in the title, its stream beside
// the page
const fleetStand = location.pathname.startsWith("/stand/");
if (fleetStand) {
  const name = decodeURIComponent(location.pathname.split("/")[2]);
  document.querySelector("h1 .dim").textContent = "stand " + name;
  document.title = "propid — " + name;
}
const es = new EventSource(fleetStand ? location.pathname + "events" : "/events");
es.onopen = () => { $("stream").textContent = "open"; };
es.onerror = () => { $("stream").textContent = es.readyState === 2 ? "closed" : "reconnecting"; };
es.onmessage = (ev) => {
  let l;
  try { l = JSON.parse(ev.data); } catch (_) { return; }
  handle(l);
};
