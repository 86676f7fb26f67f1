// ndtrace viewer: the canvas and controls of `ndtrace view` and of ndtrace.widget (one file,
// plain ES module, no build step). The server (python/ndtrace/viewer/session.py) owns the
// view: every rotation is computed there with ndtrace.rotation, so the page only reports the
// mouse in picture pixels and draws the frames it gets back.
//
// mount(root, transport) builds the viewer inside `root` and returns its live state, which
// the page exposes as window.ndtraceViewer:
//   frames       frames drawn so far
//   lastFrameMs  the server-side time (trace + composite + encode) of the last frame, ms
//   rotation     the current object rotation, N rows of N numbers (row-major)
//   sent, acked  the sequence number of the last input sent and of the last one applied
// transport: { send(object), onMessage(callback(meta, bytes|null)), onClose(callback) }.

const AXES = ["x", "y", "z", "w"];

function axisName(dim, i) {
  return dim <= 4 ? AXES[i] : `x${i}`;
}

function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") node.className = v;
    else if (k === "text") node.textContent = v;
    else if (k.startsWith("on")) node.addEventListener(k.slice(2), v);
    else node.setAttribute(k, v);
  }
  for (const c of children) if (c != null) node.append(c);
  return node;
}

function formatMatrix(m) {
  return m.map((row) => row.map((v) => (Math.abs(v) < 5e-5 ? 0 : v).toFixed(4).padStart(7)).join(" ")).join("\n");
}

function parseMatrix(text) {
  return text
    .trim()
    .split(/\n|\]\s*,?\s*\[/)
    .map((line) => line.replace(/[\[\],]/g, " ").trim().split(/\s+/).filter(Boolean).map(Number))
    .filter((row) => row.length > 0);
}

// Opacity sliders are logarithmic: position p in [0, 1000] <-> opacity 0.01 ... 2.
const OPACITY_MIN = 0.01, OPACITY_MAX = 2;
const toOpacity = (p) => OPACITY_MIN * Math.pow(OPACITY_MAX / OPACITY_MIN, p / 1000);
const fromOpacity = (o) => (1000 * Math.log(Math.max(o, OPACITY_MIN) / OPACITY_MIN)) / Math.log(OPACITY_MAX / OPACITY_MIN);

