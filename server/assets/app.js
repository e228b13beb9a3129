// ivlmap serve: the page. Plain JavaScript, no build step. It draws the map from
// GET /api/map on a canvas, chats through POST /api/sessions/{id}/instructions, and
// animates each run from the `step` events of GET /api/sessions/{id}/events.
"use strict";

(() => {
  const $ = (id) => document.getElementById(id);
  const canvas = $("map");
  const ctx = canvas.getContext("2d");
  const tip = $("tip");
  const log = $("log");
  const input = $("input");

  // Colour words as map_core::render::PALETTE draws them.
  const PALETTE = {
    black: [28, 28, 28], white: [250, 250, 250], gray: [150, 150, 150], grey: [150, 150, 150],
    silver: [192, 196, 204], red: [214, 39, 40], orange: [255, 140, 26], yellow: [245, 205, 30],
    gold: [212, 175, 55], green: [44, 160, 44], blue: [31, 100, 200], navy: [20, 40, 110],
    cyan: [40, 200, 220], teal: [0, 128, 128], purple: [128, 60, 170], violet: [150, 100, 220],
    pink: [245, 140, 180], magenta: [220, 40, 180], brown: [140, 86, 50], tan: [210, 180, 140],
    beige: [230, 218, 180], cream: [250, 240, 205], chocolate: [110, 60, 25],
  };
  const UNKNOWN = [205, 205, 205];
  const REGION_TINTS = ["#eef4ff", "#fff4e6", "#ecf8ef", "#f8eef8", "#fffbe3", "#eaf7fa", "#f3f0ff", "#fdf0ee"];

  const S = {
    token: sessionStorage.getItem("ivlmap-token") || "",
    session: null,
    map: null,
    trajectory: null,      // the session's whole trajectory (GET /api/sessions/{id})
    pose: null,            // the robot's pose as drawn
    live: [],              // path drawn so far by the running animation
    preview: null,         // {path, stops} of a preview waiting for confirm/cancel
    view: { scale: 1, ox: 0, oy: 0 },
    hover: null,
    pending: null,         // the turn card being answered
    anim: [],              // queued path segments to animate
    animating: false,
    busy: false,
    eventsAbort: null,
  };

  // ------------------------------------------------------------------ HTTP

  async function api(method, path, body) {
    for (;;) {
      const headers = {};
      if (body !== undefined) headers["Content-Type"] = "application/json";
      if (S.token) headers["Authorization"] = "Bearer " + S.token;
      const res = await fetch(path, { method, headers, body: body === undefined ? undefined : JSON.stringify(body) });
      if (res.status === 401) { await askToken(); continue; }
      const type = res.headers.get("content-type") || "";
      const data = type.includes("json") ? await res.json() : res.status === 204 ? null : await res.blob();
      if (!res.ok) {
        const err = new Error((data && data.error) || res.statusText);
        err.status = res.status; err.code = data && data.code;
        throw err;
      }
      return data;
    }
  }

  function askToken() {
    return new Promise((resolve) => {
      const dlg = $("token-dialog");
      const form = $("token-form");
      form.onsubmit = (e) => {
        e.preventDefault();
        S.token = $("token-input").value.trim();
        sessionStorage.setItem("ivlmap-token", S.token);
        dlg.close();
        resolve();
      };
      if (!dlg.open) dlg.showModal();
    });
  }

  // ------------------------------------------------------------------ events (SSE over fetch, so the token header goes along)

  async function listen() {
    if (S.eventsAbort) S.eventsAbort.abort();
    const ctl = new AbortController();
    S.eventsAbort = ctl;
    const id = S.session;
    try {
      const headers = S.token ? { Authorization: "Bearer " + S.token } : {};
      const res = await fetch(`/api/sessions/${id}/events`, { headers, signal: ctl.signal });
      if (!res.ok || !res.body) throw new Error("events: " + res.status);
      const reader = res.body.getReader();
      const dec = new TextDecoder();
      let buf = "";
      for (;;) {
        const { value, done } = await reader.read();
        if (done) break;
        buf += dec.decode(value, { stream: true });
        let cut;
        while ((cut = buf.indexOf("\n\n")) >= 0) {
          const chunk = buf.slice(0, cut);
          buf = buf.slice(cut + 2);
          let name = "message", data = "";
          for (const line of chunk.split("\n")) {
            if (line.startsWith("event:")) name = line.slice(6).trim();
            else if (line.startsWith("data:")) data += line.slice(5).trim();
          }
          if (data) onEvent(name, JSON.parse(data));
        }
      }
    } catch (e) {
      if (ctl.signal.aborted) return;
    }
    // The stream ended: the session expired, or the connection dropped. Look again shortly.
    if (S.eventsAbort === ctl && !ctl.signal.aborted) setTimeout(() => { if (S.session === id) listen(); }, 1500);
  }

  function onEvent(name, d) {
    const card = S.pending;
    if (name === "open") { canvas.dataset.events = "open"; return; }
    if (!card) return;
    switch (name) {
      case "queued":
        status(card, d.position > 1 ? `waiting for the model: number ${d.position} in the queue` : "next in the queue…", true);
        break;
      case "planning":
        status(card, "the model is planning…", true);
        break;
      case "tuples":
        showTuples(card, d.tuples, d.text);
        break;
      case "script":
        showScript(card, d.script);
        status(card, card.preview ? "previewing…" : "running…", true);
        break;
      case "step":
        card.steps.push(d);
        if (d.path && d.path.length > 1) enqueue(d.path, d.pose);
        else if (d.pose) enqueue([[d.pose[0], d.pose[1]]], d.pose);
        break;
    }
  }

  // ------------------------------------------------------------------ sessions

  async function start() {
    try {
      const info = await api("GET", "/api/info");
      $("scene").textContent = "map: " + info.scene;
      $("backend").textContent = `${info.backend} · ${info.model || "?"} · examples: ${info.examples}`;
    } catch (e) { note("cannot reach the server: " + e.message, true); return; }
    S.map = await api("GET", "/api/map");
    fit();
    const saved = sessionStorage.getItem("ivlmap-session");
    let restored = false;
    if (saved) {
      try { S.session = saved; await refresh(true); restored = true; } catch (e) { /* expired */ }
    }
    if (!restored) await newSession();
    listen();
    setInterval(pollQueue, 2000);
  }

  async function newSession() {
    const s = await api("POST", "/api/sessions", {});
    S.session = s.id;
    sessionStorage.setItem("ivlmap-session", s.id);
    S.trajectory = null;
    S.pose = s.pose;
    await refresh(false);
  }

  async function refresh(replay) {
    const s = await api("GET", `/api/sessions/${S.session}`);
    S.trajectory = s.trajectory;
    S.pose = s.pose;
    S.live = [];
    S.preview = s.pending && S.preview ? S.preview : null;
    canvas.dataset.pose = s.pose.map((v) => v.toFixed(3)).join(",");
    canvas.dataset.stops = String(s.trajectory.stops.length);
    S.undoable = s.undo;
    $("undo").disabled = !s.undo;
    if (replay && s.turns.length) {
      note(`session resumed: ${s.turns.length} earlier instruction(s)`);
      for (const t of s.turns) pastTurn(t);
    }
    draw();
    return s;
  }

  async function pollQueue() {
    try {
      const info = await api("GET", "/api/info");
      const q = info.queue;
      const el = $("queue");
      el.textContent = `queue: ${q.waiting} waiting · ${q.running} planning`;
      el.classList.toggle("busy", q.waiting + q.running > 0);
      el.classList.toggle("quiet", q.waiting + q.running === 0);
    } catch (e) { /* the server went away; the next action says so */ }
  }

  async function withSession(fn) {
    try { return await fn(); } catch (e) {
      if (e.status === 404 && e.code === "unknown_session") {
        note("this session expired; a new one started (the robot is back at the start)", true);
        await newSession();
        listen();
        return await fn();
      }
      throw e;
    }
  }

  // ------------------------------------------------------------------ chat

  function el(tag, cls, text) {
    const e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined) e.textContent = text;
    return e;
  }

  function note(text, bad) {
    const n = el("div", "note", text);
    if (bad) n.style.color = "var(--bad)";
    log.appendChild(n);
    log.scrollTop = log.scrollHeight;
  }

  function turnCard(text, preview, tag) {
    const root = el("div", "turn");
    const say = el("div", "say", text);
    if (preview) say.appendChild(el("span", "tag", "preview"));
    if (tag) say.appendChild(el("span", "tag " + tag, tag));
    root.appendChild(say);
    const st = el("div", "status", "sending…");
    root.appendChild(st);
    log.appendChild(root);
    log.scrollTop = log.scrollHeight;
    return { root, st, preview, steps: [], tuples: null, script: null };
  }

  function status(card, text, busy) {
    card.st.textContent = text;
    card.st.classList.toggle("busy", !!busy);
    card.st.hidden = !text;
  }

  function section(card, cls, title) {
    let s = card.root.querySelector(".sec." + cls);
    if (!s) {
      s = el("div", "sec " + cls);
      s.appendChild(el("div", "h", title));
      card.root.insertBefore(s, card.root.querySelector(".outcome"));
    }
    return s;
  }

  function showTuples(card, tuples, text) {
    if (card.tuples) return;
    card.tuples = tuples;
    const s = section(card, "tuples-sec", "objects (tuples)");
    const box = el("div", "tuples");
    box.title = text || "";
    if (!tuples.length) box.textContent = "[]";
    for (const t of tuples) {
      const parts = [t.object, t.ordinal === null || t.ordinal === undefined ? "None" : t.ordinal === -1 ? "last" : t.ordinal, t.colour || "None"];
      if (t.order) parts.push(t.order);
      box.appendChild(el("span", "chip", "(" + parts.join(", ") + ")"));
    }
    s.appendChild(box);
  }

  function showScript(card, script) {
    if (card.script) return;
    card.script = script;
    const s = section(card, "script-sec", "script");
    s.appendChild(el("pre", "script", script.trimEnd()));
  }

  function fmt(v) {
    if (v === null || v === undefined) return "";
    if (Array.isArray(v)) return "[" + v.map((x) => typeof x === "number" ? +x.toFixed(2) : fmt(x)).join(", ") + "]";
    if (typeof v === "object") {
      if (v.name !== undefined && v.id !== undefined) return `${v.colour ? v.colour + " " : ""}${v.name} #${v.label_id} (id ${v.id})`;
      return JSON.stringify(v);
    }
    if (typeof v === "number") return String(+v.toFixed(2));
    return JSON.stringify(v);
  }

  function showTrace(card, trace, steps) {
    if (!trace || !trace.length) return;
    const s = section(card, "trace-sec", "execution trace");
    const ol = el("ol", "trace");
    trace.forEach((t, i) => {
      const li = el("li");
      const st = steps && steps[i] && steps[i].stop;
      if (st) li.appendChild(el("span", "stopno", String(st)));
      li.appendChild(document.createTextNode(`${t.function}(${t.args.map(fmt).join(", ")})${t.result !== null && t.result !== undefined ? " → " + fmt(t.result) : ""} `));
      li.appendChild(el("span", "pose", `@ (${t.pose_after[0].toFixed(2)}, ${t.pose_after[1].toFixed(2)}, ${Math.round(t.pose_after[2])}°)`));
      if (t.error) { li.classList.add("failed"); li.appendChild(el("div", "", "error: " + t.error)); }
      if (t.warning) li.appendChild(el("div", "", "warning: " + t.warning));
      ol.appendChild(li);
    });
    s.appendChild(ol);
  }

  function outcome(card, cls, text) {
    const o = el("div", "outcome " + cls, text);
    card.root.appendChild(o);
    log.scrollTop = log.scrollHeight;
    return o;
  }

  /// Stop numbers per trace entry, as the step events would give them.
  function stopNumbers(reply) {
    let k = reply.first_stop;
    const stops = reply.trajectory.stops.slice();
    return reply.trace.map((t) => {
      const s = stops[0];
      if (s && s.call === t.function && Math.abs(s.pose[0] - t.pose_after[0]) < 1e-6 && Math.abs(s.pose[1] - t.pose_after[1]) < 1e-6) {
        stops.shift();
        return { stop: k++ };
      }
      return { stop: null };
    });
  }

  function pastTurn(t) {
    const card = turnCard(t.instruction, false);
    status(card, "");
    showTuples(card, t.tuples);
    showScript(card, t.script);
    if (t.error) outcome(card, "failed", "stopped part-way: " + t.error);
    else outcome(card, "done", `done: ${t.stops.length} stop(s)`);
  }

  async function send(preview) {
    const text = input.value.trim();
    if (!text || S.busy) return;
    cancelPreviewUi();
    S.busy = true;
    setBusy(true);
    const card = turnCard(text, preview);
    S.pending = card;
    input.value = "";
    try {
      const reply = await withSession(() => api("POST", `/api/sessions/${S.session}/instructions`, { text, preview }));
      await finishTurn(card, reply);
    } catch (e) {
      status(card, "");
      outcome(card, "error", (e.status ? `${e.status} ${e.code || ""}: ` : "") + e.message + (e.status >= 500 ? " — nothing changed; try again or rephrase" : ""));
      if (e.status === 400 || e.status === 503) input.value = text;
    } finally {
      S.pending = null;
      S.busy = false;
      setBusy(false);
      input.focus();
    }
  }

  async function finishTurn(card, reply) {
    showTuples(card, reply.tuples, reply.tuples_text);
    if (reply.script) showScript(card, reply.script);
    const steps = card.steps.length ? card.steps : stopNumbers(reply);
    showTrace(card, reply.trace, steps);
    status(card, "");
    const tr = reply.trajectory;
    switch (reply.outcome) {
      case "question":
        outcome(card, "question", "? " + reply.question);
        break;
      case "refused":
        outcome(card, "refused", "cannot do that: " + reply.error);
        break;
      case "preview": {
        S.preview = { path: tr.path, stops: tr.stops, first: reply.first_stop };
        draw();
        const o = outcome(card, "preview", `preview: ${tr.length_m.toFixed(1)} m, ${tr.stops.length} stop(s)` + (reply.error ? ` — would stop part-way: ${reply.error}` : "") + ". Nothing has moved yet.");
        const acts = el("div", "actions");
        const ok = el("button", "confirm", "Confirm");
        ok.type = "button";
        const no = el("button", "cancel", "Cancel");
        no.type = "button";
        acts.append(ok, no);
        o.appendChild(acts);
        log.scrollTop = log.scrollHeight;
        card.actions = acts;
        S.previewCard = card;
        ok.onclick = () => confirmPreview(card);
        no.onclick = () => cancelPreview(card);
        break;
      }
      default: {
        if (!card.steps.some((s) => s.path && s.path.length > 1) && tr.path.length > 1) enqueue(tr.path, reply.pose);
        await drained();
        const cls = reply.outcome === "failed" ? "failed" : "done";
        const said = reply.said && reply.said.length ? ` — robot says: “${reply.said.join(" ")}”` : "";
        outcome(card, cls, (cls === "failed" ? `stopped part-way: ${reply.error} (Undo goes back)` : `done: ${tr.length_m.toFixed(1)} m, ${tr.stops.length} stop(s)`) + said);
        card.executed = true;
        await refresh(false);
      }
    }
  }

  async function confirmPreview(card) {
    if (S.busy) return;
    S.busy = true;
    setBusy(true);
    card.actions.remove();
    outcome(card, "preview", "confirmed: it runs below");
    S.preview = null;
    const run = turnCard(card.root.querySelector(".say").firstChild.textContent, false, "confirmed");
    S.pending = run;
    try {
      const reply = await withSession(() => api("POST", `/api/sessions/${S.session}/confirm`));
      await finishTurn(run, reply);
    } catch (e) {
      status(run, "");
      outcome(run, "error", e.message);
    } finally {
      S.pending = null; S.busy = false; setBusy(false); draw();
    }
  }

  async function cancelPreview(card) {
    card.actions.remove();
    outcome(card, "preview", "cancelled");
    S.preview = null;
    draw();
    try { await api("POST", `/api/sessions/${S.session}/cancel`); } catch (e) { /* nothing pending: fine */ }
  }

  function cancelPreviewUi() {
    if (S.preview && S.previewCard && S.previewCard.actions) {
      S.previewCard.actions.remove();
      outcome(S.previewCard, "preview", "replaced by a new instruction");
    }
    S.preview = null;
  }

  function setBusy(b) {
    $("send").disabled = b; $("preview").disabled = b; $("reset").disabled = b;
    $("undo").disabled = b || !S.undoable;
  }

  async function undo() {
    try {
      await withSession(() => api("POST", `/api/sessions/${S.session}/undo`));
      const cards = [...log.querySelectorAll(".turn")].filter((c) => c.dataset.executed === "1" && !c.classList.contains("undone"));
      if (cards.length) cards[cards.length - 1].classList.add("undone");
      S.preview = null;
      await refresh(false);
      note("undone: the robot is back where it was");
    } catch (e) { note(e.message, true); }
  }

  async function reset() {
    try {
      await withSession(() => api("POST", `/api/sessions/${S.session}/reset`));
      log.querySelectorAll(".turn, .note:not(.intro)").forEach((n) => n.remove());
      S.preview = null;
      await refresh(false);
      note("reset: the robot is at the start, the history is cleared");
    } catch (e) { note(e.message, true); }
  }

  async function png() {
    try {
      const blob = await api("GET", `/api/sessions/${S.session}/map.png`);
      window.open(URL.createObjectURL(blob), "_blank");
    } catch (e) { note(e.message, true); }
  }

  // ------------------------------------------------------------------ animation

  function enqueue(points, pose) {
    S.anim.push({ points, pose });
    if (!S.animating) animate();
  }

  let drainWaiters = [];
  function drained() {
    if (!S.animating && !S.anim.length) return Promise.resolve();
    return new Promise((r) => drainWaiters.push(r));
  }

  function animate() {
    const seg = S.anim.shift();
    if (!seg) {
      S.animating = false;
      const w = drainWaiters; drainWaiters = [];
      w.forEach((r) => r());
      return;
    }
    S.animating = true;
    const pts = seg.points;
    const lens = [0];
    for (let i = 1; i < pts.length; i++) lens.push(lens[i - 1] + Math.hypot(pts[i][0] - pts[i - 1][0], pts[i][1] - pts[i - 1][1]));
    const total = lens[lens.length - 1];
    const ms = Math.min(2500, Math.max(pts.length > 1 ? 300 : 120, total / 4.0 * 1000));
    const t0 = performance.now();
    const base = S.live.length;
    const frame = (now) => {
      const f = Math.min(1, (now - t0) / ms);
      const d = f * total;
      let i = 1;
      while (i < pts.length && lens[i] < d) i++;
      S.live.length = base;
      for (let k = 0; k < i && k < pts.length; k++) S.live.push(pts[k]);
      let heading = S.pose ? S.pose[2] : 0;
      let at = pts[pts.length - 1];
      if (i < pts.length && total > 0) {
        const a = pts[i - 1], b = pts[i];
        const u = (d - lens[i - 1]) / Math.max(1e-9, lens[i] - lens[i - 1]);
        at = [a[0] + (b[0] - a[0]) * u, a[1] + (b[1] - a[1]) * u];
        heading = Math.atan2(b[0] - a[0], b[1] - a[1]) * 180 / Math.PI;
        S.live.push(at);
      }
      S.pose = [at[0], at[1], f >= 1 && seg.pose ? seg.pose[2] : heading];
      draw();
      if (f < 1) requestAnimationFrame(frame);
      else {
        S.live.length = base;
        for (const p of pts) S.live.push(p);
        if (seg.pose) S.pose = seg.pose.slice();
        canvas.dataset.pose = S.pose.map((v) => v.toFixed(3)).join(",");
        animate();
      }
    };
    requestAnimationFrame(frame);
  }

  // ------------------------------------------------------------------ drawing

  function resize() {
    const r = canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    canvas.width = Math.max(1, Math.round(r.width * dpr));
    canvas.height = Math.max(1, Math.round(r.height * dpr));
    draw();
  }

  function fit() {
    if (!S.map) return;
    const r = canvas.getBoundingClientRect();
    const [x0, y0, x1, y1] = S.map.bounds;
    const pad = 24;
    const scale = Math.min((r.width - 2 * pad) / (x1 - x0), (r.height - 2 * pad - 40) / (y1 - y0));
    S.view.scale = Math.max(4, scale);
    S.view.ox = (r.width - (x1 - x0) * S.view.scale) / 2 - x0 * S.view.scale;
    S.view.oy = (r.height - 40 - (y1 - y0) * S.view.scale) / 2 + y1 * S.view.scale;
    draw();
  }

  // world (x east, y north) -> CSS pixels
  const sx = (x) => S.view.ox + x * S.view.scale;
  const sy = (y) => S.view.oy - y * S.view.scale;
  const wx = (px) => (px - S.view.ox) / S.view.scale;
  const wy = (py) => (S.view.oy - py) / S.view.scale;

  function rgb(c, a) { return a === undefined ? `rgb(${c[0]},${c[1]},${c[2]})` : `rgba(${c[0]},${c[1]},${c[2]},${a})`; }
  function fillOf(inst) { return (inst.color && PALETTE[inst.color.toLowerCase()]) || UNKNOWN; }
  function luminance(c) { return (0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]) / 255; }

  function poly(pts) {
    ctx.beginPath();
    pts.forEach((p, i) => (i ? ctx.lineTo(sx(p[0]), sy(p[1])) : ctx.moveTo(sx(p[0]), sy(p[1]))));
    ctx.closePath();
  }

  function centroid(pts) {
    let a = 0, cx = 0, cy = 0;
    for (let i = 0; i < pts.length; i++) {
      const [x0, y0] = pts[i], [x1, y1] = pts[(i + 1) % pts.length];
      const c = x0 * y1 - x1 * y0;
      a += c; cx += (x0 + x1) * c; cy += (y0 + y1) * c;
    }
    if (Math.abs(a) < 1e-9) return pts[0] || [0, 0];
    return [cx / (3 * a), cy / (3 * a)];
  }

  function label(text, x, y, opts) {
    const o = Object.assign({ size: 12, bold: false, color: "#1d2330", bg: "rgba(255,255,255,.85)", pad: 3 }, opts || {});
    ctx.font = `${o.bold ? "700 " : ""}${o.size}px "DejaVu Sans", sans-serif`;
    const w = ctx.measureText(text).width;
    if (o.bg) {
      ctx.fillStyle = o.bg;
      ctx.fillRect(x - w / 2 - o.pad, y - o.size / 2 - o.pad + 1, w + 2 * o.pad, o.size + 2 * o.pad - 2);
    }
    ctx.fillStyle = o.color;
    ctx.textAlign = "center";
    ctx.textBaseline = "middle";
    ctx.fillText(text, x, y + 1);
  }

  function disc(x, y, r, fill, text, hollow) {
    ctx.beginPath();
    ctx.arc(x, y, r, 0, 2 * Math.PI);
    if (hollow) { ctx.fillStyle = "#fff"; ctx.fill(); ctx.lineWidth = 2.5; ctx.strokeStyle = fill; ctx.stroke(); }
    else { ctx.fillStyle = fill; ctx.fill(); ctx.lineWidth = 1.5; ctx.strokeStyle = "#fff"; ctx.stroke(); }
    if (text) label(text, x, y, { size: Math.max(9, r * 1.05), bold: true, color: hollow ? fill : "#fff", bg: null });
  }

  // A stop: a dot where the robot stopped and a numbered disc up and to the right of it,
  // so the robot marker on top of the last stop hides neither.
  function pin(pose, color, text, hollow) {
    const x = sx(pose[0]), y = sy(pose[1]);
    const bx = x + 17, by = y - 17;
    ctx.beginPath();
    ctx.moveTo(x, y); ctx.lineTo(bx, by);
    ctx.strokeStyle = color; ctx.lineWidth = 2;
    ctx.stroke();
    ctx.beginPath();
    ctx.arc(x, y, 3.5, 0, 2 * Math.PI);
    ctx.fillStyle = color; ctx.fill();
    disc(bx, by, 9, color, text, hollow);
  }

  function line(pts, color, width, dash) {
    if (pts.length < 2) return;
    ctx.beginPath();
    pts.forEach((p, i) => (i ? ctx.lineTo(sx(p[0]), sy(p[1])) : ctx.moveTo(sx(p[0]), sy(p[1]))));
    ctx.setLineDash(dash || []);
    ctx.lineJoin = "round"; ctx.lineCap = "round";
    ctx.strokeStyle = color; ctx.lineWidth = width;
    ctx.stroke();
    ctx.setLineDash([]);
  }

  function robot(pose, color, hollow) {
    const x = sx(pose[0]), y = sy(pose[1]);
    const r = Math.max(7, (S.map.robot_radius || 0.2) * S.view.scale);
    const h = (pose[2] * Math.PI) / 180; // compass: 0 = north (up), clockwise
    const dx = Math.sin(h), dy = -Math.cos(h);
    ctx.beginPath();
    ctx.arc(x, y, r, 0, 2 * Math.PI);
    ctx.fillStyle = hollow ? "rgba(255,255,255,.6)" : color;
    ctx.fill();
    ctx.lineWidth = hollow ? 2 : 2.5;
    ctx.strokeStyle = hollow ? color : "#fff";
    ctx.stroke();
    // heading: a pointer from the centre past the rim
    ctx.beginPath();
    const tipx = x + dx * (r + 9), tipy = y + dy * (r + 9);
    const px = -dy, py = dx;
    ctx.moveTo(tipx, tipy);
    ctx.lineTo(x + dx * r * 0.35 + px * r * 0.6, y + dy * r * 0.35 + py * r * 0.6);
    ctx.lineTo(x + dx * r * 0.35 - px * r * 0.6, y + dy * r * 0.35 - py * r * 0.6);
    ctx.closePath();
    ctx.fillStyle = hollow ? color : "#fff";
    ctx.fill();
    if (!hollow) { ctx.lineWidth = 1.5; ctx.strokeStyle = color; ctx.stroke(); }
  }

  function draw() {
    const dpr = window.devicePixelRatio || 1;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    const W = canvas.width / dpr, H = canvas.height / dpr;
    ctx.fillStyle = "#e9edf3";
    ctx.fillRect(0, 0, W, H);
    const m = S.map;
    if (!m) return;
    const [x0, y0, x1, y1] = m.bounds;
    ctx.fillStyle = "#ffffff";
    ctx.fillRect(sx(x0), sy(y1), (x1 - x0) * S.view.scale, (y1 - y0) * S.view.scale);

    // regions: tint and dashed outline
    m.regions.forEach((r, i) => {
      poly(r.polygon);
      ctx.fillStyle = REGION_TINTS[i % REGION_TINTS.length];
      ctx.fill();
      ctx.setLineDash([6, 5]);
      ctx.strokeStyle = "#9aa6c0"; ctx.lineWidth = 1;
      ctx.stroke();
      ctx.setLineDash([]);
    });

    // obstacles (walls and objects) from the grid
    const cs = m.cell_size, [ox, oy] = m.origin;
    ctx.fillStyle = "#404652";
    const px = cs * S.view.scale;
    m.obstacles.rows.forEach((runs, row) => {
      const y = sy(oy - row * cs);
      for (let k = 0; k < runs.length; k += 2) {
        ctx.fillRect(sx(ox + runs[k] * cs), y, runs[k + 1] * px + 0.5, px + 0.5);
      }
    });

    // instances in their colours
    for (const inst of m.instances) {
      const c = fillOf(inst);
      poly(inst.contour);
      ctx.fillStyle = rgb(c);
      ctx.fill();
      const dark = luminance(c) < 0.25;
      ctx.lineWidth = S.hover === inst ? 3 : 1.5;
      ctx.strokeStyle = S.hover === inst ? "#1e6ef0" : dark ? "#8a93a6" : rgb(c.map((v) => Math.round(v * 0.55)));
      ctx.stroke();
    }

    // region names
    ctx.globalAlpha = 0.9;
    for (const r of m.regions) {
      const [cx, cy] = centroid(r.polygon);
      const ys = r.polygon.map((p) => p[1]);
      const top = Math.max(...ys);
      const ty = Math.min(sy(cy), sy(top) + 16);
      label(r.name.toUpperCase(), sx(cx), ty, { size: 12, bold: true, color: "#5a6782", bg: "rgba(255,255,255,.75)" });
    }
    ctx.globalAlpha = 1;

    // names and ids where they fit in the footprint, else the id (everything on hover)
    ctx.font = '11px "DejaVu Sans", sans-serif';
    for (const inst of m.instances) {
      const c = fillOf(inst);
      const [cx, cy] = inst.centroid;
      const w = (inst.bbox_m[2] - inst.bbox_m[0]) * S.view.scale;
      const h = (inst.bbox_m[3] - inst.bbox_m[1]) * S.view.scale;
      const ink = luminance(c) < 0.5 ? "#fff" : "#1d2330";
      const name = inst.label;
      if (w > ctx.measureText(name).width + 8 && h > 30) {
        label(name, sx(cx), sy(cy) - 7, { size: 11, bold: true, color: ink, bg: null });
        label("#" + inst.id, sx(cx), sy(cy) + 7, { size: 10, color: ink, bg: null });
        ctx.font = '11px "DejaVu Sans", sans-serif';
      } else if (w > ctx.measureText(name + " #" + inst.id).width + 8 && h > 15) {
        label(name + " #" + inst.id, sx(cx), sy(cy), { size: 10, color: ink, bg: null });
        ctx.font = '11px "DejaVu Sans", sans-serif';
      } else if (S.view.scale >= 22) {
        label(String(inst.id), sx(cx), sy(cy), { size: 10, color: ink, bg: null });
        ctx.font = '11px "DejaVu Sans", sans-serif';
      }
    }

    // the session's path so far, and its stops
    const tr = S.trajectory;
    if (tr) line(tr.path, "#1e6ef0", 3.5);
    if (S.live.length > 1) line(S.live, "#1e6ef0", 3.5);
    if (S.preview) line(S.preview.path, "#8e44ad", 3, [8, 6]);

    // start pose and robot, then the stops as numbered pins beside them
    robot(m.start_pose, "#148c3c", true);
    if (S.pose) robot(S.pose, "#dc1e3c", false);
    if (tr) tr.stops.forEach((s, i) => pin(s.pose, "#ff9614", String(i + 1), false));
    if (S.preview) S.preview.stops.forEach((s, i) => pin(s.pose, "#8e44ad", String(S.preview.first + i), true));

    // north arrow and scale bar
    const nx = W - 70, ny = 120;
    ctx.fillStyle = "#1d2330";
    ctx.beginPath(); ctx.moveTo(nx, ny - 18); ctx.lineTo(nx - 7, ny); ctx.lineTo(nx + 7, ny); ctx.closePath(); ctx.fill();
    label("N", nx, ny + 10, { size: 12, bold: true, bg: null });
    const metres = S.view.scale > 60 ? 1 : S.view.scale > 25 ? 2 : 5;
    const bx = W - 30 - metres * S.view.scale, by = H - 24;
    ctx.fillStyle = "#1d2330";
    ctx.fillRect(bx, by, metres * S.view.scale, 3);
    label(`${metres} m`, bx + (metres * S.view.scale) / 2, by - 9, { size: 11, bg: null });
  }

  // ------------------------------------------------------------------ pan, zoom, hover, click

  function pointIn(pts, x, y) {
    let inside = false;
    for (let i = 0, j = pts.length - 1; i < pts.length; j = i++) {
      const [xi, yi] = pts[i], [xj, yj] = pts[j];
      if (yi > y !== yj > y && x < ((xj - xi) * (y - yi)) / (yj - yi) + xi) inside = !inside;
    }
    return inside;
  }

  function instanceAt(px, py) {
    if (!S.map) return null;
    const x = wx(px), y = wy(py);
    const slack = 4 / S.view.scale; // a few pixels around small objects
    let best = null;
    for (const inst of S.map.instances) {
      const [a, b, c, d] = inst.bbox_m;
      if (x < a - slack || x > c + slack || y < b - slack || y > d + slack) continue;
      if (pointIn(inst.contour, x, y) || !best) best = inst;
    }
    return best;
  }

  let drag = null;
  canvas.addEventListener("mousedown", (e) => { drag = { x: e.clientX, y: e.clientY, moved: false }; });
  window.addEventListener("mouseup", (e) => {
    if (drag && !drag.moved) {
      const r = canvas.getBoundingClientRect();
      const inst = instanceAt(e.clientX - r.left, e.clientY - r.top);
      if (inst && e.target === canvas) pick(inst);
    }
    drag = null;
    canvas.classList.remove("dragging");
  });
  window.addEventListener("mousemove", (e) => {
    const r = canvas.getBoundingClientRect();
    if (drag) {
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      if (Math.abs(dx) + Math.abs(dy) > 3) { drag.moved = true; canvas.classList.add("dragging"); }
      if (drag.moved) {
        S.view.ox += dx; S.view.oy += dy;
        drag.x = e.clientX; drag.y = e.clientY;
        tip.hidden = true;
        draw();
        return;
      }
    }
    if (e.target !== canvas) { if (S.hover) { S.hover = null; tip.hidden = true; draw(); } return; }
    const inst = instanceAt(e.clientX - r.left, e.clientY - r.top);
    if (inst !== S.hover) { S.hover = inst; draw(); }
    canvas.classList.toggle("hovering", !!inst);
    if (inst) {
      tip.hidden = false;
      tip.innerHTML = "";
      const b = el("b", "", `${inst.color ? inst.color + " " : ""}${inst.label}`);
      tip.appendChild(b);
      tip.appendChild(el("div", "", `id ${inst.id} · ${inst.label_id} of ${inst.num_of_same_class}${inst.region ? " · " + inst.region : ""}`));
      if (inst.description) tip.appendChild(el("div", "", `“${inst.description}” — click to use`));
      const x = Math.min(e.clientX - r.left + 14, r.width - 290);
      tip.style.left = x + "px";
      tip.style.top = e.clientY - r.top + 14 + "px";
    } else tip.hidden = true;
  });
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    const r = canvas.getBoundingClientRect();
    zoom(Math.exp(-e.deltaY * 0.0015), e.clientX - r.left, e.clientY - r.top);
  }, { passive: false });

  function zoom(f, px, py) {
    const x = wx(px), y = wy(py);
    S.view.scale = Math.min(400, Math.max(3, S.view.scale * f));
    S.view.ox = px - x * S.view.scale;
    S.view.oy = py + y * S.view.scale;
    draw();
  }

  function pick(inst) {
    const words = inst.description || `the ${inst.color ? inst.color + " " : ""}${inst.label}`;
    const cur = input.value;
    if (!cur.trim()) input.value = "go to " + words;
    else {
      const at = input.selectionStart ?? cur.length;
      const before = cur.slice(0, at), after = cur.slice(at);
      const sep = before && !before.endsWith(" ") ? " " : "";
      input.value = before + sep + words + (after && !after.startsWith(" ") ? " " : "") + after;
    }
    input.focus();
  }

  // ------------------------------------------------------------------ wiring

  $("form").addEventListener("submit", (e) => { e.preventDefault(); send(false); });
  $("preview").addEventListener("click", () => send(true));
  $("undo").addEventListener("click", undo);
  $("reset").addEventListener("click", reset);
  $("png").addEventListener("click", png);
  $("zoom-in").addEventListener("click", () => { const r = canvas.getBoundingClientRect(); zoom(1.25, r.width / 2, r.height / 2); });
  $("zoom-out").addEventListener("click", () => { const r = canvas.getBoundingClientRect(); zoom(0.8, r.width / 2, r.height / 2); });
  $("zoom-fit").addEventListener("click", fit);
  new ResizeObserver(() => { const first = canvas.width <= 300; resize(); if (first) fit(); }).observe(canvas);

  // Cards of executed turns are marked so undo can grey out the right one.
  new MutationObserver(() => {
    for (const c of log.querySelectorAll(".turn")) {
      if (c.querySelector(".outcome.done, .outcome.failed")) c.dataset.executed = "1";
    }
  }).observe(log, { childList: true, subtree: true });

  window.ivlmap = S; // for the browser test and the curious
  start();
})();
