// gyrofilter live view: reads /stream (Server-Sent Events) and draws on canvases.
// Served by the package itself; no library, nothing fetched from elsewhere.
"use strict";
(() => {
  const AXES = ["x", "y", "z"];
  const COLORS = { x: "#c0392b", y: "#1e8449", z: "#1f5fa8" };
  const RAW_COLOR = "#b8c0c6";
  const GRID = "#e6e9ec";
  const TEXT = "#5f6b73";
  const MIN_SPAN_DPS = 0.02;
  const state = { historyS: 60, windowS: 30, rows: [], raw: [], bias: null, allan: null, dirty: true, ended: false };
  const $ = (id) => document.getElementById(id);

  // ---------------------------------------------------------------- data
  function append(list, rows) {
    if (rows.length && list.length && rows[0][0] < list[list.length - 1][0]) list.length = 0; // time went back
    for (const r of rows) list.push(r);
    if (!list.length) return;
    const oldest = list[list.length - 1][0] - state.historyS;
    let i = 0;
    while (i < list.length && list[i][0] < oldest) i++;
    if (i) list.splice(0, i);
  }

  function fixed(v, digits) { return v === null || v === undefined ? "–" : Number(v).toFixed(digits); }
  function signed(v) { return (v >= 0 ? "+" : "") + v.toFixed(4); }

  function showStatus(s) {
    $("source").textContent = s.source || "";
    $("sample-rate").textContent = s.sample_rate_hz ? `${s.sample_rate_hz} Hz in, ${fixed(s.output_rate_hz, 1)} rows/s out (blocks of ${s.block_len})` : "";
    $("samples-in").textContent = String(s.samples_in);
    $("rows-out").textContent = String(s.rows_out);
    $("lost-samples").textContent = String(s.lost_samples);
    $("rejected").textContent = s.rejected_outliers.join(", ");
    $("calibration").textContent = s.calibration;
    $("bias").textContent = s.bias_dps ? s.bias_dps.map(signed).join(", ") : "–";
    $("temperature").textContent = s.temp_c === null ? "–" : `${s.temp_c.toFixed(2)} °C`;
    $("sensor-time").textContent = s.t_s === null ? "–" : `${s.t_s.toFixed(2)} s`;
    $("viewers").textContent = `${s.clients}; ${s.dropped_frames}`;
    state.bias = s.bias_dps;
    state.allan = s.allan;
    if (s.allan) showAllan(s.allan);
    if (!s.running) ended();
    state.dirty = true;
  }

  function showAllan(a) {
    const body = $("allan");
    body.textContent = "";
    a.tau_s.forEach((tau, i) => {
      const tr = document.createElement("tr");
      const cells = [String(Number(tau.toPrecision(3))), ...a.adev_dps[i].map((v) => v.toExponential(2)),
        `${(100 * a.relative_error[i]).toFixed(0)} %`, String(a.pairs[i])];
      for (const text of cells) {
        const td = document.createElement("td");
        td.textContent = text;
        tr.appendChild(td);
      }
      body.appendChild(tr);
    });
    $("still-time").textContent = `Still so far: ${a.still_s.toFixed(1)} s.`;
  }

  // ---------------------------------------------------------------- drawing
  function fit(canvas) {
    const ratio = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(canvas.clientWidth * ratio));
    const h = Math.max(1, Math.round(canvas.clientHeight * ratio));
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    const ctx = canvas.getContext("2d");
    ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
    return { ctx, w: canvas.clientWidth, h: canvas.clientHeight };
  }

  function niceStep(span, count) {
    const raw = span / count;
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    for (const m of [1, 2, 5, 10]) if (m * mag >= raw) return m * mag;
    return 10 * mag;
  }

  // points of `list` (rows [t, x, y, z]) on axis `a` within [t0, t1], at most two per pixel column
  function columns(list, a, offset, t0, t1, x0, width) {
    const out = [];
    let col = -1, lo = 0, hi = 0;
    for (const r of list) {
      if (r[0] < t0 || r[0] > t1) continue;
      const v = r[1 + a] - offset;
      const c = Math.floor(x0 + (r[0] - t0) / (t1 - t0) * width);
      if (c !== col) {
        if (col >= 0) out.push([col, lo, hi]);
        col = c; lo = v; hi = v;
      } else { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    }
    if (col >= 0) out.push([col, lo, hi]);
    return out;
  }

  // every text a figure draws goes through here: it is kept inside the canvas, a tick label that
  // would overlap one drawn before it (titles first) is left out, and each one drawn is listed in
  // canvas.dataset.labels ({text, kind, x0, y0, x1, y1} in CSS px) for the browser test to check
  function labeller(canvas, ctx, w, h) {
    const boxes = [];
    canvas.dataset.labels = "[]";
    return (text, x, y, align, baseline, kind) => {
      const m = ctx.measureText(text);
      const tw = m.width, th = (m.actualBoundingBoxAscent || 9) + (m.actualBoundingBoxDescent || 2);
      let x0 = align === "right" ? x - tw : align === "center" ? x - tw / 2 : x;
      let y0 = baseline === "bottom" ? y - th : baseline === "middle" ? y - th / 2 : y;
      x0 = Math.min(Math.max(x0, 1), w - tw - 1); y0 = Math.min(Math.max(y0, 1), h - th - 1);
      const box = { text, kind, x0, y0, x1: x0 + tw, y1: y0 + th };
      if (boxes.some((b) => box.x0 < b.x1 + 2 && b.x0 < box.x1 + 2 && box.y0 < b.y1 && b.y0 < box.y1)) {
        if (kind === "tick") return;
      }
      ctx.textAlign = "left"; ctx.textBaseline = "top";
      ctx.fillText(text, x0, y0);
      boxes.push(box);
      canvas.dataset.labels = JSON.stringify(boxes);
    };
  }

  // tick values of one step written with the same number of decimals (0.10, 0.05, 0.00)
  function tickText(v, step) { return v.toFixed(Math.max(0, -Math.floor(Math.log10(step) + 1e-9))); }

  // a power of ten as a tick label: plain from 0.001 to 1000, else 1e-5
  function decade(e) { return e >= -3 && e <= 3 ? String(Number((10 ** e).toFixed(Math.max(0, -e)))) : `1e${e}`; }

  function drawAxis(canvas, a) {
    const { ctx, w, h } = fit(canvas);
    ctx.clearRect(0, 0, w, h);
    const left = 58, right = 8, top = 18, bottom = 32;
    const width = w - left - right, height = h - top - bottom;
    const last = Math.max(state.rows.length ? state.rows[state.rows.length - 1][0] : -Infinity,
      state.raw.length ? state.raw[state.raw.length - 1][0] : -Infinity);
    const t1 = Number.isFinite(last) ? last : state.windowS, t0 = t1 - state.windowS;
    const offset = state.bias ? state.bias[a] : 0;
    const raw = columns(state.raw, a, offset, t0, t1, left, width);
    const filt = columns(state.rows, a, 0, t0, t1, left, width);
    let lo = Infinity, hi = -Infinity;
    for (const p of raw.concat(filt)) { lo = Math.min(lo, p[1]); hi = Math.max(hi, p[2]); }
    if (!Number.isFinite(lo)) { lo = -MIN_SPAN_DPS; hi = MIN_SPAN_DPS; }
    if (hi - lo < MIN_SPAN_DPS) { const mid = (hi + lo) / 2; lo = mid - MIN_SPAN_DPS / 2; hi = mid + MIN_SPAN_DPS / 2; }
    const pad = 0.08 * (hi - lo); lo -= pad; hi += pad;
    const y = (v) => top + (hi - v) / (hi - lo) * height;
    ctx.font = "11px system-ui, sans-serif";
    ctx.lineWidth = 1;
    ctx.strokeStyle = GRID; ctx.fillStyle = TEXT;
    const label = labeller(canvas, ctx, w, h);
    label(`${AXES[a]}: rate (deg/s)`, 4, 3, "left", "top", "y-title");
    label("sensor time (s)", w - right, h - 2, "right", "bottom", "x-title");
    const ys = niceStep(hi - lo, 6);
    for (let k = Math.ceil(lo / ys); k * ys <= hi; k++) {
      const v = k * ys;
      ctx.beginPath(); ctx.moveTo(left, y(v)); ctx.lineTo(left + width, y(v)); ctx.stroke();
      label(tickText(k === 0 ? 0 : v, ys), left - 4, y(v), "right", "middle", "tick");
    }
    const xs = niceStep(state.windowS, 6);
    for (let k = Math.ceil(t0 / xs); k * xs <= t1; k++) {
      const x = left + (k * xs - t0) / (t1 - t0) * width;
      ctx.beginPath(); ctx.moveTo(x, top); ctx.lineTo(x, top + height); ctx.stroke();
      label(tickText(k * xs, xs), x, top + height + 3, "center", "top", "tick");
    }
    for (const [points, color, lineWidth] of [[raw, RAW_COLOR, 1], [filt, COLORS[AXES[a]], 1.5]]) {
      if (!points.length) continue;
      ctx.strokeStyle = color; ctx.lineWidth = lineWidth;
      ctx.beginPath();
      points.forEach(([c, l, u], i) => {
        if (i === 0) ctx.moveTo(c, y(l)); else ctx.lineTo(c, y(l));
        if (u !== l) ctx.lineTo(c, y(u));
      });
      ctx.stroke();
    }
  }

  function drawAllan(canvas) {
    const { ctx, w, h } = fit(canvas);
    ctx.clearRect(0, 0, w, h);
    const a = state.allan;
    ctx.font = "11px system-ui, sans-serif"; ctx.fillStyle = TEXT;
    const label = labeller(canvas, ctx, w, h);
    if (!a || !a.tau_s.length) {
      label("waiting for still data (9 cluster pairs at least)", w / 2, h / 2, "center", "middle", "note");
      return;
    }
    const left = 48, right = 12, top = 18, bottom = 32;
    const width = w - left - right, height = h - top - bottom;
    const values = a.adev_dps.flat().filter((v) => v > 0);
    // at least one decade; no `|| fallback`: a top decade of 1e0 s is 0 (or -0), which is false
    const lx0 = Math.floor(Math.log10(a.tau_s[0])), lx1 = Math.max(lx0 + 1, Math.ceil(Math.log10(a.tau_s[a.tau_s.length - 1]) - 1e-9));
    const ly0 = Math.floor(Math.log10(Math.min(...values))), ly1 = Math.ceil(Math.log10(Math.max(...values)) + 1e-9);
    const X = (t) => left + (Math.log10(t) - lx0) / Math.max(1, lx1 - lx0) * width;
    const Y = (v) => top + (ly1 - Math.log10(v)) / Math.max(1, ly1 - ly0) * height;
    label("Allan deviation (deg/s)", 4, 3, "left", "top", "y-title");
    label("cluster time tau (s)", w - right, h - 2, "right", "bottom", "x-title");
    AXES.forEach((name, i) => {
      ctx.fillStyle = COLORS[name];
      label(name, w - right - 14 * (AXES.length - i), 3, "left", "top", "legend");
    });
    ctx.fillStyle = TEXT;
    ctx.strokeStyle = GRID; ctx.lineWidth = 1;
    for (let e = lx0; e <= Math.max(lx1, lx0 + 1); e++) {
      ctx.beginPath(); ctx.moveTo(X(10 ** e), top); ctx.lineTo(X(10 ** e), top + height); ctx.stroke();
      label(decade(e), X(10 ** e), top + height + 3, "center", "top", "tick");
    }
    for (let e = ly0; e <= Math.max(ly1, ly0 + 1); e++) {
      ctx.beginPath(); ctx.moveTo(left, Y(10 ** e)); ctx.lineTo(left + width, Y(10 ** e)); ctx.stroke();
      label(decade(e), left - 4, Y(10 ** e), "right", "middle", "tick");
    }
    AXES.forEach((name, i) => {
      ctx.strokeStyle = COLORS[name]; ctx.lineWidth = 1.5;
      ctx.beginPath();
      a.tau_s.forEach((t, k) => {
        const v = a.adev_dps[k][i];
        if (!(v > 0)) return;
        if (k === 0) ctx.moveTo(X(t), Y(v)); else ctx.lineTo(X(t), Y(v));
      });
      ctx.stroke();
    });
  }

  function draw() {
    if (!state.dirty) return;
    state.dirty = false;
    AXES.forEach((name, a) => drawAxis($(`plot-${name}`), a));
    drawAllan($("plot-allan"));
  }

  // ---------------------------------------------------------------- the stream
  function badge(text, cls) {
    const el = $("connection");
    el.textContent = text;
    el.className = `badge ${cls || ""}`;
  }

  function ended() {
    if (state.ended) return;
    state.ended = true;
    badge("run ended", "ended");
    events.close();
  }

  const events = new EventSource("/stream");
  events.addEventListener("open", () => badge("live", "live"));
  events.addEventListener("error", () => {
    if (state.ended) return;
    badge(events.readyState === EventSource.CLOSED ? "not connected (the run ended, or too many viewers)" : "reconnecting", "lost");
  });
  events.addEventListener("hello", (e) => {
    const d = JSON.parse(e.data);
    state.historyS = d.history_s;
    state.rows = d.rows;
    state.raw = d.raw;
    showStatus(d.status);
  });
  events.addEventListener("rows", (e) => {
    const d = JSON.parse(e.data);
    append(state.rows, d.rows);
    append(state.raw, d.raw);
    state.dirty = true;
  });
  events.addEventListener("status", (e) => showStatus(JSON.parse(e.data)));

  $("window").addEventListener("change", (e) => { state.windowS = Number(e.target.value); state.dirty = true; });
  window.addEventListener("resize", () => { state.dirty = true; });
  setInterval(draw, 100);
})();