export function mount(root, transport) {
  const state = { frames: 0, lastFrameMs: null, rotation: [], sent: 0, acked: 0, dim: null, quality: null, options: {} };
  let hello = null;
  let arcballMode = false;
  let rollHelp = "";

  /** The option value of a select's choice: its text ("volume", "auto", "true", "false"). */
  const choiceValue = (c) => String(c);

  // -- layout --------------------------------------------------------------------------
  const canvas = el("canvas", { class: "ndv-canvas", width: 512, height: 512, tabindex: 0 });
  const badge = el("div", { class: "ndv-badge", text: "connecting…" });
  const hint = el("div", { class: "ndv-hint" });
  const stage = el("div", { class: "ndv-stage" }, canvas, badge, hint);
  const title = el("span", { class: "ndv-scene", text: "" });
  const status = el("span", { class: "ndv-status", text: "" });
  const bar = el("header", { class: "ndv-bar" }, el("span", { class: "ndv-logo", text: "ndtrace view" }), title, status);

  const rollButton = el("button", { class: "ndv-seg ndv-on", text: "Rolling ball", title: "drag turns x–w / y–w (key A toggles)" });
  const arcButton = el("button", { class: "ndv-seg", text: "4D arcball", title: "drag: left factor, ctrl-drag: right factor (key A)" });
  const controllerHelp = el("p", { class: "ndv-help" });
  const rotateSection = el("section", {}, el("h3", { text: "Rotate" }), el("div", { class: "ndv-segs" }, rollButton, arcButton), controllerHelp);

  const modeSelect = el("select", { class: "ndv-mode", title: "composite mode (keys M / shift-M)" });
  const opacity = el("input", { type: "range", min: 0, max: 1000, step: 1, class: "ndv-opacity", title: "opacity (keys [ and ])" });
  const opacityValue = el("output", { class: "ndv-value" });
  const depthCue = el("input", { type: "range", min: 0, max: 100, step: 1, class: "ndv-depthcue" });
  const depthCueValue = el("output", { class: "ndv-value" });
  const zoomValue = el("output", { class: "ndv-value" });
  const orbitValue = el("output", { class: "ndv-value" });
  const compositeSection = el(
    "section", {},
    el("h3", { text: "Composite" }),
    el("label", { class: "ndv-row" }, el("span", { text: "mode" }), modeSelect),
    el("label", { class: "ndv-row" }, el("span", { text: "opacity" }), opacity, opacityValue),
    el("label", { class: "ndv-row" }, el("span", { text: "depth cue" }), depthCue, depthCueValue),
    el("div", { class: "ndv-row" }, el("span", { text: "zoom" }), zoomValue),
    el("div", { class: "ndv-row" }, el("span", { text: "3D view" }), orbitValue),
  );
  // Slice mode: the scene cut by the hyperplane (last axis) = offset, drawn as an (N−1)-D
  // scene; the rolling ball turns the object through the hyperplane.
  const sliceOn = el("input", { type: "checkbox", class: "ndv-slice-on", title: "show the slice by the hyperplane instead of the projection" });
  const sliceOffset = el("input", { type: "range", min: -200, max: 200, step: 1, value: 0, class: "ndv-slice-offset", title: "the hyperplane's offset" });
  const sliceValue = el("output", { class: "ndv-value", text: "0.00" });
  const sliceAxis = el("span", { text: "slice" });
  const sliceSection = el(
    "section", { hidden: "" }, el("h3", { text: "Slice" }),
    el("label", { class: "ndv-row" }, sliceAxis, sliceOn),
    el("label", { class: "ndv-row" }, el("span", { text: "offset" }), sliceOffset, sliceValue),
  );
  const sendSlice = () => {
    const offset = Number(sliceOffset.value) / 100;
    sliceValue.textContent = offset.toFixed(2);
    send({ type: "slice", on: sliceOn.checked, offset });
  };
  sliceOn.addEventListener("change", sendSlice);
  sliceOffset.addEventListener("input", () => { if (sliceOn.checked) sendSlice(); else sliceValue.textContent = (Number(sliceOffset.value) / 100).toFixed(2); });
  const aidsBox = el("div", { class: "ndv-aids" });
  const aidsSection = el("section", { hidden: "" }, el("h3", { text: "Display aids" }), aidsBox);

  const button = (text, key, tip, onclick) => el("button", { class: "ndv-btn", title: `${tip} (key ${key})`, onclick }, text, el("kbd", { text: key }));
  const viewSection = el(
    "section", {}, el("h3", { text: "View" }),
    el("div", { class: "ndv-buttons" },
      button("Snap to axes", "S", "turn to the nearest axis-aligned orientation", () => send({ type: "snap" })),
      button("Reset", "R", "identity rotation, the scene's composite options", () => send({ type: "reset" }))),
    el("div", { class: "ndv-buttons ndv-orbit-buttons" },
      button("Front", "1", "3D view along the retina's slices", () => send({ type: "view", azimuth: 0, elevation: 0 })),
      button("Side", "2", "3D view from the right", () => send({ type: "view", azimuth: 90, elevation: 0 })),
      button("Top", "3", "3D view from above", () => send({ type: "view", azimuth: 0, elevation: 90 }))),
  );

  const matrix = el("textarea", { class: "ndv-matrix", rows: 4, spellcheck: "false", title: "the object rotation (rows); edit and Apply" });
  const tomlBox = el("textarea", { class: "ndv-toml", rows: 8, readonly: "", spellcheck: "false" });
  const tomlDetails = el("details", { class: "ndv-details" }, el("summary", { text: "the view as a scene file" }), tomlBox);
  const matrixSection = el(
    "section", {}, el("h3", { class: "ndv-matrix-title", text: "Rotation" }), matrix,
    el("div", { class: "ndv-buttons" },
      button("Copy TOML", "C", "copy the current view as a TOML scene", () => copyToml()),
      el("button", { class: "ndv-btn", title: "use the matrix as typed (rounded entries are re-orthonormalized)", onclick: () => applyMatrix() }, "Apply")),
    tomlDetails,
  );
  const keyList = el("ul", {});
  const keys = el("section", { class: "ndv-keys" }, el("h3", { text: "Mouse and keys" }), keyList);
  function listKeys(msg) {
    const item = (...parts) => el("li", {}, ...parts.map((p, i) => (i % 2 === 0 ? el("b", { text: p }) : p)));
    keyList.replaceChildren(
      item("drag", msg.arcball ? " rolling ball, or the 4D arcball (A toggles)" : " rolling ball"),
      ...(msg.orbit ? [item("shift-drag", " orbit the 3D view of the retina"), item("wheel", " zoom"),
        item("M", " next composite mode · ", "[ ]", " opacity"), item("1 2 3", " front, side, top")] : []),
      item("S", " snap to axes · ", "R", " reset · ", "C", " copy TOML"),
    );
  }
  const panel = el("aside", { class: "ndv-panel" }, rotateSection, matrixSection, sliceSection, compositeSection, aidsSection, viewSection, keys);
  const message = el("div", { class: "ndv-message", hidden: "" });
  const main = el("div", { class: "ndv-main" }, stage, panel);
  const viewer = el("div", { class: "ndv" }, bar, main, message);
  root.append(viewer);
  const ctx = canvas.getContext("2d");
  ctx.fillStyle = "#0b0c10";
  ctx.fillRect(0, 0, canvas.width, canvas.height);

  // -- talking to the server --------------------------------------------------------------
  function send(msg) {
    msg.seq = ++state.sent;
    transport.send(msg);
  }

  let messageTimer = null;
  function showMessage(text, kind = "error") {
    message.textContent = text;
    message.className = `ndv-message ndv-${kind}`;
    message.hidden = false;
    clearTimeout(messageTimer);
    messageTimer = setTimeout(() => (message.hidden = true), kind === "error" ? 8000 : 2500);
  }

  let drawing = Promise.resolve();
  const frameTimes = [];
  function onFrame(meta, bytes) {
    const blob = new Blob([bytes], { type: meta.format === "png" ? "image/png" : "image/jpeg" });
    drawing = drawing.then(async () => {
      const bitmap = await createImageBitmap(blob);
      ctx.imageSmoothingEnabled = true;
      ctx.imageSmoothingQuality = "high";
      ctx.drawImage(bitmap, 0, 0, canvas.width, canvas.height);
      bitmap.close();
      state.frames += 1;
      state.lastFrameMs = meta.ms;
      state.quality = meta.quality;
      const now = performance.now();
      frameTimes.push(now);
      while (frameTimes.length && now - frameTimes[0] > 1000) frameTimes.shift();
      const cells = meta.retina.join("×");
      badge.textContent = meta.quality === "draft" ? `draft · retina ${cells}` : `retina ${cells}`;
      badge.className = `ndv-badge ndv-${meta.quality}`;
      const rate = frameTimes.length >= 3 ? `${frameTimes.length} frames/s · ` : "";
      const parts = Object.entries(meta.timings).map(([k, v]) => `${k} ${v.toFixed(0)}`).join(", ");
      status.textContent = `${rate}last frame ${meta.ms.toFixed(0)} ms (${parts})`;
    }).catch((e) => showMessage(`could not draw a frame: ${e}`));
  }

  function onState(msg) {
    state.acked = msg.seq;
    state.rotation = msg.rotation;
    state.options = msg.options;
    if (document.activeElement !== sliceOn) sliceOn.checked = msg.slice != null;
    if (msg.slice != null && !sliceOffset.matches(":active")) {
      sliceOffset.value = Math.round(msg.slice * 100);
      sliceValue.textContent = msg.slice.toFixed(2);
    }
    if (document.activeElement !== matrix) matrix.value = formatMatrix(msg.rotation);
    const o = msg.options;
    if (hello && hello.dim >= 4) {
      // A slider the user is holding keeps its own position (this reply may be older).
      const held = (input) => input.matches(":active");
      modeSelect.value = o.mode ?? "";
      const op = o.opacity ?? 1;
      if (!held(opacity)) opacity.value = fromOpacity(op);
      opacityValue.textContent = op.toFixed(op < 0.1 ? 3 : 2);
      const dc = o.depth_cue ?? 0;
      if (!held(depthCue)) depthCue.value = Math.round(dc * 100);
      depthCueValue.textContent = dc.toFixed(2);
      zoomValue.textContent = `${(o.zoom ?? 1).toFixed(2)}×`;
      orbitValue.textContent = `azimuth ${(o.azimuth ?? 30).toFixed(0)}°, elevation ${(o.elevation ?? 20).toFixed(0)}°`;
      for (const aid of hello.aids) {
        const input = aidsBox.querySelector(`[data-aid="${aid.name}"]`);
        if (!input || document.activeElement === input) continue;
        const v = aid.name in o ? o[aid.name] : aid.default;
        if (aid.kind === "bool") input.checked = !!v;
        else if (aid.kind === "text") input.value = v == null ? "" : typeof v === "string" ? JSON.stringify(v) : tomlValue(v);
        else if (aid.kind === "choice") input.value = choiceValue(v);
        else if (aid.kind === "string") input.value = v ?? "";
        else input.value = v;
      }
    }
  }

  function onHello(msg) {
    hello = msg;
    state.dim = msg.dim;
    canvas.width = msg.picture[0];
    canvas.height = msg.picture[1];
    stage.style.setProperty("--aspect", `${msg.picture[0]} / ${msg.picture[1]}`);
    const res = msg.resolution.join("×");
    title.textContent = `${msg.scene} · ${msg.dim}D · retina ${res} (drafts ${msg.draft.join("×")})`;
    if (root === document.body) document.title = `${msg.scene} — ndtrace view`;
    const n = msg.dim;
    const last = axisName(n, n - 1), x = axisName(n, 0), y = axisName(n, 1);
    hint.textContent = `drag: turn ${x}–${last} / ${y}–${last}` + (msg.orbit ? " · shift-drag: orbit the 3D view · wheel: zoom" : "");
    rollHelp = `Rolling ball (course eq. 5): a drag pulls the ${last} axis toward the drag, turning the ${x}–${last} and ${y}–${last} planes; small circles turn ${x}–${y} the other way.`;
    setArcball(arcballMode);
    arcButton.hidden = !msg.arcball;
    rotateSection.querySelector(".ndv-segs").hidden = !msg.arcball;
    listKeys(msg);
    matrix.rows = n;
    matrixSection.querySelector(".ndv-matrix-title").textContent = `Rotation in SO(${n})`;
    compositeSection.hidden = !msg.orbit;
    sliceSection.hidden = !msg.slices;
    sliceAxis.textContent = `slice ${last} = offset`;
    viewSection.querySelector(".ndv-orbit-buttons").hidden = !msg.orbit;
    modeSelect.replaceChildren(
      el("option", { value: "", text: msg.mode_default ? `default (${msg.mode_default})` : "default" }),
      ...msg.modes.map((m) => el("option", { value: m, text: m })),
    );
    aidsBox.replaceChildren();
    for (const aid of msg.aids) aidsBox.append(aidControl(aid));
    aidsSection.hidden = msg.aids.length === 0;
    onState(msg);
  }

  function tomlValue(v) {
    if (Array.isArray(v)) return `[${v.map(tomlValue).join(", ")}]`;
    if (v && typeof v === "object") return `{ ${Object.entries(v).map(([k, x]) => `${k} = ${tomlValue(x)}`).join(", ")} }`;
    return typeof v === "string" ? JSON.stringify(v) : String(v);
  }

  function aidControl(aid) {
    const label = aid.name.replace(/_/g, " ");
    let input;
    if (aid.kind === "bool") {
      input = el("input", { type: "checkbox" });
      input.addEventListener("change", () => send({ type: "set", options: { [aid.name]: input.checked } }));
    } else if (aid.kind === "choice") {
      // Choices may be strings or booleans (legend: "auto", true, false): options by index.
      // A choice's option value is its name ("volume", "auto", "true"): the choices of legend
      // and axes mix a string with booleans, sent back as the choice itself.
      input = el("select", {}, ...aid.choices.map((c) => el("option", { value: choiceValue(c), text: String(c) })));
      input.addEventListener("change", () => send({ type: "set", options: {
        [aid.name]: aid.choices.find((c) => choiceValue(c) === input.value) } }));
    } else if (aid.kind === "string") {
      input = el("input", { type: "text", placeholder: "none", spellcheck: "false" });
      input.addEventListener("change", () => send({ type: "set", options: { [aid.name]: input.value === "" ? null : input.value } }));
    } else if (aid.kind === "number") {
      input = el("input", { type: "number", step: "any" });
      input.addEventListener("change", () => send({ type: "set", options: { [aid.name]: Number(input.value) } }));
    } else {
      input = el("input", { type: "text", placeholder: aid.hint || "TOML value", spellcheck: "false" });
      input.addEventListener("change", () => send({ type: "set", options: { [aid.name]: input.value } }));
    }
    input.dataset.aid = aid.name;
    input.title = `ndtrace.composite(…, ${aid.name}=…)${aid.hint ? `: ${aid.hint}` : ""}`;
    return el("label", { class: "ndv-row" }, el("span", { text: label }), input);
  }

  transport.onMessage((meta, bytes) => {
    if (bytes) return onFrame(meta, bytes);
    if (meta.type === "hello") onHello(meta);
    else if (meta.type === "state") onState(meta);
    else if (meta.type === "toml") onToml(meta);
    else if (meta.type === "error") {
      if (meta.seq != null) state.acked = Math.max(state.acked, meta.seq);
      if (document.activeElement !== matrix && state.rotation.length) matrix.value = formatMatrix(state.rotation);
      showMessage(meta.message);
    }
  });
  transport.onClose(() => {
    badge.textContent = "disconnected";
    badge.className = "ndv-badge ndv-off";
    showMessage("The connection to ndtrace view is closed: restart it and reload the page.");
  });

  // -- the mouse ----------------------------------------------------------------------------
  // Steps are collected per animation frame and sent in order (the server composes one rolling
  // ball per mouse event, so coalesced events are unpacked rather than summed).
  let drag = null; // { kind: "roll" | "orbit" | "arcball", x, y, id }
  let steps = [];
  let orbitStep = [0, 0];
  let arcPoint = null;
  let flushQueued = false;

  function picturePoint(e) {
    const r = canvas.getBoundingClientRect();
    return [((e.clientX - r.left) * canvas.width) / r.width, ((e.clientY - r.top) * canvas.height) / r.height];
  }

  function flush() {
    flushQueued = false;
    if (steps.length) send({ type: "roll", steps: steps.splice(0) });
    if (orbitStep[0] || orbitStep[1]) {
      send({ type: "orbit", dx: orbitStep[0], dy: orbitStep[1] });
      orbitStep = [0, 0];
    }
    if (arcPoint) {
      send({ type: "arcball", phase: "drag", x: arcPoint[0], y: arcPoint[1] });
      arcPoint = null;
    }
  }

  function queueFlush() {
    if (!flushQueued) {
      flushQueued = true;
      requestAnimationFrame(flush);
    }
  }

  canvas.addEventListener("contextmenu", (e) => e.preventDefault());
  canvas.addEventListener("pointerdown", (e) => {
    if (!hello || drag) return;
    canvas.setPointerCapture(e.pointerId);
    canvas.focus();
    const [x, y] = picturePoint(e);
    const kind = e.shiftKey && hello.orbit ? "orbit" : arcballMode && hello.arcball ? "arcball" : "roll";
    drag = { kind, x, y, id: e.pointerId };
    canvas.classList.add("ndv-dragging");
    if (kind === "arcball") send({ type: "arcball", phase: "press", x, y, right: e.button === 2 || e.ctrlKey });
    e.preventDefault();
  });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag || e.pointerId !== drag.id) return;
    const events = typeof e.getCoalescedEvents === "function" && e.getCoalescedEvents().length ? e.getCoalescedEvents() : [e];
    for (const ev of events) {
      const [x, y] = picturePoint(ev);
      const dx = x - drag.x, dy = y - drag.y;
      if (dx === 0 && dy === 0) continue;
      drag.x = x;
      drag.y = y;
      if (drag.kind === "roll") steps.push([dx, dy]);
      else if (drag.kind === "orbit") orbitStep = [orbitStep[0] + dx, orbitStep[1] + dy];
      else arcPoint = [x, y];
    }
    queueFlush();
  });
  const endDrag = (e) => {
    if (!drag || e.pointerId !== drag.id) return;
    flush();
    drag = null;
    canvas.classList.remove("ndv-dragging");
    send({ type: "release" });
  };
  canvas.addEventListener("pointerup", endDrag);
  canvas.addEventListener("pointercancel", endDrag);
  canvas.addEventListener("wheel", (e) => {
    if (!hello || !hello.orbit) return;
    e.preventDefault();
    const lines = e.deltaMode === 1 ? 30 : e.deltaMode === 2 ? 300 : 1;
    send({ type: "zoom", factor: Math.exp(-e.deltaY * lines * 0.0015) });
  }, { passive: false });

  // -- controls -----------------------------------------------------------------------------
  const ARC_HELP = "4D arcball (course eq. 10): the picture's disk is a ball and a drag carries one point of S³ to another: drag for the left quaternion factor, ctrl-drag (or right-drag) for the right one; the same drag both ways is the 3D arcball of x, y, z.";
  function setArcball(on) {
    arcballMode = on && !!(hello && hello.arcball);
    rollButton.classList.toggle("ndv-on", !arcballMode);
    arcButton.classList.toggle("ndv-on", arcballMode);
    controllerHelp.textContent = arcballMode ? ARC_HELP : rollHelp;
  }
  rollButton.addEventListener("click", () => setArcball(false));
  arcButton.addEventListener("click", () => setArcball(true));
  modeSelect.addEventListener("change", () => send({ type: "set", options: { mode: modeSelect.value || null } }));
  opacity.addEventListener("input", () => {
    const o = toOpacity(Number(opacity.value));
    opacityValue.textContent = o.toFixed(o < 0.1 ? 3 : 2);
    send({ type: "set", options: { opacity: Number(o.toPrecision(3)) } });
  });
  depthCue.addEventListener("input", () => send({ type: "set", options: { depth_cue: Number(depthCue.value) / 100 } }));

  function applyMatrix() {
    const m = parseMatrix(matrix.value);
    send({ type: "rotation", matrix: m });
    matrix.blur();
  }
  matrix.addEventListener("keydown", (e) => {
    if (e.key === "Enter" && (e.ctrlKey || e.metaKey)) applyMatrix();
    e.stopPropagation();
  });

  let tomlWanted = false;
  function copyToml() {
    tomlWanted = true;
    send({ type: "toml" });
  }
  async function onToml(msg) {
    tomlBox.value = msg.text;
    if (!tomlWanted) return;
    tomlWanted = false;
    try {
      await navigator.clipboard.writeText(msg.text);
      showMessage(`Copied the view as TOML (${msg.text.split("\n").length} lines).`, "info");
    } catch (e) {
      tomlDetails.open = true;
      tomlBox.select();
      showMessage("The browser refused the clipboard: the TOML is selected below, copy it with ctrl-C.", "info");
    }
  }

  function stepMode(by) {
    const values = ["", ...hello.modes];
    const i = values.indexOf(modeSelect.value);
    const next = values[(i + by + values.length) % values.length];
    send({ type: "set", options: { mode: next || null } });
  }

  viewer.addEventListener("keydown", onKey);
  if (root === document.body) document.addEventListener("keydown", (e) => { if (!viewer.contains(e.target)) onKey(e); });
  function onKey(e) {
    if (!hello || e.target.matches("input, textarea, select") || e.ctrlKey || e.metaKey || e.altKey) return;
    const k = e.key;
    const op = state.options.opacity ?? 1;
    const actions = {
      m: () => hello.orbit && stepMode(1),
      M: () => hello.orbit && stepMode(-1),
      "[": () => hello.orbit && send({ type: "set", options: { opacity: Number(Math.max(OPACITY_MIN, op / 1.25).toPrecision(3)) } }),
      "]": () => hello.orbit && send({ type: "set", options: { opacity: Number(Math.min(OPACITY_MAX, op * 1.25).toPrecision(3)) } }),
      a: () => setArcball(!arcballMode),
      s: () => send({ type: "snap" }),
      r: () => send({ type: "reset" }),
      c: () => copyToml(),
      1: () => hello.orbit && send({ type: "view", azimuth: 0, elevation: 0 }),
      2: () => hello.orbit && send({ type: "view", azimuth: 90, elevation: 0 }),
      3: () => hello.orbit && send({ type: "view", azimuth: 0, elevation: 90 }),
    };
    const action = actions[k] || actions[k.toLowerCase()];
    if (action) {
      action();
      e.preventDefault();
    }
  }

  send({ type: "hello" });
  return state;
}

// The transport of the page: one websocket, JSON text messages both ways and binary frames
// (a 4-byte little-endian header length, the JSON header, then the encoded picture).
export function websocketTransport(url) {
  const ws = new WebSocket(url);
  ws.binaryType = "arraybuffer";
  const queue = [];
  let onMessage = () => {}, onClose = () => {};
  ws.addEventListener("open", () => queue.splice(0).forEach((m) => ws.send(m)));
  ws.addEventListener("message", (e) => {
    if (typeof e.data === "string") return onMessage(JSON.parse(e.data), null);
    const view = new DataView(e.data);
    const n = view.getUint32(0, true);
    const meta = JSON.parse(new TextDecoder().decode(new Uint8Array(e.data, 4, n)));
    onMessage(meta, new Uint8Array(e.data, 4 + n));
  });
  ws.addEventListener("close", () => onClose());
  return {
    send(msg) {
      const text = JSON.stringify(msg);
      if (ws.readyState === WebSocket.OPEN) ws.send(text);
      else queue.push(text);
    },
    onMessage(cb) { onMessage = cb; },
    onClose(cb) { onClose = cb; },
  };
}
