// lapclone live view: draws the frames and scene messages the server sends, and turns
// pointer gestures into structured edits (which patch, which handle, which value). The
// server writes the REPL line; this page never sends source code or paths.
"use strict";
(() => {
  const $ = (id) => document.getElementById(id);
  // `overlay` covers the frame and takes the pointer; what it shows is drawn into `marks`, a
  // canvas only as large as the box the handles, pins and outlines need (see drawOverlay).
  const frame = $("frame"), overlay = $("overlay"), marks = $("marks");
  // Both canvases are desynchronized: chromium then paints a preview's frame in about 0.3 ms
  // instead of 0.8-1.0 ms when the marks are redrawn with it (a handle dragged).
  const fctx = frame.getContext("2d", { desynchronized: true }), mctx = marks.getContext("2d", { desynchronized: true });
  // While drawOverlay measures, drawing goes nowhere; then it goes to `marks`.
  const nowhere = new Proxy({}, { get: () => () => {}, set: () => true });
  let octx = nowhere;
  const token = new URLSearchParams(location.search).get("token") || "";
  const TRACK_COLOURS = { at: "#f0c674", scale: "#81a2be", rotate: "#b294bb", depth: "#8abeb7", opacity: "#de935f" };
  let ws = null, scene = null, located = null, gesture = null, selected = null;
  // pendingEdit: { edit, t }, t being the playhead its gesture began at.
  let pendingEdit = null, inFlight = false, locating = false, nextLocate = null;
  let playing = false, meshOn = false, scrubbing = false;
  // Pointer event → pixels painted, ms, per preview: from the earliest pointer event the
  // preview answers to the end of the browser frame that paints it (read by the browser test
  // and benchmark), and when each was painted (performance.now(), for updates per second).
  const timings = (window.lapcloneTimings = []);
  const paintedAt = (window.lapclonePaintedAt = []);
  // Where each timing went, ms: [waiting to be sent, the round trip to the pixels put in the
  // canvas, waiting for the frame that paints them, that frame's paint]; they add up to it.
  const timingParts = (window.lapcloneTimingParts = []);
  // The last scene message, for tests that drive the page.
  window.lapcloneScene = () => scene;
  let pointerAt = 0, sentAt = 0, sendAt = 0;

  function send(message) {
    if (ws && ws.readyState === 1) ws.send(JSON.stringify(message));
  }
  function setText(element, text) {
    if (element.textContent !== text) element.textContent = text;
  }
  function notice(text, kind) {
    const n = $("notice");
    n.textContent = text;
    n.className = kind || "";
  }
  function log(text) {
    const l = $("log");
    l.textContent += (l.textContent ? "\n" : "") + text;
    l.scrollTop = l.scrollHeight;
  }

  function connect() {
    ws = new WebSocket(`ws://${location.host}/ws?token=${encodeURIComponent(token)}`);
    ws.binaryType = "arraybuffer";
    ws.onopen = () => { $("conn").textContent = "live"; $("conn").className = "good"; };
    ws.onclose = () => { $("conn").textContent = "disconnected (reload the page)"; $("conn").className = "bad"; };
    ws.onmessage = (event) => (typeof event.data === "string" ? onText(JSON.parse(event.data)) : onFrame(event.data));
  }

  // The frame's pixels as the canvas holds them: updates that carry only each row's changed
  // run are written into it, then its changed rectangle is put into the canvas.
  let frameData = null;

  function onFrame(buffer) {
    const head = new DataView(buffer, 0, 28);
    const [kind, width, height, x, y, w, hh] = [0, 4, 8, 12, 16, 20, 24].map((at) => head.getUint32(at, true));
    if (kind !== 1 && kind !== 2) return;
    if (frame.width !== width || frame.height !== height || !frameData) {
      frame.width = overlay.width = width;
      frame.height = overlay.height = height;
      frameData = new ImageData(width, height);
      fitStage();
    }
    if (w > 0 && hh > 0) {
      const data = frameData.data;
      if (kind === 1) {
        for (let j = 0; j < hh; j++) data.set(new Uint8Array(buffer, 28 + j * w * 4, w * 4), ((y + j) * width + x) * 4);
      } else {
        const runs = new DataView(buffer, 28, hh * 8);
        let at = 28 + hh * 8;
        for (let j = 0; j < hh; j++) {
          const first = runs.getUint32(j * 8, true), length = runs.getUint32(j * 8 + 4, true);
          if (!length) continue;
          data.set(new Uint8Array(buffer, at, length * 4), ((y + j) * width + x + first) * 4);
          at += length * 4;
        }
      }
      fctx.putImageData(frameData, 0, 0, x, y, w, hh);
    }
    if (sentAt) {
      // requestAnimationFrame runs just before the frame's paint; a task queued from it runs
      // once that paint is done.
      const [from, sent, put] = [sentAt, sendAt, performance.now()];
      sentAt = 0;
      requestAnimationFrame(() => {
        const frameAt = performance.now();
        setTimeout(() => {
          const now = performance.now();
          timings.push(now - from);
          paintedAt.push(now);
          timingParts.push([sent - from, put - sent, frameAt - put, now - frameAt]);
        }, 0);
      });
    }
    inFlight = false;
    flushEdit();
    if (playing) requestAnimationFrame(playStep);
  }

  function onText(m) {
    if (m.type === "scene") {
      scene = m;
      // A drag sends a scene message per preview: only what changed is touched, so the page
      // is not laid out again for nothing before the preview's paint.
      setText($("file"), m.file || "(no file)");
      if ($("scrub").max !== String(m.duration)) $("scrub").max = m.duration;
      if (!scrubbing && $("scrub").value !== String(m.t)) $("scrub").value = m.t;
      setText($("clock"), `t = ${+m.t.toFixed(4)} s · frame ${m.frame} / ${m.frames}`);
      drawMarkers();
      drawOverlay();
    } else if (m.type === "located") {
      located = m;
      locating = false;
      showCoords();
      if (nextLocate) { const p = nextLocate; nextLocate = null; locate(p); }
    } else if (m.type === "error") {
      // A line's error comes as the terminal shows it, its source line and caret below:
      // the notice takes its first line, the log (monospace, lines kept) all of it.
      const lines = m.message.split("\n");
      notice(lines[0], "error");
      if (lines.length > 1) log(m.message);
      inFlight = false;
      sentAt = 0;
    } else if (m.type === "line") {
      log(m.text);
      notice("", "");
    }
  }

  // --- geometry: a patch's placement (rest → canvas) and its inverse ---
  function place(p, q) {
    const r = (p.rotation * Math.PI) / 180, c = Math.cos(r), s = Math.sin(r);
    const dx = q[0] - p.pivot[0], dy = q[1] - p.pivot[1];
    return [p.at[0] + p.scale * (c * dx - s * dy), p.at[1] + p.scale * (s * dx + c * dy)];
  }
  function unplace(p, q) {
    const r = (p.rotation * Math.PI) / 180, c = Math.cos(r), s = Math.sin(r);
    const dx = (q[0] - p.at[0]) / p.scale, dy = (q[1] - p.at[1]) / p.scale;
    return [p.pivot[0] + c * dx + s * dy, p.pivot[1] - s * dx + c * dy];
  }
  function canvasPoint(e) {
    const r = overlay.getBoundingClientRect();
    return [((e.clientX - r.left) * overlay.width) / r.width, ((e.clientY - r.top) * overlay.height) / r.height];
  }
  // The stage (the frame, the pointer's canvas and the marks over it) is sized in whole CSS
  // pixels to fit the space the header, timeline and footer leave, keeping the canvas's
  // aspect and never enlarging it: sized by CSS limits alone, the frame could overflow that
  // space and be clipped while the pointer's canvas was squeezed into it, so pointer
  // positions were off vertically.
  const stage = $("stage"), room = document.querySelector("main");
  function fitStage() {
    const [aw, ah] = [room.clientWidth - 20, room.clientHeight - 10];
    const s = Math.max(Math.min(1, aw / frame.width, ah / frame.height), 0);
    // At least a pixel: a window with no room left would make the canvas's scale infinite.
    const [w, h] = [frame.width * s, frame.height * s].map((v) => Math.max(1, Math.floor(v)));
    if (stage.style.width !== `${w}px`) stage.style.width = `${w}px`;
    if (stage.style.height !== `${h}px`) stage.style.height = `${h}px`;
    drawOverlay();
  }
  new ResizeObserver(fitStage).observe(room);
  const screenScale = () => overlay.width / overlay.getBoundingClientRect().width;
  const patchNamed = (name) => scene && scene.patches.find((p) => p.name === name);
  const r2 = (v) => Math.round(v * 100) / 100;
  const dist = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1]);

  // The overlay is redrawn per scene message. Its drawing runs twice: once to find the box
  // it covers (`mark`), then into `marks` sized to that box and placed over it, so the
  // browser composites a small canvas per preview instead of a frame-sized one.
  let overlayBox = null, overlayPad = 0;
  function mark(x, y, r) {
    const d = r + overlayPad;
    if (!overlayBox) overlayBox = [x - d, y - d, x + d, y + d];
    else {
      const b = overlayBox;
      b[0] = Math.min(b[0], x - d); b[1] = Math.min(b[1], y - d);
      b[2] = Math.max(b[2], x + d); b[3] = Math.max(b[3], y + d);
    }
  }
  function drawOverlay() {
    overlayBox = null;
    octx = nowhere;
    drawOverlayInto();
    const b = overlayBox;
    const [x0, y0] = b ? [Math.floor(Math.max(b[0], 0)), Math.floor(Math.max(b[1], 0))] : [0, 0];
    const [x1, y1] = b ? [Math.ceil(Math.min(b[2], overlay.width)), Math.ceil(Math.min(b[3], overlay.height))] : [0, 0];
    if (x1 <= x0 || y1 <= y0) { marks.style.display = "none"; return; }
    // Resizing a canvas reallocates it and lays the page out again, which cost a preview's
    // frame about 2 ms in chromium: the canvas keeps its size (whole 128-px steps) while the
    // box moves or changes a little, and is only cleared.
    const [w, h] = [x1 - x0, y1 - y0].map((v) => Math.ceil(v / 128) * 128);
    if (marks.width !== w || marks.height !== h) {
      marks.width = w; // also clears it
      marks.height = h;
    } else {
      mctx.setTransform(1, 0, 0, 1, 0, 0);
      mctx.clearRect(0, 0, w, h);
    }
    const percent = (v, whole) => `${(100 * v) / whole}%`;
    const style = {
      display: "block",
      left: percent(x0, overlay.width), top: percent(y0, overlay.height),
      width: percent(w, overlay.width), height: percent(h, overlay.height),
    };
    for (const key in style) if (marks.style[key] !== style[key]) marks.style[key] = style[key];
    octx = mctx;
    octx.setTransform(1, 0, 0, 1, -x0, -y0);
    drawOverlayInto();
  }
  function drawOverlayInto() {
    if (!scene) return;
    const px = screenScale();
    overlayPad = 3 * px + 2;
    octx.lineWidth = 1.5 * px;
    if (meshOn && scene.meshes) {
      octx.strokeStyle = "rgba(120, 220, 255, 0.55)";
      octx.beginPath();
      for (const m of scene.meshes) {
        const P = m.points, T = m.triangles;
        for (let i = 0; i < P.length; i += 2) mark(P[i], P[i + 1], 0);
        for (let i = 0; i < T.length; i += 3) {
          const a = T[i] * 2, b = T[i + 1] * 2, c = T[i + 2] * 2;
          octx.moveTo(P[a], P[a + 1]); octx.lineTo(P[b], P[b + 1]); octx.lineTo(P[c], P[c + 1]); octx.closePath();
        }
      }
      octx.stroke();
    }
    for (const p of scene.patches) {
      if (p.follow) drawPath(p.follow, (q) => q, px);
      p.handles.forEach((h) => { if (h.follow) drawPath(h.follow, (q) => place(p, q), px); });
    }
    for (const p of scene.patches) {
      const hot = (located && located.patch === p.name) || (gesture && gesture.patch === p.name);
      if (hot && p.bbox) {
        mark(p.bbox[0], p.bbox[1], 0);
        mark(p.bbox[2], p.bbox[3], 0);
        octx.setLineDash([4 * px, 4 * px]);
        octx.strokeStyle = "rgba(255,255,255,0.7)";
        octx.strokeRect(p.bbox[0], p.bbox[1], p.bbox[2] - p.bbox[0], p.bbox[3] - p.bbox[1]);
        octx.setLineDash([]);
      }
      p.handles.forEach((h, i) => {
        const grab = place(p, h.from), target = place(p, h.to);
        const sel = selected && selected.kind === "handle" && selected.patch === p.name && selected.index === i;
        const sizing = gesture && gesture.kind === "radius" && gesture.patch === p.name && gesture.index === i;
        mark(target[0], target[1], Math.max(h.radius * p.scale, 5 * px));
        mark(grab[0], grab[1], 3 * px);
        octx.strokeStyle = sel ? "#fff" : "rgba(255, 200, 80, 0.9)";
        if (sizing) octx.lineWidth = 3 * px;
        octx.beginPath(); octx.arc(target[0], target[1], h.radius * p.scale, 0, 2 * Math.PI); octx.stroke();
        octx.lineWidth = 1.5 * px;
        octx.beginPath(); octx.moveTo(grab[0], grab[1]); octx.lineTo(target[0], target[1]); octx.stroke();
        octx.fillStyle = "rgba(255, 200, 80, 0.9)";
        octx.beginPath(); octx.arc(grab[0], grab[1], 3 * px, 0, 2 * Math.PI); octx.fill();
        octx.fillStyle = sel ? "#fff" : "#ff5050";
        octx.beginPath(); octx.arc(target[0], target[1], 5 * px, 0, 2 * Math.PI); octx.fill();
      });
      p.pins.forEach((pin, i) => {
        const q = place(p, pin.at);
        mark(q[0], q[1], 4 * px);
        const sel = selected && selected.kind === "pin" && selected.patch === p.name && selected.index === i;
        octx.fillStyle = sel ? "#fff" : "#50c8ff";
        octx.fillRect(q[0] - 4 * px, q[1] - 4 * px, 8 * px, 8 * px);
      });
    }
  }

  // A followed track's path: its positions over the shot, the current frame's ringed.
  function drawPath(f, toCanvas, px) {
    const pts = f.path.map(toCanvas);
    if (!pts.length) return;
    pts.forEach((q) => mark(q[0], q[1], 6 * px));
    octx.strokeStyle = "rgba(140, 255, 140, 0.85)";
    octx.setLineDash([6 * px, 3 * px]);
    octx.beginPath();
    pts.forEach((q, i) => (i ? octx.lineTo(q[0], q[1]) : octx.moveTo(q[0], q[1])));
    octx.stroke();
    octx.setLineDash([]);
    octx.fillStyle = "rgba(140, 255, 140, 0.85)";
    for (const q of pts) octx.fillRect(q[0] - 1.5 * px, q[1] - 1.5 * px, 3 * px, 3 * px);
    const c = pts[Math.min(f.current, pts.length - 1)];
    octx.beginPath(); octx.arc(c[0], c[1], 6 * px, 0, 2 * Math.PI); octx.stroke();
  }

  function showCoords() {
    if (!located) return;
    let text = `canvas [${Math.round(located.x)}, ${Math.round(located.y)}]`;
    if (located.patch !== null) {
      text += ` · ${located.patch} source [${r2(located.source[0])}, ${r2(located.source[1])}]`;
    }
    $("coords").textContent = text;
    drawOverlay();
  }

  function locate(p) {
    if (locating) { nextLocate = p; return; }
    locating = true;
    send({ type: "locate", x: p[0], y: p[1] });
  }

  // --- what is under the pointer: a handle's target, a pin, or a patch ---
  function pick(q) {
    if (!scene) return null;
    const near = 8 * screenScale();
    for (const p of scene.patches) {
      for (let i = 0; i < p.handles.length; i++) {
        if (dist(place(p, p.handles[i].to), q) <= near) return { kind: "handle", patch: p.name, index: i };
      }
      for (let i = 0; i < p.pins.length; i++) {
        if (dist(place(p, p.pins[i].at), q) <= near) return { kind: "pin", patch: p.name, index: i };
      }
    }
    // A handle's circle of influence, grabbed at its edge.
    for (const p of scene.patches) {
      for (let i = 0; i < p.handles.length; i++) {
        const h = p.handles[i];
        if (Math.abs(dist(place(p, h.to), q) - h.radius * p.scale) <= near / 2 + 2) return { kind: "radius", patch: p.name, index: i };
      }
    }
    if (located && located.patch !== null && dist([located.x, located.y], q) < 2 * near) {
      return { kind: "patch", patch: located.patch };
    }
    const order = scene.draw_order.slice().reverse();
    for (const i of order) {
      const b = scene.patches[i].bbox;
      if (b && q[0] >= b[0] && q[0] <= b[2] && q[1] >= b[1] && q[1] <= b[3]) return { kind: "patch", patch: scene.patches[i].name };
    }
    return null;
  }

  function editFor(g, q) {
    const p = patchNamed(g.patch);
    if (!p) return null;
    if (g.kind === "handle") return { op: "handle_key", patch: p.name, handle: g.index, value: unplace(g.base, q).map(r2) };
    if (g.kind === "radius") {
      const centre = place(g.base, g.base.handles[g.index].to);
      return { op: "handle_radius", patch: p.name, handle: g.index, value: Math.max(0.01, r2(dist(q, centre) / g.base.scale)) };
    }
    if (g.mode === "rotate") {
      const a0 = Math.atan2(g.start[1] - g.base.at[1], g.start[0] - g.base.at[0]);
      const a1 = Math.atan2(q[1] - g.base.at[1], q[0] - g.base.at[0]);
      return { op: "rotate", patch: p.name, value: r2(g.base.rotation + ((a1 - a0) * 180) / Math.PI) };
    }
    if (g.mode === "scale") {
      const d0 = Math.max(dist(g.start, g.base.at), 1);
      return { op: "scale", patch: p.name, value: Math.max(0.0001, Math.round(((g.base.scale * dist(q, g.base.at)) / d0) * 1e4) / 1e4) };
    }
    return { op: "at", patch: p.name, value: [r2(g.base.at[0] + q[0] - g.start[0]), r2(g.base.at[1] + q[1] - g.start[1])] };
  }

  // One preview in flight at a time; the newest waiting one replaces older ones.
  function queueEdit(edit, t) {
    pendingEdit = { edit, t };
    flushEdit();
  }
  function flushEdit() {
    if (inFlight || !pendingEdit || !scene) return;
    sendAt = performance.now();
    sentAt = pointerAt || sendAt;
    pointerAt = 0;
    inFlight = true;
    send({ type: "edit", rev: scene.rev, commit: false, t: pendingEdit.t, edit: pendingEdit.edit });
    pendingEdit = null;
  }

  // A drag reads pointerrawupdate where the browser has it: it comes as the pointer moves,
  // not held back to the next display frame as pointermove is, so the answer can be painted
  // in that frame instead of the one after.
  const rawUpdates = "onpointerrawupdate" in window;
  overlay.addEventListener("pointermove", (e) => {
    if (gesture) {
      if (!rawUpdates) dragMove(e);
      return;
    }
    const q = canvasPoint(e);
    const hit = pick(q);
    overlay.style.cursor = !hit || hit.kind === "patch" ? "" : hit.kind === "radius" ? "ew-resize" : "move";
    locate(q);
  });
  if (rawUpdates) overlay.addEventListener("pointerrawupdate", (e) => { if (gesture) dragMove(e); });

  function dragMove(e) {
    const q = canvasPoint(e);
    if (dist(q, gesture.start) * (1 / screenScale()) > 2) gesture.moved = true;
    if (gesture.moved && gesture.kind !== "add") {
      gesture.last = editFor(gesture, q);
      if (gesture.last) {
        if (!pointerAt) pointerAt = e.timeStamp;
        queueEdit(gesture.last, gesture.t);
      }
    }
  }

  overlay.addEventListener("pointerdown", (e) => {
    if (!scene || e.button !== 0) return;
    overlay.focus();
    const q = canvasPoint(e);
    const hit = pick(q);
    if ((e.ctrlKey || e.metaKey) && hit && hit.kind === "patch") {
      gesture = { kind: "add", patch: hit.patch, start: q, pin: e.shiftKey };
      return;
    }
    if (!hit) { gesture = { kind: "none", start: q, shift: e.shiftKey }; return; }
    // A gesture edits the frame it grabbed: playback stops, and its keys go at this playhead
    // (its values are measured here) even if another page seeks meanwhile.
    if (playing) togglePlay();
    const base = JSON.parse(JSON.stringify(patchNamed(hit.patch)));
    const mode = e.shiftKey ? "rotate" : e.altKey ? "scale" : "move";
    gesture = { kind: hit.kind, patch: hit.patch, index: hit.index, base, start: q, mode, moved: false, shift: e.shiftKey, t: scene.t };
    if (hit.kind === "handle" || hit.kind === "pin") { selected = hit; drawOverlay(); }
    overlay.setPointerCapture(e.pointerId);
  });

  overlay.addEventListener("pointerup", (e) => {
    const g = gesture;
    gesture = null;
    if (!g) return;
    const q = canvasPoint(e);
    if (g.kind === "add") {
      const p = patchNamed(g.patch);
      if (!p) return;
      const at = located && located.patch === p.name ? located.source : unplace(p, q);
      const edit = g.pin
        ? { op: "add_pin", patch: p.name, at: at.map(r2) }
        : { op: "add_handle", patch: p.name, from: at.map(r2), radius: r2(40 / p.scale) };
      send({ type: "edit", rev: scene.rev, commit: true, edit });
      return;
    }
    if (g.kind === "patch" && g.mode === "move" && !g.moved) { selected = null; drawOverlay(); }
    if (!g.moved || g.kind === "pin") {
      if (g.kind === "radius") drawOverlay();
      else copyPair(q, g.shift);
      return;
    }
    const edit = editFor(g, q);
    pendingEdit = null;
    pointerAt = 0;
    if (edit) send({ type: "edit", rev: scene.rev, commit: true, t: g.t, edit });
  });

  function copyPair(q, source) {
    let pair = `[${Math.round(q[0])}, ${Math.round(q[1])}]`;
    if (source && located && located.patch !== null) pair = `[${r2(located.source[0])}, ${r2(located.source[1])}]`;
    const done = () => notice(`copied ${pair}`, "ok");
    if (navigator.clipboard) navigator.clipboard.writeText(pair).then(done, () => notice(pair));
    else notice(pair);
  }

  // --- timeline ---
  // The markers are built again only when their keys, the duration or the selection change.
  let markersDrawn = null;
  function drawMarkers() {
    const drawn = scene && JSON.stringify([
      scene.duration,
      selected,
      scene.patches.map((p) => [p.name, p.keys, p.handles.map((h) => h.keys)]),
    ]);
    if (drawn === markersDrawn) return;
    markersDrawn = drawn;
    const box = $("markers");
    box.textContent = "";
    if (!scene) return;
    let row = 0;
    // One row per keyed track: the patch's, then each handle's (`handle` null: the patch).
    const rows = (owner, keys, handle) => {
      for (const [track, times] of Object.entries(keys)) {
        if (!times.length) continue;
        for (const t of times) {
          const key = { kind: "key", patch: owner.name, handle, track, t };
          const m = document.createElement("div");
          m.className = handle === null ? "marker" : "marker handle";
          if (sameKey(selected, key)) m.classList.add("selected");
          m.style.left = `${(100 * t) / scene.duration}%`;
          m.style.top = `${row * 10 + 2}px`;
          m.style.background = TRACK_COLOURS[track];
          const what = handle === null ? `${owner.name} ${track}` : `${owner.name} handle ${handle} ${track}`;
          m.title = `${what} key at ${t} s (drag: move_key, Delete: remove_key)`;
          m.dataset.key = JSON.stringify(key);
          m.addEventListener("pointerdown", (e) => markerDrag(e, m, key));
          box.appendChild(m);
        }
        row++;
      }
    };
    for (const p of scene.patches) {
      rows(p, p.keys, null);
      p.handles.forEach((h, i) => rows(p, h.keys, i));
    }
    box.style.height = `${row * 10 + 4}px`;
  }
  const sameKey = (a, b) => a && a.kind === "key" && a.patch === b.patch && a.handle === b.handle && a.track === b.track && a.t === b.t;
  // A key edit on the patch's track, or its handle's.
  function keyEdit(key, fields) {
    const edit = { patch: key.patch, track: key.track, ...fields };
    if (key.handle !== null) edit.handle = key.handle;
    return edit;
  }

  function markerDrag(e, m, key) {
    e.preventDefault();
    const t = key.t;
    selected = key;
    drawMarkers();
    const box = $("markers").getBoundingClientRect();
    const timeAt = (x) => {
      const raw = Math.min(Math.max((x - box.left) / box.width, 0), 1) * scene.duration;
      return Math.round(raw * scene.fps) / scene.fps;
    };
    let to = t;
    const move = (ev) => { to = timeAt(ev.clientX); m.style.left = `${(100 * to) / scene.duration}%`; };
    const up = (ev) => {
      move(ev);
      markersDrawn = null; // the marker was moved by hand: the next scene message redraws it
      window.removeEventListener("pointermove", move);
      window.removeEventListener("pointerup", up);
      if (Math.abs(to - t) > 1e-9) {
        send({ type: "edit", rev: scene.rev, commit: true, edit: keyEdit(key, { op: "move_key", from: t, to: +to.toFixed(6) }) });
      }
    };
    window.addEventListener("pointermove", move);
    window.addEventListener("pointerup", up);
  }

  $("scrub").addEventListener("input", () => {
    scrubbing = true;
    send({ type: "seek", t: +$("scrub").value });
  });
  $("scrub").addEventListener("change", () => { scrubbing = false; });

  let lastPlay = 0;
  function playStep(now) {
    if (!playing || !scene) return;
    const wait = 1000 / scene.fps - (now - lastPlay);
    if (wait > 1) { setTimeout(() => requestAnimationFrame(playStep), wait); return; }
    lastPlay = now;
    let t = scene.t + 1 / scene.fps;
    if (t >= scene.duration - 1e-9) t = 0;
    send({ type: "seek", t });
  }
  function togglePlay() {
    playing = !playing;
    $("play").textContent = playing ? "❚❚" : "▶";
    if (playing) { lastPlay = 0; requestAnimationFrame(playStep); }
  }
  $("play").addEventListener("click", togglePlay);
  $("mesh").addEventListener("change", () => { meshOn = $("mesh").checked; send({ type: "mesh", on: meshOn }); drawOverlay(); });

  document.addEventListener("keydown", (e) => {
    const mod = e.ctrlKey || e.metaKey;
    if (e.key === "Escape" && gesture) {
      gesture = null; pendingEdit = null; pointerAt = 0;
      send({ type: "cancel" });
      notice("cancelled", "");
    } else if (mod && e.key.toLowerCase() === "z") {
      e.preventDefault();
      send({ type: "undo" });
    } else if (mod && e.key.toLowerCase() === "s") {
      e.preventDefault();
      if (!scene || !scene.file) notice("no scene file loaded: :save FILE in the terminal", "error");
      else if (confirm(`Save the session to ${scene.file}?`)) send({ type: "save", rev: scene.rev });
    } else if ((e.key === "Delete" || e.key === "Backspace") && selected && scene) {
      const s = selected;
      selected = null;
      const edit = s.kind === "handle" ? { op: "remove_handle", patch: s.patch, handle: s.index }
        : s.kind === "pin" ? { op: "remove_pin", patch: s.patch, pin: s.index }
        : keyEdit(s, { op: "remove_key", t: s.t });
      send({ type: "edit", rev: scene.rev, commit: true, edit });
    } else if (e.key === " " && e.target === overlay) {
      e.preventDefault();
      togglePlay();
    } else if (e.key.toLowerCase() === "m" && !mod && e.target === overlay) {
      $("mesh").checked = !$("mesh").checked;
      $("mesh").dispatchEvent(new Event("change"));
    }
  });
  $("coords").addEventListener("click", () => located && copyPair([located.x, located.y], false));

  connect();
})();
