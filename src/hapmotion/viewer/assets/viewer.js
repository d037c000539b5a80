/* hapmotion viewer: plays a rendered recording (skeleton, motion salient triangle, dynamic point, ray, vest
 * intensities, timeline, music) or a live `hapmotion live` WebSocket broadcast. Self-contained: no library, no
 * network except the optional live WebSocket. Data layout: see hapmotion/viewer/packing.py and page.py.
 *
 * Test hook (read-only): window.hapmotionViewer.state() returns a copy of what is displayed now. */
(function () {
  "use strict";

  const $ = (id) => document.getElementById(id);
  const DATA = JSON.parse($("hm-data").textContent);
  const CHART_NAMES = { "-1": "none", 0: "front", 1: "back", 2: "performer-left shoulder", 3: "performer-right shoulder" };
  const LIVE_WINDOW_S = 20;        // seconds of history kept on the live timeline
  const LIVE_STALL_S = 1.0;        // no frame for this long: show "stalled" and blank the vest
  const MISSING = -32768;          // int16 sentinel of a missing point (page.py)

  const S = {
    ready: false, mode: "file", playing: false, time: 0, rate: 1, trackIdx: 0,
    frame: -1, motionFrame: -1, intensities: null, level: null, chart: null, distance: null, active: [0, 0],
    shown: { joints: 0, triangle: false, dynamicPoint: false, hitPoint: false }, scaleChoice: "fit", scaleTop: 100,
    live: { url: null, connected: false, hello: null, seq: -1, frames: 0, dropped: 0, stopped: false, bad: 0,
            lastAt: 0, stalled: false, retries: 0 },
    stats: { loadMs: null, firstDrawMs: null, drawMs: [], frameGapMs: [] },
    error: null,
  };
  let TRACKS = [];      // decoded tracks
  let MOTION = null;    // decoded motion
  let AUDIO = null;     // {el, waveform, onsets, offset}
  let N_ACT = DATA.actuators.length;
  let ACT_IDS = DATA.actuators.slice();
  let JOINTS = DATA.joints.slice();
  let BONES = DATA.bones.slice();

  // ------------------------------------------------------------------ decoding of packed blobs
  const TYPED = { uint8: Uint8Array, int8: Int8Array, uint16: Uint16Array, int16: Int16Array };

  function base64Bytes(text) {
    if (typeof Uint8Array.fromBase64 === "function") return Uint8Array.fromBase64(text);
    const bin = atob(text);
    const out = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
    return out;
  }

  async function inflate(bytes) {
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  }

  /* Blob descriptor -> {arr: typed array of stored integers, shape, scale}. Undoes base64, zlib, byte shuffle and
   * delta coding (running sum in the stored type: typed-array stores wrap exactly like numpy). */
  async function decodeBlob(meta) {
    const el = document.getElementById(meta.id);
    if (!el) throw new Error("page data is incomplete: missing block " + meta.id);
    const raw = await inflate(base64Bytes(el.textContent.trim()));
    el.remove();
    const T = TYPED[meta.dtype];
    const k = T.BYTES_PER_ELEMENT;
    const n = meta.shape.reduce((a, b) => a * b, 1);
    if (raw.length !== n * k) throw new Error("page data block " + meta.id + " has " + raw.length + " bytes, expected " + n * k);
    let bytes = raw;
    if (k > 1) {
      bytes = new Uint8Array(n * k);
      for (let b = 0; b < k; b++) {
        const off = b * n;
        for (let i = 0; i < n; i++) bytes[i * k + b] = raw[off + i];
      }
    }
    const arr = new T(bytes.buffer, 0, n);
    if (meta.delta && meta.shape[0] > 1) {
      const row = n / meta.shape[0];
      for (let i = row; i < n; i++) arr[i] = arr[i] + arr[i - row];
    }
    return { arr: arr, shape: meta.shape, scale: meta.scale };
  }

  async function decodeAll() {
    const jobs = [];
    const put = (obj, key, meta) => { if (meta) jobs.push(decodeBlob(meta).then((v) => { obj[key] = v; })); };
    if (DATA.motion) {
      MOTION = { fps: DATA.motion.fps, n: DATA.motion.n_frames, joints: DATA.motion.joints, floor: DATA.motion.floor_y };
      put(MOTION, "pos", DATA.motion.positions);
    }
    for (const t of DATA.tracks) {
      const tr = { info: t, fps: t.fps, n: t.n_frames, debug: {} };
      put(tr, "I", t.intensities);
      for (const key of Object.keys(t.debug || {})) put(tr.debug, key, t.debug[key]);
      TRACKS.push(tr);
    }
    if (DATA.audio) {
      AUDIO = { info: DATA.audio, offset: DATA.audio.offset_s || 0, onsets: DATA.audio.onsets || [] };
      put(AUDIO, "waveform", DATA.audio.waveform);
      jobs.push(decodeBlob(DATA.audio.data).then((v) => {
        const blob = new Blob([new Uint8Array(v.arr.buffer, v.arr.byteOffset, v.arr.length)], { type: DATA.audio.mime });
        AUDIO.url = URL.createObjectURL(blob);
      }));
    }
    await Promise.all(jobs);
    for (const tr of TRACKS) {
      // Total intensity per frame: sum over actuators (Player units), computed once.
      const tot = new Float32Array(tr.n);
      const I = tr.I.arr;
      let peak = 0;
      for (let f = 0; f < tr.n; f++) {
        let s = 0;
        for (let a = 0, o = f * N_ACT; a < N_ACT; a++) s += I[o + a];
        tot[f] = s;
        if (s > peak) peak = s;
      }
      tr.total = tot;
      tr.totalPeak = peak;
      let top = 0;
      for (let i = 0; i < I.length; i++) if (I[i] > top) top = I[i];
      tr.peak = top;
    }
  }

  // ------------------------------------------------------------------ colours
  const LUT = DATA.colors;  // 101 CSS colours for intensities 0..100
  const BRIGHT_FROM = DATA.bright_from;  // from this intensity on, the label text is dark
  const LUT_RGB = LUT.map((c) => [parseInt(c.slice(1, 3), 16), parseInt(c.slice(3, 5), 16), parseInt(c.slice(5, 7), 16)]);
  /* Colour index 0..100 of an intensity under the current colour scale (top = S.scaleTop); 0 stays "off". */
  const colorIndex = (v) => (v <= 0 ? 0 : Math.max(1, Math.min(100, Math.round((v * 100) / S.scaleTop))));
  const colorOf = (v) => LUT[colorIndex(v)];
  const fitTop = (peak) => DATA.scale_tops.find((t) => peak <= t) || 100;

  function setScale(choice) {
    S.scaleChoice = choice;
    const peak = S.mode === "file" ? track().peak : LIVE.peak;
    S.scaleTop = choice === "fit" ? fitTop(peak) : 100;
    $("scale-top").textContent = String(S.scaleTop);
    for (const c of CELLS) if (c) c.last = -1;
    showIntensities(S.intensities);
    if (timeline) timeline.dirty = true;
  }

  function drawColorbar() {
    const c = $("colorbar-canvas");
    const g = c.getContext("2d");
    for (let x = 0; x < c.width; x++) {
      g.fillStyle = LUT[Math.round((x / (c.width - 1)) * 100)];
      g.fillRect(x, 0, 1, c.height);
    }
  }

  // ------------------------------------------------------------------ vest panels
  const CELLS = [];      // per actuator column: {el, val, last}
  function buildVest() {
    const root = $("vest");
    root.textContent = "";
    CELLS.length = 0;
    for (let i = 0; i < N_ACT; i++) CELLS.push(null);
    const colOf = new Map(ACT_IDS.map((id, i) => [id, i]));
    const devices = DATA.devices.filter((d) => ACT_IDS.some((id) => id.startsWith(d.name + "_")));
    // Devices of a live hello that the page does not know: one row each.
    const known = new Set(devices.map((d) => d.name));
    for (const id of ACT_IDS) {
      const name = id.replace(/_\d+$/, "");
      if (!known.has(name)) {
        const count = ACT_IDS.filter((x) => x.replace(/_\d+$/, "") === name).length;
        devices.push({ name: name, rows: 1, cols: count, title: name, subtitle: "", left: "", right: "", top: "", bottom: "" });
        known.add(name);
      }
    }
    const panels = new Map();
    for (const d of devices) {
      const panel = document.createElement("div");
      panel.className = "panel";
      panel.dataset.device = d.name;
      panels.set(d.name, panel);
      const title = document.createElement("div");
      title.className = "ptitle";
      title.textContent = d.title;
      if (d.subtitle) { const s = document.createElement("small"); s.textContent = d.subtitle; title.appendChild(s); }
      panel.appendChild(title);
      for (const [cls, text] of [["edge-top", d.top], ["edge-bottom", d.bottom], ["edge-l", d.left], ["edge-r", d.right]]) {
        const e = document.createElement("div");
        e.className = "edge " + cls;
        e.textContent = text || "";
        panel.appendChild(e);
      }
      const grid = document.createElement("div");
      grid.className = "grid";
      grid.style.gridTemplateColumns = "repeat(" + d.cols + ", auto)";
      for (let r = 0; r < d.rows; r++) {
        for (let c = 0; c < d.cols; c++) {
          const index = r * d.cols + c;
          const id = d.name + "_" + index;
          const cell = document.createElement("div");
          cell.className = "act";
          cell.dataset.id = id;
          cell.dataset.intensity = "0";
          const idx = document.createElement("span");
          idx.className = "idx";
          idx.textContent = index;
          const val = document.createElement("span");
          val.className = "val";
          cell.append(idx, val);
          // a cell with a name of its own (a glove's fingertips and wrist) shows it and says it in its tooltip
          const label = Array.isArray(d.labels) && typeof d.labels[index] === "string" ? d.labels[index] : "";
          if (label) {
            cell.dataset.label = label;
            const lab = document.createElement("span");
            lab.className = "lab";
            lab.textContent = label;
            cell.append(lab);
          }
          const col = colOf.has(id) ? colOf.get(id) : -1;
          cell.title = id + (label ? " (" + label + ")" : "") + (col < 0 ? " (not in this track)" : "");
          if (col < 0) cell.classList.add("missing");
          else CELLS[col] = { el: cell, val: val, last: -1 };
          grid.appendChild(cell);
        }
      }
      panel.appendChild(grid);
    }
    // Where each part sits on the wearer (page.py sends the panels in that order, hapmotion/viewer/bodymap.py):
    // left shoulder, chest, right shoulder side by side (wearer's left on the left), the gloves in a row of their
    // own under them (left hand on the left), then the back as seen from behind; any other device after them.
    for (const place of ["front", "hands"]) {
      const row = document.createElement("div");
      row.className = "body-front body-" + place;
      for (const d of devices) if (d.place === place) row.appendChild(panels.get(d.name));
      if (row.childElementCount) root.appendChild(row);
    }
    for (const d of devices) if (d.place === "back") root.appendChild(panels.get(d.name));
    for (const d of devices) if (!["front", "hands", "back"].includes(d.place)) root.appendChild(panels.get(d.name));
  }

  /* Back under the front when the vest panel has the height for it (a tall window), else beside it: the first
   * arrangement whose content the panel shows without scrolling. Called at start and on every resize. */
  function fitVest() {
    const vest = $("vest"), side = $("side");
    vest.classList.add("stacked");
    if (side.scrollHeight > side.clientHeight || side.scrollWidth > side.clientWidth) vest.classList.remove("stacked");
  }

  function showIntensities(values) {
    for (let i = 0; i < N_ACT; i++) {
      const c = CELLS[i];
      if (!c) continue;
      const v = values ? Math.max(0, Math.min(100, Math.round(values[i]))) : 0;
      if (v === c.last) continue;
      c.last = v;
      const k = colorIndex(v);
      c.el.style.background = LUT[k];
      c.el.dataset.intensity = String(v);
      c.el.dataset.color = String(k);
      c.val.textContent = v > 0 ? String(v) : "";
      c.el.classList.toggle("bright", k >= BRIGHT_FROM);
    }
  }

  // ------------------------------------------------------------------ 3D scene (canvas projection, orbit, zoom)
  const V = {
    sub: (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]],
    add: (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]],
    mul: (a, s) => [a[0] * s, a[1] * s, a[2] * s],
    dot: (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2],
    cross: (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]],
    norm: (a) => { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; },
    ok: (a) => !!a && isFinite(a[0]) && isFinite(a[1]) && isFinite(a[2]),
  };

  class Scene {
    constructor(canvas) {
      this.canvas = canvas;
      this.g = canvas.getContext("2d");
      this.yaw = 0; this.pitch = 0.18; this.dist = 2.9; this.target = [0, 1, 0];
      this.follow = true; this.fov = 0.75; this.frameData = null; this.floor = 0; this.panned = [0, 0, 0];
      this.dirty = true;
      let drag = null;
      canvas.addEventListener("pointerdown", (e) => {
        drag = { x: e.clientX, y: e.clientY, pan: e.shiftKey || e.button === 2 };
        canvas.setPointerCapture(e.pointerId);
      });
      canvas.addEventListener("pointermove", (e) => {
        if (!drag) return;
        const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
        drag.x = e.clientX; drag.y = e.clientY;
        if (drag.pan) {
          const b = this.basis();
          const k = this.dist / this.focal();
          this.panned = V.add(this.panned, V.add(V.mul(b.r, -dx * k), V.mul(b.u, dy * k)));
        } else {
          this.yaw -= dx * 0.008;
          this.pitch = Math.max(-1.45, Math.min(1.45, this.pitch + dy * 0.006));
        }
        this.dirty = true;
      });
      canvas.addEventListener("pointerup", () => { drag = null; });
      canvas.addEventListener("contextmenu", (e) => e.preventDefault());
      canvas.addEventListener("wheel", (e) => {
        e.preventDefault();
        this.dist = Math.max(0.8, Math.min(40, this.dist * Math.exp(e.deltaY * 0.0012)));
        this.dirty = true;
      }, { passive: false });
      canvas.addEventListener("dblclick", () => { this.panned = [0, 0, 0]; this.dist = 2.9; this.setView("audience"); });
    }
    focal() { return (this.canvas.height / 2) / Math.tan(this.fov / 2); }
    center() { return V.add(this.target, this.panned); }
    eye() {
      const c = this.center();
      const cp = Math.cos(this.pitch);
      return V.add(c, V.mul([cp * Math.sin(this.yaw), Math.sin(this.pitch), cp * Math.cos(this.yaw)], this.dist));
    }
    basis() {
      const f = V.norm(V.sub(this.center(), this.eye()));
      const r = V.norm(V.cross(f, [0, 1, 0]));
      const u = V.cross(r, f);
      return { f: f, r: r, u: u };
    }
    /* Camera placement relative to the performer's facing direction (horizontal forward vector). */
    setView(kind) {
      const fwd = this.performerForward();
      const base = Math.atan2(fwd[0], fwd[2]);
      this.yaw = kind === "behind" ? base + Math.PI : kind === "side" ? base - Math.PI / 2 : base + 0.35;
      this.pitch = 0.18;
      this.dirty = true;
    }
    performerForward() {
      const d = this.frameData;
      const J = (n) => d && d.joints ? d.joints[JOINTS.indexOf(n)] : null;
      const sl = J("SHOULDER_LEFT"), sr = J("SHOULDER_RIGHT"), nk = J("NECK"), pv = J("PELVIS");
      if (!V.ok(sl) || !V.ok(sr) || !V.ok(nk) || !V.ok(pv)) return [0, 0, 1];
      // forward = up x right (out of the chest), the same body frame as the renderer (docs/algorithm.md, Conventions).
      const f = V.cross(V.sub(nk, pv), V.sub(sr, sl));
      const h = [f[0], 0, f[2]];
      return Math.hypot(h[0], h[2]) > 1e-6 ? V.norm(h) : [0, 0, 1];
    }
    resize() {
      const dpr = window.devicePixelRatio || 1;
      const w = Math.max(10, Math.round(this.canvas.clientWidth * dpr));
      const h = Math.max(10, Math.round(this.canvas.clientHeight * dpr));
      if (w !== this.canvas.width || h !== this.canvas.height) { this.canvas.width = w; this.canvas.height = h; this.dirty = true; }
    }
    setFrame(d) {
      this.frameData = d;
      if (this.follow && d && d.joints) {
        const pv = d.joints[JOINTS.indexOf("PELVIS")], nk = d.joints[JOINTS.indexOf("NECK")];
        if (V.ok(pv) && V.ok(nk)) this.target = [(pv[0] + nk[0]) / 2, (pv[1] + nk[1]) / 2, (pv[2] + nk[2]) / 2];
      }
      this.dirty = true;
    }
    draw() {
      if (!this.dirty) return;
      this.dirty = false;
      this.resize();
      const g = this.g, W = this.canvas.width, H = this.canvas.height, dpr = window.devicePixelRatio || 1;
      g.clearRect(0, 0, W, H);
      const eye = this.eye(), b = this.basis(), F = this.focal();
      const NEAR = 0.05;
      const cam = (p) => { const d = V.sub(p, eye); return [V.dot(d, b.r), V.dot(d, b.u), V.dot(d, b.f)]; };
      const screen = (q) => [W / 2 + (F * q[0]) / q[2], H / 2 - (F * q[1]) / q[2], q[2]];
      const P = (p) => {
        if (!V.ok(p)) return null;
        const q = cam(p);
        return q[2] < NEAR ? null : screen(q);
      };
      const line = (a, c, color, width, dash) => {
        if (!V.ok(a) || !V.ok(c)) return;
        let qa = cam(a), qc = cam(c);
        if (qa[2] < NEAR && qc[2] < NEAR) return;
        // Clip the part behind the camera (near plane), so long floor lines stay drawn when the camera is close.
        if (qa[2] < NEAR || qc[2] < NEAR) {
          const k = (NEAR - qa[2]) / (qc[2] - qa[2]);
          const cut = [qa[0] + k * (qc[0] - qa[0]), qa[1] + k * (qc[1] - qa[1]), NEAR];
          if (qa[2] < NEAR) qa = cut; else qc = cut;
        }
        const pa = screen(qa), pc = screen(qc);
        g.strokeStyle = color; g.lineWidth = width * dpr; g.setLineDash(dash ? dash.map((x) => x * dpr) : []);
        g.beginPath(); g.moveTo(pa[0], pa[1]); g.lineTo(pc[0], pc[1]); g.stroke();
      };
      const dot = (p, r, fill, stroke) => {
        const q = P(p);
        if (!q) return null;
        const rr = Math.max(1.5, (r * F) / q[2]);
        g.beginPath(); g.arc(q[0], q[1], rr, 0, 2 * Math.PI);
        if (fill) { g.fillStyle = fill; g.fill(); }
        if (stroke) { g.setLineDash([]); g.strokeStyle = stroke; g.lineWidth = 2 * dpr; g.stroke(); }
        return q;
      };
      // Floor grid (1 m), around the performer, to read depth and travel.
      const c = this.center();
      const y0 = this.floor;
      const cx = Math.round(c[0]), cz = Math.round(c[2]);
      for (let k = -4; k <= 4; k++) {
        line([cx + k, y0, cz - 4], [cx + k, y0, cz + 4], "#262b35", 1);
        line([cx - 4, y0, cz + k], [cx + 4, y0, cz + k], "#262b35", 1);
      }
      const d = this.frameData;
      if (!d || !d.joints) {
        g.fillStyle = "#6f7888"; g.font = 14 * dpr + "px sans-serif"; g.textAlign = "center";
        g.fillText(S.mode === "live" ? "waiting for skeleton frames" : "no skeleton in this page", W / 2, H / 2);
        return;
      }
      const J = d.joints;
      // Performer's facing direction, drawn on the floor under the pelvis.
      const pv = J[JOINTS.indexOf("PELVIS")];
      if (V.ok(pv)) {
        const fwd = this.performerForward();
        const a = [pv[0], y0, pv[2]], tip = V.add(a, V.mul(fwd, 0.6));
        line(a, tip, "#3d4656", 3);
        const q = P(tip);
        if (q) { g.fillStyle = "#6f7888"; g.font = 11 * dpr + "px sans-serif"; g.textAlign = "center"; g.fillText("performer faces", q[0], q[1] + 14 * dpr); }
      }
      // Motion salient triangle under the skeleton.
      if (d.tri) {
        const q = d.tri.map(P);
        if (q[0] && q[1] && q[2]) {
          g.setLineDash([]);
          g.fillStyle = "rgba(186, 104, 200, 0.38)"; g.strokeStyle = "rgba(225, 170, 235, 0.95)"; g.lineWidth = 2 * dpr;
          g.beginPath(); g.moveTo(q[0][0], q[0][1]); g.lineTo(q[1][0], q[1][1]); g.lineTo(q[2][0], q[2][1]); g.closePath();
          g.fill(); g.stroke();
        }
      }
      for (const [p, ch] of BONES) {
        const side = sideOf(JOINTS[ch]);
        line(J[p], J[ch], side === "L" ? "#4fc3f7" : side === "R" ? "#ffb74d" : "#cfd8dc", 3);
      }
      for (let j = 0; j < J.length; j++) {
        const side = sideOf(JOINTS[j]);
        dot(J[j], 0.022, side === "L" ? "#4fc3f7" : side === "R" ? "#ffb74d" : "#cfd8dc");
      }
      // Active joint(s): rings on the hands the renderer picked.
      const hands = [J[JOINTS.indexOf("HAND_LEFT")], J[JOINTS.indexOf("HAND_RIGHT")]];
      for (let h = 0; h < 2; h++) if (d.active && d.active[h]) dot(hands[h], 0.075, null, "#fff176");
      g.font = "bold " + 12 * dpr + "px sans-serif"; g.textAlign = "center";
      for (let h = 0; h < 2; h++) {
        const q = P(hands[h]);
        if (q) { g.fillStyle = h === 0 ? "#4fc3f7" : "#ffb74d"; g.fillText(h === 0 ? "L" : "R", q[0], q[1] - 12 * dpr); }
      }
      // Ray from the dynamic point towards the target point; solid to the hit on the vest, dashed beyond.
      if (d.dp && d.hit) line(d.dp, d.hit, "#7CFC9A", 2.5);
      if (d.hit && d.target) line(d.hit, d.target, "rgba(124, 252, 154, 0.5)", 1.5, [5, 4]);
      else if (d.dp && d.target) line(d.dp, d.target, "rgba(124, 252, 154, 0.5)", 1.5, [5, 4]);
      if (d.target) dot(d.target, 0.018, "rgba(124, 252, 154, 0.6)");
      if (d.hit) dot(d.hit, 0.035, "#7CFC9A", "#0b3d1a");
      if (d.dp) dot(d.dp, 0.045, "#ff4fd8", "#ffffff");
    }
  }

  function sideOf(name) {
    if (!name) return "C";
    if (name.endsWith("_LEFT")) return "L";
    if (name.endsWith("_RIGHT")) return "R";
    return "C";
  }

  // ------------------------------------------------------------------ timeline
  class Timeline {
    constructor(bg, head) {
      this.bg = bg; this.head = head;
      this.t0 = 0; this.t1 = 1; this.dirty = true; this.lanes = [];
      let dragging = false;
      const seekAt = (e) => {
        const r = head.getBoundingClientRect();
        const x = e.clientX - r.left;
        if (x < this.gutterCss()) return;
        seek(this.t0 + ((x - this.gutterCss()) / Math.max(1, r.width - this.gutterCss())) * (this.t1 - this.t0));
      };
      head.addEventListener("pointerdown", (e) => { if (S.mode !== "file") return; dragging = true; head.setPointerCapture(e.pointerId); seekAt(e); });
      head.addEventListener("pointermove", (e) => { if (dragging) seekAt(e); });
      head.addEventListener("pointerup", () => { dragging = false; });
      head.addEventListener("wheel", (e) => {
        if (S.mode !== "file") return;
        e.preventDefault();
        const r = head.getBoundingClientRect();
        const frac = Math.max(0, Math.min(1, (e.clientX - r.left - this.gutterCss()) / Math.max(1, r.width - this.gutterCss())));
        const tm = this.t0 + frac * (this.t1 - this.t0);
        const span = Math.max(0.5, Math.min(duration(), (this.t1 - this.t0) * Math.exp(e.deltaY * 0.0015)));
        this.setWindow(tm - frac * span, tm - frac * span + span);
      }, { passive: false });
    }
    gutterCss() { return 92; }
    setWindow(a, b) {
      const D = Math.max(duration(), 1e-3);
      const span = Math.min(b - a, D);
      a = Math.max(0, Math.min(a, D - span));
      this.t0 = a; this.t1 = a + span; this.dirty = true;
    }
    resize() {
      const dpr = window.devicePixelRatio || 1;
      for (const c of [this.bg, this.head]) {
        const w = Math.max(10, Math.round(c.clientWidth * dpr)), h = Math.max(10, Math.round(c.clientHeight * dpr));
        if (w !== c.width || h !== c.height) { c.width = w; c.height = h; this.dirty = true; }
      }
    }
    /* Lane geometry in device pixels: heat map, total intensity, motion energy, audio. The lanes share the canvas
     * height in fixed proportions (the canvas follows the window height, see --timeline-h) above a 16 px time axis. */
    layout() {
      const dpr = window.devicePixelRatio || 1, H = this.bg.height;
      const parts = [["heat", "actuators", 80], ["total", "total intensity", 50], ["energy", "motion energy", 36], ["audio", "audio", 36]];
      const GAP = 6, AXIS = 16;
      const k = Math.max(0.5, (H / dpr - AXIS - GAP * parts.length) / parts.reduce((a, p) => a + p[2], 0));
      const lanes = [];
      let y = GAP * dpr;
      for (const [key, label, h] of parts) { lanes.push({ key: key, label: label, y: y, h: Math.floor(h * k) * dpr }); y += (Math.floor(h * k) + GAP) * dpr; }
      this.axisY = Math.min(H - 2, y);
      this.lanes = lanes;
      return lanes;
    }
    /* Draw a label and remember its box (CSS pixels in the canvas) for the test hook's layout check. */
    label(g, text, x, y, dpr) {
      g.fillText(text, x, y);
      const w = g.measureText(text).width / dpr, h = parseFloat(g.font) / dpr;
      const left = g.textAlign === "right" ? x / dpr - w : g.textAlign === "center" ? x / dpr - w / 2 : x / dpr;
      this.labels.push({ text: text, x: left, y: y / dpr - h / 2, w: w, h: h });
    }
    drawBackground() {
      this.resize();
      if (!this.dirty) return;
      this.dirty = false;
      const g = this.bg.getContext("2d"), W = this.bg.width, H = this.bg.height, dpr = window.devicePixelRatio || 1;
      g.clearRect(0, 0, W, H);
      this.labels = [];
      const x0 = this.gutterCss() * dpr, PW = Math.max(1, W - x0 - 4 * dpr);
      const src = timelineSource();
      const t0 = this.t0, t1 = this.t1;
      g.font = 11 * dpr + "px sans-serif"; g.textBaseline = "middle";
      for (const lane of this.layout()) {
        g.fillStyle = "#14171d"; g.fillRect(x0, lane.y, PW, lane.h);
        g.fillStyle = "#9aa3b2"; g.textAlign = "right";
        if (lane.key !== "heat") this.label(g, lane.label, x0 - 8 * dpr, lane.y + lane.h / 2, dpr);
        if (lane.key === "heat") this.drawHeat(g, src, lane, x0, PW, t0, t1, dpr);
        else if (lane.key === "total") this.drawCurve(g, src.total, lane, x0, PW, t0, t1, "#80cbc4", true, dpr);
        else if (lane.key === "energy") this.drawCurve(g, src.energy, lane, x0, PW, t0, t1, "#ce93d8", false, dpr);
        else if (lane.key === "audio") this.drawAudio(g, src.audio, lane, x0, PW, t0, t1, dpr);
      }
      // Time axis.
      const span = t1 - t0;
      const steps = [0.1, 0.2, 0.5, 1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800];
      const step = steps.find((s) => (PW / (span / s)) > 70 * dpr) || 3600;
      g.fillStyle = "#9aa3b2"; g.textAlign = "center"; g.strokeStyle = "#2c313c"; g.lineWidth = 1;
      const live = S.mode === "live";
      // Live: ticks counted back from the newest frame ("now"); file: time from the start.
      const first = live ? t1 - Math.floor(span / step) * step : Math.ceil(t0 / step) * step;
      for (let t = first; t <= t1 + 1e-9; t += step) {
        const x = x0 + ((t - t0) / span) * PW;
        g.beginPath(); g.moveTo(x, 0); g.lineTo(x, this.axisY); g.stroke();
        g.textAlign = x > x0 + PW - 20 * dpr ? "right" : "center";
        const label = live ? (Math.abs(t1 - t) < 1e-6 ? "now" : "-" + fmtTime(t1 - t, step < 1)) : fmtTime(t, step < 1);
        this.label(g, label, x, this.axisY + 8 * dpr, dpr);
      }
    }
    /* Max over the frames under each pixel column, so short pulses stay visible when zoomed out. */
    drawHeat(g, src, lane, x0, PW, t0, t1, dpr) {
      if (!src.heat) return this.noData(g, lane, x0, PW, "no track", dpr);
      const { I, fps, n, nAct } = src.heat;
      const cols = Math.max(1, Math.floor(PW));
      const img = g.createImageData(cols, nAct);
      const px = img.data;
      for (let x = 0; x < cols; x++) {
        const ta = t0 + (x / cols) * (t1 - t0), tb = t0 + ((x + 1) / cols) * (t1 - t0);
        const fa = Math.floor(ta * fps - src.heat.f0), fb = Math.max(fa + 1, Math.floor(tb * fps - src.heat.f0));
        for (let a = 0; a < nAct; a++) {
          let m = 0;
          for (let f = Math.max(0, fa); f < Math.min(n, fb); f++) { const v = I[f * nAct + a]; if (v > m) m = v; }
          const c = LUT_RGB[colorIndex(m)], o = (a * cols + x) * 4;
          px[o] = c[0]; px[o + 1] = c[1]; px[o + 2] = c[2]; px[o + 3] = 255;
        }
      }
      const tmp = document.createElement("canvas");
      tmp.width = cols; tmp.height = nAct;
      tmp.getContext("2d").putImageData(img, 0, 0);
      g.imageSmoothingEnabled = false;
      g.drawImage(tmp, x0, lane.y, PW, lane.h);
      // Group boundaries and names (front, back, sleeves). The two sleeves have 6 rows each of the lane's 52:
      // their names are spread to one line apart (kept inside the lane) so they never print over each other.
      g.textAlign = "left"; g.font = 10 * dpr + "px sans-serif";
      const groups = groupsOf(ACT_IDS), LINE = 11 * dpr, ys = [];
      for (const grp of groups) {
        const ya = lane.y + (grp.start / nAct) * lane.h, yb = lane.y + ((grp.start + grp.count) / nAct) * lane.h;
        g.strokeStyle = "#e6e8ec"; g.lineWidth = 1;
        if (grp.start > 0) { g.beginPath(); g.moveTo(x0, ya); g.lineTo(x0 + PW, ya); g.stroke(); }
        ys.push(Math.max((ya + yb) / 2, ys.length ? ys[ys.length - 1] + LINE : lane.y + LINE / 2));
      }
      for (let i = ys.length - 1; i >= 0; i--) ys[i] = Math.min(ys[i], i + 1 < ys.length ? ys[i + 1] - LINE : lane.y + lane.h - LINE / 2);
      g.fillStyle = "#9aa3b2"; g.textAlign = "right";
      groups.forEach((grp, i) => this.label(g, grp.short, x0 - 4 * dpr, ys[i], dpr));
      g.font = 11 * dpr + "px sans-serif";
    }
    drawCurve(g, cur, lane, x0, PW, t0, t1, color, fill, dpr) {
      if (!cur || !cur.v) return this.noData(g, lane, x0, PW, cur && cur.why ? cur.why : "not available", dpr);
      const { v, fps, f0 } = cur;
      const top = cur.peak > 0 ? cur.peak : 1;
      const cols = Math.max(1, Math.floor(PW));
      g.beginPath();
      g.moveTo(x0, lane.y + lane.h);
      for (let x = 0; x < cols; x++) {
        const ta = t0 + (x / cols) * (t1 - t0), tb = t0 + ((x + 1) / cols) * (t1 - t0);
        const fa = Math.floor(ta * fps - f0), fb = Math.max(fa + 1, Math.floor(tb * fps - f0));
        let m = 0;
        for (let f = Math.max(0, fa); f < Math.min(v.length, fb); f++) if (v[f] > m) m = v[f];
        g.lineTo(x0 + x + 0.5, lane.y + lane.h - (Math.min(m, top) / top) * (lane.h - 2 * dpr));
      }
      g.lineTo(x0 + cols, lane.y + lane.h);
      if (fill) { g.fillStyle = color + "55"; g.fill(); }
      g.strokeStyle = color; g.lineWidth = 1.2 * dpr; g.stroke();
      g.fillStyle = "#6f7888"; g.textAlign = "left";
      g.fillText(cur.peakLabel || "", x0 + 4 * dpr, lane.y + 8 * dpr);
    }
    drawAudio(g, au, lane, x0, PW, t0, t1, dpr) {
      if (!au) return this.noData(g, lane, x0, PW, "no audio in this page", dpr);
      const { w, fps } = au;
      const n = w.length / 2, mid = lane.y + lane.h / 2, half = lane.h / 2 - 1;
      const cols = Math.max(1, Math.floor(PW));
      g.fillStyle = "#64b5f6";
      for (let x = 0; x < cols; x++) {
        const ta = t0 + (x / cols) * (t1 - t0), tb = t0 + ((x + 1) / cols) * (t1 - t0);
        const fa = Math.floor(ta * fps), fb = Math.max(fa + 1, Math.floor(tb * fps));
        let lo = 0, hi = 0;
        for (let f = Math.max(0, fa); f < Math.min(n, fb); f++) { lo = Math.min(lo, w[2 * f]); hi = Math.max(hi, w[2 * f + 1]); }
        if (hi > lo) g.fillRect(x0 + x, mid - (hi / 127) * half, 1, Math.max(1, ((hi - lo) / 127) * half));
      }
      g.strokeStyle = "#ff7043"; g.lineWidth = 1.5 * dpr;
      for (const t of au.onsets) {
        const x = x0 + ((t - t0) / (t1 - t0)) * PW;
        if (x < x0 || x > x0 + PW) continue;
        g.beginPath(); g.moveTo(x, lane.y); g.lineTo(x, lane.y + 7 * dpr); g.stroke();
      }
    }
    noData(g, lane, x0, PW, text, dpr) {
      g.fillStyle = "#6f7888"; g.textAlign = "left";
      g.fillText(text, x0 + 8 * dpr, lane.y + lane.h / 2);
    }
    drawHead(t) {
      this.resize();
      const g = this.head.getContext("2d"), W = this.head.width, H = this.head.height, dpr = window.devicePixelRatio || 1;
      g.clearRect(0, 0, W, H);
      if (S.mode === "live") return;
      const x0 = this.gutterCss() * dpr, PW = Math.max(1, W - x0 - 4 * dpr);
      if (t < this.t0 || t > this.t1) return;
      const x = x0 + ((t - this.t0) / (this.t1 - this.t0)) * PW;
      g.strokeStyle = "#ffffff"; g.lineWidth = 1.5 * dpr;
      g.beginPath(); g.moveTo(x, 0); g.lineTo(x, this.axisY || H); g.stroke();
    }
  }

  function groupsOf(ids) {
    const out = [];
    const shortName = { VestFront: "vest front", VestBack: "vest back", ForearmL: "L shoulder", ForearmR: "R shoulder" };
    ids.forEach((id, i) => {
      const name = id.replace(/_\d+$/, "");
      const last = out[out.length - 1];
      if (last && last.name === name) last.count++;
      else out.push({ name: name, short: shortName[name] || name, start: i, count: 1 });
    });
    return out;
  }

  // ------------------------------------------------------------------ data for the current time
  const track = () => TRACKS[S.trackIdx];

  function duration() {
    if (S.mode === "live") return LIVE_WINDOW_S;
    let d = 0;
    for (const tr of TRACKS) d = Math.max(d, tr.n / tr.fps);
    if (MOTION) d = Math.max(d, MOTION.n / MOTION.fps);
    if (AUDIO && AUDIO.info.duration_s) d = Math.max(d, AUDIO.info.duration_s);
    return d;
  }

  function point(dbg, key, f) {
    const b = dbg[key];
    if (!b || f < 0 || f >= b.shape[0]) return null;
    const a = b.arr, o = f * 3;
    if (a[o] === MISSING) return null;
    return [a[o] * b.scale, a[o + 1] * b.scale, a[o + 2] * b.scale];
  }

  function scalar(dbg, key, f) {
    const b = dbg[key];
    if (!b || f < 0 || f >= b.shape[0]) return null;
    return b.arr[f] * b.scale;
  }

  /* Everything shown at time t (file mode). Rows are held for 1/fps seconds; past the end of a track nothing plays. */
  function fileFrame(t) {
    const tr = track();
    const f = Math.floor(t * tr.fps + 1e-9);
    const inTrack = f >= 0 && f < tr.n;
    const out = { frame: inTrack ? f : -1, intensities: null, joints: null, tri: null, dp: null, hit: null, target: null,
      active: [0, 0], level: null, chart: null, distance: null, motionFrame: -1 };
    if (inTrack) {
      out.intensities = tr.I.arr.subarray(f * N_ACT, (f + 1) * N_ACT);
      const dbg = tr.debug;
      out.dp = point(dbg, "dynamic_point", f);
      out.hit = point(dbg, "hit_point", f);
      out.target = point(dbg, "target_point", f);
      const act = scalar(dbg, "active", f);
      if (act !== null) out.active = [act & 1 ? 1 : 0, act & 2 ? 1 : 0];
      out.level = scalar(dbg, "level", f);
      out.chart = scalar(dbg, "chart", f);
      out.distance = scalar(dbg, "distance", f);
      out.triIdx = dbg.triangle ? Array.from(dbg.triangle.arr.subarray(f * 3, f * 3 + 3)) : null;
    }
    if (MOTION && MOTION.pos) {
      const fm = Math.max(0, Math.min(MOTION.n - 1, Math.floor(t * MOTION.fps + 1e-9)));
      out.motionFrame = fm;
      const K = MOTION.joints.length, a = MOTION.pos.arr, sc = MOTION.pos.scale;
      const J = new Array(JOINTS.length).fill(null);
      for (let k = 0; k < K; k++) {
        const o = (fm * K + k) * 3;
        J[MOTION.joints[k]] = [a[o] * sc, a[o + 1] * sc, a[o + 2] * sc];
      }
      out.joints = J;
      if (out.triIdx && out.triIdx[0] >= 0) out.tri = out.triIdx.map((j) => J[j]);
    }
    return out;
  }

  function timelineSource() {
    if (S.mode === "live") return liveTimelineSource();
    const tr = track();
    const src = {
      heat: { I: tr.I.arr, fps: tr.fps, n: tr.n, nAct: N_ACT, f0: 0 },
      total: { v: tr.total, fps: tr.fps, f0: 0, peak: tr.totalPeak, peakLabel: "peak " + Math.round(tr.totalPeak) + " (sum of " + N_ACT + ")" },
      energy: null, audio: null,
    };
    const e = tr.debug.motion_energy;
    if (e) {
      if (!tr.energyF) tr.energyF = Float32Array.from(e.arr, (x) => x * e.scale);
      const peak = tr.energyF.reduce((m, x) => Math.max(m, x), 0);
      src.energy = { v: tr.energyF, fps: tr.fps, f0: 0, peak: peak, peakLabel: "peak " + peak.toPrecision(3) + " " + DATA.energy_units };
    } else {
      src.energy = { why: tr.info.energy_note || "not available" };
    }
    if (AUDIO && AUDIO.waveform) src.audio = { w: AUDIO.waveform.arr, fps: AUDIO.info.waveform_fps, onsets: AUDIO.onsets };
    return src;
  }

  // ------------------------------------------------------------------ playback clock (audio is the master when present)
  let perfT0 = 0, perfStart = 0, audioOk = true;

  function audioUsable(t) {
    // Audio time a plays at track time a + offset (hapmotion.audio convention); duration_s is the track time it ends.
    return AUDIO && AUDIO.el && audioOk && t >= AUDIO.offset && t < AUDIO.info.duration_s;
  }

  function currentTime() {
    if (!S.playing) return S.time;
    if (AUDIO && AUDIO.el && !AUDIO.el.paused && !AUDIO.el.ended) return AUDIO.el.currentTime + AUDIO.offset;
    return perfT0 + ((performance.now() - perfStart) / 1000) * S.rate;
  }

  function syncAudio(t) {
    if (!AUDIO || !AUDIO.el) return;
    const el = AUDIO.el;
    if (S.playing && audioUsable(t)) {
      el.playbackRate = S.rate;
      if (Math.abs(el.currentTime - (t - AUDIO.offset)) > 0.05) el.currentTime = t - AUDIO.offset;
      if (el.paused) {
        const p = el.play();
        if (p && p.catch) p.catch((err) => { audioOk = false; console.warn("hapmotion viewer: audio cannot play here:", err.message); });
      }
    } else if (!el.paused) {
      el.pause();
    }
  }

  function play() {
    if (S.mode !== "file" || S.playing) return;
    if (S.time >= duration() - 1e-6) S.time = 0;
    S.playing = true;
    perfT0 = S.time; perfStart = performance.now();
    syncAudio(S.time);
    $("play").innerHTML = "&#10074;&#10074; pause";
  }

  function pause() {
    if (!S.playing) return;
    S.time = currentTime();
    S.playing = false;
    if (AUDIO && AUDIO.el) AUDIO.el.pause();
    $("play").innerHTML = "&#9654; play";
  }

  function seek(t) {
    if (S.mode !== "file") return;
    S.time = Math.max(0, Math.min(duration(), t));
    perfT0 = S.time; perfStart = performance.now();
    if (AUDIO && AUDIO.el) {
      if (audioUsable(S.time)) AUDIO.el.currentTime = S.time - AUDIO.offset;
      syncAudio(S.time);
    }
    showFileTime();
  }

  function setRate(r) {
    const t = currentTime();
    S.rate = r;
    perfT0 = t; perfStart = performance.now();
    if (AUDIO && AUDIO.el) AUDIO.el.playbackRate = r;
  }

  // ------------------------------------------------------------------ readouts
  function fmtTime(t, fine) {
    t = Math.round(t * 1000) / 1000;  // tick positions are sums of floats: 15.9999 must print as 16
    const m = Math.floor(t / 60), s = t - m * 60;
    if (m >= 60) return Math.floor(m / 60) + ":" + String(m % 60).padStart(2, "0") + ":" + String(Math.floor(s)).padStart(2, "0");
    return m + ":" + (fine ? s.toFixed(1).padStart(4, "0") : String(Math.floor(s)).padStart(2, "0"));
  }

  function setReadout(pairs) {
    const dl = $("readout");
    if (dl.childElementCount !== pairs.length) {
      dl.textContent = "";
      for (const [k] of pairs) {
        const kv = document.createElement("div"); kv.className = "kv";
        const dt = document.createElement("dt"); dt.textContent = k;
        const dd = document.createElement("dd"); dd.dataset.key = k;
        kv.append(dt, dd);
        dl.append(kv);
      }
      const dds = dl.querySelectorAll("dd");
      pairs.forEach(([, v], i) => { dds[i].textContent = v; });
      fitVest();   // the stats take room under the vest: choose the arrangement with them in place
    }
    const dds = dl.querySelectorAll("dd");
    pairs.forEach(([, v], i) => { if (dds[i].textContent !== v) dds[i].textContent = v; });
  }

  function activeText(a) {
    return a[0] && a[1] ? "both hands" : a[0] ? "left hand" : a[1] ? "right hand" : "none";
  }

  function showReadout(fr, total) {
    const tr = S.mode === "file" ? track() : null;
    setReadout([
      ["frame", fr.frame >= 0 ? String(fr.frame) : "-"],
      ["total", total === null ? "-" : String(total)],
      ["active joint", activeText(fr.active)],
      ["level", fr.level === null || fr.level === undefined ? "-" : fr.level.toFixed(2)],
      ["vest chart", fr.chart === null || fr.chart === undefined ? "-" : CHART_NAMES[String(Math.round(fr.chart))] || String(fr.chart)],
      ["distance", fr.distance === null || fr.distance === undefined ? "-" : (fr.distance * 100).toFixed(1) + " cm"],
      ["method", tr ? tr.info.method || "-" : S.live.hello ? "live" : "-"],
      ["preset", tr ? tr.info.preset || "-" : "-"],
    ]);
  }

  // ------------------------------------------------------------------ main loop
  let scene, timeline;
  let lastShown = null;

  function render(now) {
    const t0 = performance.now();
    if (S.mode === "file") {
      let t = currentTime();
      const D = duration();
      if (S.playing && t >= D) { t = D; S.time = D; pause(); }
      if (S.playing) {
        S.time = t;
        // Keep the playhead inside a zoomed timeline: page forward.
        if (t > timeline.t1 || t < timeline.t0) { const span = timeline.t1 - timeline.t0; timeline.setWindow(t - 0.05 * span, t + 0.95 * span); }
        if (AUDIO && AUDIO.el && audioUsable(t) && AUDIO.el.paused && audioOk) syncAudio(t);
        if (AUDIO && AUDIO.el && !audioUsable(t) && !AUDIO.el.paused) AUDIO.el.pause();
      }
      if (S.time !== lastShown) showFileTime();
    } else {
      liveTick();
    }
    scene.draw();
    timeline.drawBackground();
    timeline.drawHead(S.time);
    const dt = performance.now() - t0;
    if (S.stats.firstDrawMs === null) S.stats.firstDrawMs = dt;  // includes drawing the whole timeline once
    else pushStat(S.stats.drawMs, dt);
    if (render.prev) pushStat(S.stats.frameGapMs, now - render.prev);
    render.prev = now;
    requestAnimationFrame(render);
  }

  function showFrame(fr) {
    scene.setFrame(fr);
    S.shown = { joints: fr.joints ? fr.joints.filter((p) => V.ok(p)).length : 0, triangle: !!(fr.tri && fr.tri.every((p) => V.ok(p))),
      dynamicPoint: V.ok(fr.dp), hitPoint: V.ok(fr.hit) };
  }

  /* Show everything at S.time (file mode). Called by the animation loop and, synchronously, by every control that
   * moves the time or changes the track, so the test hook never reports a half-updated frame. */
  function showFileTime() {
    const tr = track();
    const fr = fileFrame(S.time);
    S.frame = fr.frame; S.motionFrame = fr.motionFrame;
    S.intensities = fr.intensities ? Array.from(fr.intensities) : new Array(N_ACT).fill(0);
    S.level = fr.level; S.chart = fr.chart; S.distance = fr.distance; S.active = fr.active;
    showIntensities(S.intensities);
    showFrame(fr);
    showReadout(fr, fr.frame >= 0 ? Math.round(tr.total[fr.frame]) : 0);
    $("clock").textContent = fmtTime(S.time, true).padEnd(7) + " / " + fmtTime(duration(), false) + "   (" + S.time.toFixed(3) + " s)";
    lastShown = S.time;
  }

  function pushStat(arr, v) { arr.push(v); if (arr.length > 600) arr.shift(); }

  // ------------------------------------------------------------------ live mode
  const LIVE = { ws: null, latest: null, hist: [], timer: null, warned: new Set(), peak: 0, triCode: 0 };

  function liveWarn(kind, detail) {
    S.live.bad++;
    if (!LIVE.warned.has(kind)) { LIVE.warned.add(kind); console.warn("hapmotion viewer (live): skipped " + kind + (detail ? ": " + detail : "") + " (reported once)"); }
  }

  function setStatus(text, cls) {
    const el = $("status");
    el.textContent = text;
    el.className = "status" + (cls ? " " + cls : "");
  }

  function liveConnect() {
    const url = S.live.url;
    let ws;
    try { ws = new WebSocket(url); } catch (err) { setStatus("live: bad address " + url, "live-off"); liveWarn("address", err.message); return; }
    LIVE.ws = ws;
    setStatus("live: connecting to " + url, "live-off");
    ws.onopen = () => { S.live.connected = true; S.live.retries = 0; setStatus("live: connected, waiting for hello", "live-on"); };
    ws.onmessage = (ev) => liveMessage(ev.data);
    ws.onclose = () => {
      const was = S.live.connected;
      S.live.connected = false;
      LIVE.latest = null;
      showIntensities(null);   // never show a motor running on a dead link
      S.intensities = new Array(N_ACT).fill(0);
      const wait = Math.min(5, 0.5 * Math.pow(2, S.live.retries++));
      setStatus("live: " + (was ? "disconnected" : "cannot connect") + ", retrying in " + wait.toFixed(1) + " s", "live-off");
      LIVE.timer = setTimeout(liveConnect, wait * 1000);
    };
    ws.onerror = () => { /* onclose follows and reports */ };
  }

  function vec3(v) {
    return Array.isArray(v) && v.length === 3 && v.every((x) => typeof x === "number" && isFinite(x)) ? v : null;
  }

  function liveMessage(text) {
    let m;
    try { m = JSON.parse(text); } catch (err) { return liveWarn("non-JSON message", err.message); }
    if (!m || typeof m !== "object") return liveWarn("message that is not an object");
    if (m.type === "hello") {
      if (!Array.isArray(m.actuators) || !m.actuators.every((x) => typeof x === "string")) return liveWarn("hello without actuators");
      S.live.hello = m;
      S.live.stopped = false;
      S.live.seq = -1;
      if (m.actuators.join() !== ACT_IDS.join()) { ACT_IDS = m.actuators.slice(); N_ACT = ACT_IDS.length; buildVest(); fitVest(); }
      if (Array.isArray(m.joints)) JOINTS = m.joints.slice();
      if (Array.isArray(m.bones)) BONES = m.bones.filter((b) => Array.isArray(b) && b.length === 2);
      LIVE.hist = [];
      LIVE.triCode = 0;
      setStatus("live: " + (m.layout || "") + " " + (m.fps ? m.fps + " fps" : ""), "live-on");
      return;
    }
    if (m.type === "stop") {
      S.live.stopped = true;
      LIVE.latest = { t: LIVE.latest ? LIVE.latest.t : 0, intensities: new Array(N_ACT).fill(0), skeleton: LIVE.latest ? LIVE.latest.skeleton : null,
        dp: null, hit: null, active: [0, 0], level: 0, seq: S.live.seq, fresh: true };
      setStatus("live: stopped by the sender", "live-off");
      return;
    }
    if (m.type !== "frame") return liveWarn("message of unknown type", String(m.type));
    if (!S.live.hello) return liveWarn("frame before hello");
    const I = m.intensities;
    if (!Array.isArray(I) || I.length !== N_ACT || !I.every((x) => typeof x === "number" && isFinite(x))) {
      return liveWarn("frame with bad intensities", "expected " + N_ACT + " numbers");
    }
    const seq = Number.isInteger(m.seq) ? m.seq : S.live.seq + 1;
    if (S.live.seq >= 0 && seq > S.live.seq + 1) S.live.dropped += seq - S.live.seq - 1;
    S.live.seq = seq;
    S.live.frames++;
    S.live.stopped = false;
    let skel = null;
    if (Array.isArray(m.skeleton)) skel = JOINTS.map((_, j) => vec3(m.skeleton[j]));
    const t = typeof m.t === "number" && isFinite(m.t) ? m.t : S.live.frames / (S.live.hello.fps || 60);
    const active = Array.isArray(m.active) ? [m.active[0] ? 1 : 0, m.active[1] ? 1 : 0] : [0, 0];
    const clipped = I.map((x) => Math.max(0, Math.min(100, x)));
    LIVE.latest = { t: t, seq: seq, intensities: clipped, skeleton: skel, dp: vec3(m.dynamic_point), hit: vec3(m.hit_point),
      active: active, level: typeof m.level === "number" ? m.level : null, fresh: true };
    S.live.lastAt = performance.now();
    const row = new Uint8Array(N_ACT);
    let tot = 0;
    for (let i = 0; i < N_ACT; i++) { row[i] = Math.round(clipped[i]); tot += row[i]; }
    if (row.some((v) => v > LIVE.peak)) { LIVE.peak = Math.max(...row); if (S.scaleChoice === "fit") setScale("fit"); }
    LIVE.hist.push({ t: t, row: row, total: tot });
    while (LIVE.hist.length && LIVE.hist[0].t < t - LIVE_WINDOW_S) LIVE.hist.shift();
    timeline.dirty = true;
  }

  // The motion salient triangle of a live frame, when the hello says the show runs the MST method (paper,
  // Section 4 step 4): both hands active -> (left hand, right hand, J_T); one -> (that hand, the opposite
  // shoulder, J_T); none -> the last triangle, or before any, the hand farther from J_T.
  function liveTriangle(L) {
    const render = S.live.hello && S.live.hello.render;
    if (!render || render.method !== "mst" || !L.skeleton) return null;
    const idx = (name) => JOINTS.indexOf(name);
    const hl = idx("HAND_LEFT"), hr = idx("HAND_RIGHT"), sl = idx("SHOULDER_LEFT"), sr = idx("SHOULDER_RIGHT"), jt = idx("SPINE_NAVEL");
    if ([hl, hr, sl, sr, jt].some((j) => j < 0)) return null;
    let code = (L.active[0] ? 1 : 0) + (L.active[1] ? 2 : 0);
    if (code === 0) code = LIVE.triCode || 0;
    if (code === 0) {
      const J = L.skeleton, d = (a, b) => (J[a] && J[b]) ? Math.hypot(J[a][0] - J[b][0], J[a][1] - J[b][1], J[a][2] - J[b][2]) : -1;
      code = d(hl, jt) >= d(hr, jt) ? 1 : 2;
    }
    LIVE.triCode = code;
    const verts = code === 3 ? [hl, hr, jt] : code === 1 ? [hl, sr, jt] : [hr, sl, jt];
    const tri = verts.map((j) => L.skeleton[j]);
    return tri.every((p) => p) ? tri : null;
  }

  function liveTick() {
    const L = LIVE.latest;
    const stalled = S.live.connected && !S.live.stopped && S.live.frames > 0 && (performance.now() - S.live.lastAt) / 1000 > LIVE_STALL_S;
    if (stalled !== S.live.stalled) {
      S.live.stalled = stalled;
      if (stalled) { setStatus("live: no frames for over " + LIVE_STALL_S + " s", "live-off"); showIntensities(null); S.intensities = new Array(N_ACT).fill(0); }
      else if (S.live.connected) setStatus("live: receiving", "live-on");
    }
    if (!L || !L.fresh || stalled) return;
    L.fresh = false;
    S.time = L.t;
    S.frame = L.seq;
    S.intensities = L.intensities.slice();
    S.level = L.level; S.active = L.active; S.chart = null; S.distance = null;
    showIntensities(S.intensities);
    const fr = { frame: L.seq, joints: L.skeleton, dp: L.dp, hit: L.hit, target: null, tri: liveTriangle(L), active: L.active,
      level: L.level, chart: null, distance: null };
    showFrame(fr);
    if (L.skeleton && !LIVE.viewSet) { LIVE.viewSet = true; scene.setView("audience"); }
    if (L.skeleton) {
      let lo = Infinity;
      for (const p of L.skeleton) if (p) lo = Math.min(lo, p[1]);
      if (isFinite(lo)) scene.floor = Math.min(scene.floor, lo);
    }
    showReadout(fr, S.intensities.reduce((a, b) => a + Math.round(b), 0));
    $("clock").textContent = "live  t = " + L.t.toFixed(2) + " s   frame " + L.seq + (S.live.dropped ? "   (" + S.live.dropped + " dropped)" : "");
  }

  function liveTimelineSource() {
    const h = LIVE.hist;
    const end = h.length ? h[h.length - 1].t : 0;
    timeline.t0 = end - LIVE_WINDOW_S; timeline.t1 = end;
    const fps = (S.live.hello && S.live.hello.fps) || 60;
    // Resample the history onto a regular grid of frames so the file-mode lane painters can draw it.
    const n = Math.max(1, Math.round(LIVE_WINDOW_S * fps));
    const f0 = Math.round((end - LIVE_WINDOW_S) * fps);
    const I = new Uint8Array(n * N_ACT), tot = new Float32Array(n);
    let peak = 0;
    for (const e of h) {
      const f = Math.round(e.t * fps) - f0;
      if (f < 0 || f >= n) continue;
      I.set(e.row, f * N_ACT);
      tot[f] = e.total;
      peak = Math.max(peak, e.total);
    }
    return {
      heat: { I: I, fps: fps, n: n, nAct: N_ACT, f0: f0 },
      total: { v: tot, fps: fps, f0: f0, peak: peak, peakLabel: "last " + LIVE_WINDOW_S + " s, peak " + peak },
      energy: { why: "not sent by the live broadcast" },
      audio: null,
    };
  }

  // ------------------------------------------------------------------ set-up
  function buildChrome() {
    $("title").textContent = DATA.title || "";
    document.title = (DATA.title ? DATA.title + " - " : "") + "hapmotion viewer";
    const foot = $("footer");
    foot.textContent = (DATA.footer || []).join("  \u00b7  ");
    const sel = $("track-select");
    sel.textContent = "";
    TRACKS.forEach((tr, i) => {
      const o = document.createElement("option");
      o.value = String(i);
      o.textContent = tr.info.label;
      sel.appendChild(o);
    });
    $("track-pick").hidden = S.mode !== "file" || TRACKS.length < 2;
    sel.addEventListener("change", () => {
      S.trackIdx = Number(sel.value);
      timeline.dirty = true;
      updateMirrorNote();
      setScale(S.scaleChoice);
      showFileTime();
    });
    $("scale-pick").addEventListener("change", (e) => setScale(e.target.value));
    $("play").addEventListener("click", () => (S.playing ? pause() : play()));
    $("speed").addEventListener("change", (e) => setRate(Number(e.target.value)));
    $("zoom-all").addEventListener("click", () => timeline.setWindow(0, duration()));
    $("view-audience").addEventListener("click", () => scene.setView("audience"));
    $("view-behind").addEventListener("click", () => scene.setView("behind"));
    $("view-side").addEventListener("click", () => scene.setView("side"));
    $("follow").addEventListener("change", (e) => { scene.follow = e.target.checked; scene.dirty = true; });
    window.addEventListener("keydown", (e) => {
      if (S.mode !== "file" || e.target.tagName === "SELECT") return;
      const fps = track().fps;
      if (e.code === "Space") { e.preventDefault(); S.playing ? pause() : play(); }
      else if (e.code === "ArrowRight") { pause(); seek((S.frame + 1 + 0.5) / fps); }
      else if (e.code === "ArrowLeft") { pause(); seek((Math.max(0, S.frame - 1) + 0.5) / fps); }
      else if (e.code === "Home") seek(0);
      else if (e.code === "End") seek(duration());
    });
    window.addEventListener("resize", () => { fitVest(); scene.dirty = true; timeline.dirty = true; });
    updateMirrorNote();
  }

  function updateMirrorNote() {
    const tr = S.mode === "file" ? track() : null;
    const m = tr ? tr.info.mirror : null;
    $("mirror-note").textContent = m === true ? "(mirrored: the performer's left hand is felt on the wearer's right)"
      : m === false ? "(not mirrored: the performer's left is the wearer's left)" : "";
  }

  function showError(err) {
    S.error = String(err && err.message ? err.message : err);
    const box = document.createElement("div");
    box.className = "error-box";
    box.textContent = "The viewer could not start:\n" + S.error;
    document.body.appendChild(box);
    console.error("hapmotion viewer:", err);
  }

  async function boot() {
    const params = new URLSearchParams(location.search);
    const liveUrl = params.get("live") || (DATA.live && DATA.live.url) || null;
    if (liveUrl) { S.mode = "live"; S.live.url = liveUrl; }
    if (S.mode === "file" && !DATA.tracks.length) throw new Error("this page holds no track and no live address (add ?live=ws://host:port)");
    await decodeAll();
    buildVest();
    fitVest();
    drawColorbar();
    scene = new Scene($("scene"));
    timeline = new Timeline($("timeline"), $("timeline-head"));
    if (MOTION) scene.floor = MOTION.floor;
    buildChrome();
    setScale(S.mode === "live" ? "100" : "fit");
    $("scale-pick").value = S.scaleChoice;
    if (S.mode === "file") {
      const want = params.get("track");
      const k = TRACKS.findIndex((tr) => tr.info.key === want);
      if (k >= 0) { S.trackIdx = k; $("track-select").value = String(k); updateMirrorNote(); }
      if (AUDIO && AUDIO.url) {
        const el = new Audio();
        el.preload = "auto";
        el.src = AUDIO.url;
        el.addEventListener("error", () => { audioOk = false; console.warn("hapmotion viewer: this browser cannot decode the embedded audio (" + DATA.audio.mime + ")"); });
        AUDIO.el = el;
      }
      const hash = /(?:^|[#&])t=([0-9.]+)/.exec(location.hash);
      timeline.setWindow(0, duration());
      seek(hash ? Number(hash[1]) : 0);
      setStatus(DATA.audio ? "with audio: " + DATA.audio.name : "", "");
      scene.setFrame(fileFrame(S.time));
      scene.setView("audience");
    } else {
      // Nothing to play, seek or zoom in a live show: hide those controls.
      document.querySelectorAll("#zoom-all, #play, #speed, .hint2").forEach((el) => { el.closest("label, button, span").hidden = true; });
      showIntensities(null);
      S.intensities = new Array(N_ACT).fill(0);
      liveConnect();
    }
    S.ready = true;
    S.stats.loadMs = performance.now();
    requestAnimationFrame(render);
  }

  /* The timeline's drawn labels (lane names, sleeve and panel names, time ticks) as viewport boxes {text, x, y, w, h}. */
  function timelineLabelBoxes() {
    const r = timeline.bg.getBoundingClientRect();
    return (timeline.labels || []).map((b) => ({ text: b.text, x: r.left + b.x, y: r.top + b.y, w: b.w, h: b.h }));
  }

  const median = (a) => { if (!a.length) return null; const s = a.slice().sort((x, y) => x - y); return s[Math.floor(s.length / 2)]; };
  const pct = (a, q) => { if (!a.length) return null; const s = a.slice().sort((x, y) => x - y); return s[Math.min(s.length - 1, Math.floor(q * s.length))]; };

  const hook = {
    /* A copy of what is displayed now; changing it changes nothing. */
    state() {
      const tr = S.mode === "file" && TRACKS.length ? track() : null;
      return JSON.parse(JSON.stringify({
        ready: S.ready, error: S.error, mode: S.mode, playing: S.playing, time: S.time, duration: S.ready ? duration() : null,
        frame: S.frame, motionFrame: S.motionFrame, fps: tr ? tr.fps : (S.live.hello && S.live.hello.fps) || null,
        track: tr ? tr.info.key : null, tracks: TRACKS.map((x) => x.info.key), rate: S.rate,
        actuators: ACT_IDS, intensities: S.intensities, shown: S.shown, scaleTop: S.scaleTop, level: S.level, chart: S.chart, distance: S.distance, active: S.active,
        audio: AUDIO ? { playing: !!(AUDIO.el && !AUDIO.el.paused), time: AUDIO.el ? AUDIO.el.currentTime : null, usable: audioOk } : null,
        live: { url: S.live.url, connected: S.live.connected, hello: !!S.live.hello, seq: S.live.seq, frames: S.live.frames,
          dropped: S.live.dropped, stopped: S.live.stopped, stalled: S.live.stalled, skipped: S.live.bad },
        timelineLabels: timeline ? timelineLabelBoxes() : [],
        stats: { loadMs: S.stats.loadMs, firstDrawMs: S.stats.firstDrawMs, drawMsMedian: median(S.stats.drawMs), drawMsP95: pct(S.stats.drawMs, 0.95),
          frameGapMsMedian: median(S.stats.frameGapMs), frameGapMsP95: pct(S.stats.frameGapMs, 0.95), samples: S.stats.drawMs.length },
      }));
    },
  };
  Object.defineProperty(window, "hapmotionViewer", { value: Object.freeze(hook), writable: false, configurable: false });

  boot().catch(showError);
})();
