// The fleet page: one row per stand from the `fleet` lines of /events (propid fleet), each
// stand's name opening its single-stand page (/stand/NAME/), fed from the broker.
"use strict";
const $ = (id) => document.getElementById(id);
const fmt = (x, p = 4) =>
  x === null || x === undefined || (typeof x === "number" && !isFinite(x)) ? "—"
    : typeof x === "number" ? Number(x.toPrecision(p)).toString() : String(x);
const el = (tag, text, cls) => {
  const e = document.createElement(tag);
  if (text !== undefined) e.textContent = text;
  if (cls) e.className = cls;
  return e;
};
const taus = (m) => (m.time_constants_s || []).map((t) => fmt(t, 3)).join(", ");

function modelCell(m) {
  const td = el("td");
  if (!m) { td.textContent = "—"; return td; }
  td.append(el("div", "throttle " + fmt(m.operating_point, 3) + ", order " + m.order));
  td.append(el("div", "DC gain " + fmt(m.dc_gain) + (taus(m) ? ", τ " + taus(m) + " s" : "")));
  td.append(el("div", "fn " + fmt(m.fn_hz, 3) + " Hz, ζ " + fmt(m.zeta, 3) + ", t " + fmt(m.t_s, 5) + " s", "dim"));
  return td;
}

function scheduleCell(rows) {
  const td = el("td");
  if (!rows.length) { td.textContent = "—"; return td; }
  const ul = el("ul");
  for (const r of rows) {
    const shape = taus(r) ? "τ " + taus(r) : "fn " + fmt(r.fn_hz, 3);
    ul.append(el("li", fmt(r.operating_point, 3) + ": " + fmt(r.dc_gain) + ", " + shape));
  }
  td.append(ul);
  return td;
}

function warningsCell(ws) {
  const td = el("td");
  if (!ws.length) { td.textContent = "—"; return td; }
  const ul = el("ul");
  for (const w of ws.slice(-4).reverse()) ul.append(el("li", w.kind, "warning"));
  td.append(ul);
  return td;
}

function onFleet(f) {
  const body = document.querySelector("#stands tbody");
  body.replaceChildren();
  let online = 0;
  for (const s of f.stands) {
    if (s.status === "online") online++;
    const tr = el("tr");
    tr.dataset.status = s.status;
    tr.dataset.stand = s.stand;
    const name = el("td");
    const a = el("a", s.stand);
    a.href = "/stand/" + encodeURIComponent(s.stand) + "/";
    name.append(a);
    const st = el("td", s.status, "status");
    st.dataset.status = s.status;
    tr.append(name, st, el("td", s.phase || "—"), modelCell(s.model), scheduleCell(s.schedule),
      warningsCell(s.warnings));
    body.append(tr);
  }
  $("count").textContent = f.stands.length;
  $("online").textContent = online;
  $("empty").hidden = f.stands.length > 0;
}

const es = new EventSource("/events");
es.onopen = () => { $("stream").textContent = "open"; };
es.onerror = () => { $("stream").textContent = es.readyState === 2 ? "closed" : "reconnecting"; };
es.onmessage = (ev) => {
  let l;
  try { l = JSON.parse(ev.data); } catch (_) { return; }
  if (l.type === "fleet") onFleet(l);
};
