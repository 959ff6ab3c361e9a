// scanlines viewer: scrub a log, tune an extractor, compare two configurations.
// Everything is computed by the server (the library); this page asks and draws.
"use strict";

const $ = (selector) => document.querySelector(selector);
const COLOURS = { returns: "#3c4043", breakpoint: "#f29900", corner: "#d93025",
                  outlier: "#202124", difference: "rgba(233, 30, 160, 0.45)", path: "#1a73e8",
                  axis: "#444" };
// The marks of the point features: the canvas and the legend draw them from this table.
const MARKS = [["breakpoints", COLOURS.breakpoint, "circle"], ["corners", COLOURS.corner, "diamond"],
               ["outliers", COLOURS.outlier, "cross"]];
// The strokes of the map's lines: the canvas and the legend draw them from this table.
// Map lines are drawn first (under the scan) and thinner than the scan's segments.
const STROKES = { map: { colour: "#7f9bb8", width: 1.5 }, segments: { width: 2.5, selected: 5 } };
const LAYERS = ["returns", "segments", "breakpoints", "corners", "outliers", "sensor", "map"];
const OFF_AT_START = ["map"];
const AXIS_FONT_PX = 12;

const state = {
  log: null, methods: new Map(), panels: [], index: 0, frame: null, world: null,
  view: "scan", compare: false, layout: "overlay", selected: null,
  transform: null,       // {scale: pixels per metre, x, y: screen position of the origin}
  requested: 0, drawn: 0, inputTime: null, playing: null,
  layers: new Set(LAYERS.filter((layer) => !OFF_AT_START.includes(layer))),  // the checkboxes under "Layers"
  map: null, mapState: "none",  // the log's line map: "none", "building", "built" or "failed"
  speed: 10,                // playback, scans per second
};
// Read by the tests and the latency benchmark: input-to-redraw times, in milliseconds.
const stats = { latencies: [], frames: 0, drawn: null };
window.viewer = { state, stats };

// -- talking to the server ------------------------------------------------------------------

async function api(path, body) {
  const options = body === undefined ? {} : {
    method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body),
  };
  const response = await fetch(path, options);
  const answer = await response.json();
  if (!response.ok) throw new Error(answer.error || response.statusText);
  return answer;
}

function showError(error) {
  const box = $("#error");
  box.hidden = error === null;
  box.textContent = error === null ? "" : String(error.message || error);
}

// -- a configuration panel: method, preset and parameter controls from the domains ------

class ConfigPanel {
  constructor(element, name, onChange) {
    this.element = element; this.name = name; this.onChange = onChange;
    this.controls = new Map();   // parameter name -> {read, write, row}
    element.innerHTML = `<h2>Configuration ${name}</h2>
      <div class="param"><label>method</label><select class="method"></select></div>
      <div class="param"><label>preset</label><select class="preset"></select></div>
      <div class="params"></div>
      <div class="actions"><button type="button" class="copy">Copy as command</button>
        <button type="button" class="save">Save config</button></div>
      <pre class="command" hidden></pre>`;
    this.methodSelect = element.querySelector(".method");
    this.presetSelect = element.querySelector(".preset");
    for (const method of state.methods.keys()) this.methodSelect.add(new Option(method, method));
    this.methodSelect.addEventListener("change", (event) => this.setMethod(event));
    this.presetSelect.addEventListener("change", (event) => this.setPreset(event));
    element.querySelector(".copy").addEventListener("click", () => this.copyCommand());
    element.querySelector(".save").addEventListener("click", () => this.saveConfig());
  }

  get method() { return state.methods.get(this.methodSelect.value); }
  get preset() { return this.presetSelect.value || null; }

  defaults() {
    const values = {};
    for (const p of this.method.params) values[p.name] = p.default;
    return { ...values, ...(this.preset ? this.method.presets[this.preset] : {}) };
  }

  setMethod(event, values = {}) {
    this.presetSelect.innerHTML = "";
    this.presetSelect.add(new Option("(defaults)", ""));
    for (const preset of Object.keys(this.method.presets)) this.presetSelect.add(new Option(preset, preset));
    this.buildParams(values);
    if (event) this.onChange(event);
  }

  setPreset(event) {
    const defaults = this.defaults();
    for (const [name, control] of this.controls) control.write(defaults[name]);
    this.markChanged();
    this.onChange(event);
  }

  buildParams(values) {
    const box = this.element.querySelector(".params");
    box.innerHTML = "";
    this.controls.clear();
    const defaults = { ...this.defaults(), ...values };
    for (const param of this.method.params) {
      const row = document.createElement("div");
      row.className = "param";
      row.dataset.param = param.name;
      row.title = `${param.name}: ${param.doc}\nallowed: ${param.allowed}`;
      row.innerHTML = `<label><span class="name"></span><small class="doc"></small></label><span class="value"></span>`;
      row.querySelector(".name").textContent = param.name;
      row.querySelector(".doc").textContent = shortDoc(param.doc);
      const control = makeControl(param.domain, row.querySelector(".value"), param.name);
      control.write(defaults[param.name]);
      control.row = row;
      control.applies = param.applies;
      row.addEventListener("input", (event) => this.changed(event, control));
      row.addEventListener("change", (event) => this.changed(event, control));
      this.controls.set(param.name, control);
      box.append(row);
    }
    this.markChanged();
  }

  changed(event, control) {
    this.showApplying();
    if (control.read() === undefined) return;   // not a valid value yet: keep the last frame
    this.markChanged();
    this.onChange(event);
  }

  // Hide the parameters the chosen values make unread (a clustering rule's constants when
  // another rule is chosen, a switched-off step's options): the server's ``applies``.
  showApplying() {
    for (const control of this.controls.values()) {
      const rule = control.applies;
      const other = rule ? this.controls.get(rule.param) : null;
      const value = other ? other.read() : undefined;
      const held = value !== undefined && rule.values.some((v) => JSON.stringify(v) === JSON.stringify(value));
      control.row.hidden = value !== undefined && held !== rule.when_in;
    }
  }

  markChanged() {
    this.showApplying();
    const overrides = this.overrides();
    for (const [name, control] of this.controls) control.row.classList.toggle("changed", name in overrides);
  }

  // The parameters that differ from the method's (or preset's) defaults.
  overrides() {
    const defaults = this.defaults(), params = {};
    for (const [name, control] of this.controls) {
      const value = control.read();
      if (value !== undefined && JSON.stringify(value) !== JSON.stringify(defaults[name])) params[name] = value;
    }
    return params;
  }

  config() { return { method: this.methodSelect.value, preset: this.preset, params: this.overrides() }; }

  load(config) {
    this.methodSelect.value = config.method;
    this.setMethod(null, config.params || {});
    this.presetSelect.value = config.preset || "";
    const values = { ...this.defaults(), ...(config.params || {}) };
    for (const [name, control] of this.controls) control.write(values[name]);
    this.markChanged();
  }

  async copyCommand() {
    try {
      const answer = await api("/api/config", { config: this.config(), log: state.log.path });
      const box = this.element.querySelector(".command");
      box.hidden = false;
      box.textContent = answer.command;
      await navigator.clipboard.writeText(answer.command).catch(() => {});
    } catch (error) { showError(error); }
  }

  async saveConfig() {
    try {
      const answer = await api("/api/config", { config: this.config() });
      const link = document.createElement("a");
      link.href = URL.createObjectURL(new Blob([answer.toml], { type: "application/toml" }));
      link.download = `scanlines-${this.methodSelect.value}.toml`;
      link.click();
      URL.revokeObjectURL(link.href);
    } catch (error) { showError(error); }
  }
}

// A parameter's doc, short: its first clause (before "; ", ", or " or " (with").
function shortDoc(doc) {
  const first = doc.split(/; |, or | \(with /)[0].trim();
  return first.length <= 44 ? first : `${first.slice(0, first.lastIndexOf(" ", 42))}…`;
}

// One parameter's input(s), from its domain: read() gives the typed value, or undefined
// while the input does not hold an allowed one.
function makeControl(domain, box, name) {
  if (domain.type === "choice") {
    const select = document.createElement("select");
    select.setAttribute("aria-label", name);
    for (const choice of domain.choices) select.add(new Option(String(choice), JSON.stringify(choice)));
    box.append(select);
    return { read: () => JSON.parse(select.value), write: (v) => { select.value = JSON.stringify(v); } };
  }
  const alternative = "or" in domain ? domain.or : undefined;   // "auto", or null (off)
  const element = domain.type === "pair" ? domain.element : domain;
  const inputs = (domain.type === "pair" ? [0, 1] : [0]).map((k) => {
    const input = document.createElement("input");
    input.type = "number";
    input.step = element.type === "int" ? "1" : "any";
    input.min = element.low; input.max = element.high;
    input.setAttribute("aria-label", domain.type === "pair" ? `${name} ${k}` : name);
    box.append(input);
    return input;
  });
  let toggle = null;
  if (alternative !== undefined) {
    const label = document.createElement("label");
    toggle = document.createElement("input");
    toggle.type = "checkbox";
    toggle.setAttribute("aria-label", `${name} ${alternative === null ? "off" : alternative}`);
    label.append(toggle, alternative === null ? "off" : String(alternative));
    box.append(label);
    toggle.addEventListener("change", () => { for (const i of inputs) i.disabled = toggle.checked; });
  }
  const readNumber = (input) => {
    const value = Number(input.value);
    const valid = input.value.trim() !== "" && Number.isFinite(value) && inDomain(element, value);
    input.classList.toggle("invalid", !valid);
    return valid ? value : undefined;
  };
  return {
    read() {
      if (toggle && toggle.checked) return alternative;
      const values = inputs.map(readNumber);
      if (values.includes(undefined)) return undefined;
      return domain.type === "pair" ? values : values[0];
    },
    write(value) {
      const off = value === alternative && alternative !== undefined;
      if (toggle) toggle.checked = off;
      const numbers = off ? [] : (Array.isArray(value) ? value : [value]);
      inputs.forEach((input, k) => {
        input.disabled = off;
        if (numbers[k] !== undefined && numbers[k] !== null) input.value = numbers[k];
        input.classList.remove("invalid");
      });
    },
  };
}

function inDomain(domain, value) {
  if (domain.type === "int" && !Number.isInteger(value)) return false;
  if (value < domain.low || value > domain.high) return false;
  return !(domain.low_open && value === domain.low);
}

// -- frames: ask, then draw ------------------------------------------------------------------

// The first scan's returns, drawn at once: they need no kernel, while the extractor's load.
async function drawReturnsFirst() {
  try {
    state.frame = await api("/api/frame", { index: 0, configs: [] });
    draw();
    showFacts();
    stats.frames += 1;
  } catch (error) { showError(error); }
}

function configs() {
  return state.panels.slice(0, state.compare ? 2 : 1).map((panel) => panel.config());
}

// Ask for the current scan (or world stretch); a reply older than the newest drawn is dropped.
async function refresh(event) {
  if (event && event.timeStamp !== undefined && state.inputTime === null) state.inputTime = event.timeStamp;
  const ticket = ++state.requested;
  try {
    if (state.view === "world") {
      const span = Math.max(1, Number($("#world-span").value) || 200);
      const answer = await api("/api/world", {
        first: Math.max(0, state.index - span + 1), last: state.index, config: configs()[0] });
      if (ticket < state.drawn) return;
      state.world = answer;
    } else {
      const answer = await api("/api/frame", { index: state.index, configs: configs() });
      if (ticket < state.drawn) return;
      state.frame = answer;
    }
    state.drawn = ticket;
    showError(null);
    draw();
    showFacts();
  } catch (error) {
    showError(error);
  }
  requestAnimationFrame(() => {
    if (state.inputTime !== null && ticket === state.requested) {
      stats.latencies.push(performance.now() - state.inputTime);
      state.inputTime = null;
    }
    stats.frames += 1;
    document.body.dataset.frame = String(ticket);
  });
}

function canvases() {
  const side = state.compare && state.layout === "side" && state.view === "scan";
  $("#view-1").hidden = !side;
  return side ? [$("#view-0 canvas"), $("#view-1 canvas")] : [$("#view-0 canvas")];
}

function draw() {
  const list = canvases();
  for (const canvas of list) {
    const ratio = window.devicePixelRatio || 1;
    const width = canvas.clientWidth, height = canvas.clientHeight;
    if (canvas.width !== Math.round(width * ratio)) canvas.width = Math.round(width * ratio);
    if (canvas.height !== Math.round(height * ratio)) canvas.height = Math.round(height * ratio);
    const context = canvas.getContext("2d");
    context.setTransform(ratio, 0, 0, ratio, 0, 0);
    context.clearRect(0, 0, width, height);
    if (!state.transform) fit(width, height);
    drawGrid(context, width, height);
  }
  stats.axis = { fontPx: AXIS_FONT_PX, colour: COLOURS.axis };
  if (state.view === "world") return drawWorld(list[0].getContext("2d"));
  const frame = state.frame;
  if (!frame) return;
  stats.drawn = { index: frame.index, segments: frame.results.map(() => 0), differences: 0,
                  layers: Object.fromEntries(LAYERS.map((layer) => [layer, 0])), shapes: {},
                  order: [], widths: {} };
  const results = frame.results;
  list.forEach((canvas, k) => {
    const context = canvas.getContext("2d");
    const shown = list.length === 2 ? [k] : results.map((_, i) => i);
    drawMap(context, frame.pose);
    for (const i of shown) drawResult(context, frame, results[i], i, list.length === 1 && i === 1);
    drawReturns(context, frame.x, frame.y);   // on top: how well the segments fit them
    drawSensor(context);
  });
  drawLegend(results.length);
}

const toScreen = (x, y) => [state.transform.x + x * state.transform.scale,
                            state.transform.y - y * state.transform.scale];

function fit(width, height) {
  let extent = 5;
  const xs = state.view === "world" && state.world ? state.world.x : state.frame ? state.frame.x : [];
  const ys = state.view === "world" && state.world ? state.world.y : state.frame ? state.frame.y : [];
  let [minX, maxX, minY, maxY] = [Infinity, -Infinity, Infinity, -Infinity];
  xs.forEach((x, i) => {
    const y = ys[i];
    if (x === null || y === null) return;
    minX = Math.min(minX, x); maxX = Math.max(maxX, x); minY = Math.min(minY, y); maxY = Math.max(maxY, y);
  });
  if (minX === Infinity) { minX = minY = -extent; maxX = maxY = extent; }
  extent = Math.max(maxX - minX, maxY - minY, 1);
  const scale = 0.9 * Math.min(width, height) / extent;
  state.transform = { scale, x: width / 2 - scale * (minX + maxX) / 2, y: height / 2 + scale * (minY + maxY) / 2 };
}

function drawGrid(context, width, height) {
  const { scale } = state.transform;
  const steps = [0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500];
  const step = steps.find((s) => s * scale >= 50) || 1000;
  const [left, top] = [-state.transform.x / scale, state.transform.y / scale];
  const [right, bottom] = [left + width / scale, top - height / scale];
  context.strokeStyle = "#e4e4e4"; context.fillStyle = COLOURS.axis; context.lineWidth = 1;
  context.font = `${AXIS_FONT_PX}px sans-serif`;
  for (let x = Math.ceil(left / step) * step; x <= right; x += step) {
    const [sx] = toScreen(x, 0);
    context.beginPath(); context.moveTo(sx, 0); context.lineTo(sx, height); context.stroke();
    context.fillText(`${+x.toFixed(1)} m`, sx + 2, height - 5);
  }
  for (let y = Math.ceil(bottom / step) * step; y <= top; y += step) {
    const [, sy] = toScreen(0, y);
    context.beginPath(); context.moveTo(0, sy); context.lineTo(width, sy); context.stroke();
    context.fillText(`${+y.toFixed(1)} m`, 2, sy - 2);
  }
}

function drawReturns(context, xs, ys, colour = COLOURS.returns, size = 2) {
  if (!state.layers.has("returns")) return;
  context.fillStyle = colour;
  for (let i = 0; i < xs.length; i++) {
    if (xs[i] === null || ys[i] === null) continue;
    const [sx, sy] = toScreen(xs[i], ys[i]);
    context.fillRect(sx - size / 2, sy - size / 2, size, size);
    stats.drawn.layers.returns += 1;
  }
}

const segmentColour = (k) => `hsl(${(k * 137.5) % 360}, 70%, 40%)`;

function drawResult(context, frame, result, which, dashed) {
  const differing = new Set(result.differing_segments || []);
  if (state.layers.has("segments")) result.segments.forEach((segment, k) => {
    const [a, b] = [toScreen(...segment.start), toScreen(...segment.end)];
    if (differing.has(k)) {
      strokeLine(context, a, b, COLOURS.difference, 10, []);
      stats.drawn.differences += 1;
    }
    stats.drawn.segments[which] += 1;
    const selected = state.selected && state.selected.which === which && state.selected.k === k;
    strokeLine(context, a, b, segmentColour(k), selected ? STROKES.segments.selected : STROKES.segments.width, dashed ? [6, 4] : []);
    stats.drawn.layers.segments += 1;
    drawnNow("segments", STROKES.segments.width);
  });
  const point = (beam) => [frame.x[beam], frame.y[beam]];
  for (const [name, colour, shape] of MARKS) {
    if (!state.layers.has(name)) continue;
    const differ = new Set(result[`differing_${name}`] || []);
    for (const beam of result[name]) {
      const [x, y] = point(beam);
      if (x === null || x === undefined) continue;
      const [sx, sy] = toScreen(x, y);
      if (differ.has(beam)) mark(context, sx, sy, COLOURS.difference, "ring");
      mark(context, sx, sy, colour, shape, dashed);
      stats.drawn.layers[name] += 1;
      stats.drawn.shapes[name] = shape;
    }
  }
}

function strokeLine(context, a, b, colour, width, dash) {
  context.strokeStyle = colour; context.lineWidth = width; context.setLineDash(dash);
  context.lineCap = "round";
  context.beginPath(); context.moveTo(...a); context.lineTo(...b); context.stroke();
  context.setLineDash([]);
}

function mark(context, x, y, colour, shape, hollow = false) {
  context.strokeStyle = colour; context.fillStyle = colour; context.lineWidth = 1.5;
  context.beginPath();
  if (shape === "circle") context.arc(x, y, 4, 0, 2 * Math.PI);
  else if (shape === "ring") { context.lineWidth = 4; context.arc(x, y, 8, 0, 2 * Math.PI); context.stroke(); return; }
  else if (shape === "diamond") { context.moveTo(x, y - 5); context.lineTo(x + 5, y); context.lineTo(x, y + 5); context.lineTo(x - 5, y); context.closePath(); }
  else { context.moveTo(x - 3, y - 3); context.lineTo(x + 3, y + 3); context.moveTo(x + 3, y - 3); context.lineTo(x - 3, y + 3); context.stroke(); return; }
  if (hollow) context.stroke(); else context.fill();
}

// The sensor's pose as an arrow: a shaft from its position, the head where it looks.
function drawSensor(context, pose = [0, 0, 0]) {
  if (!state.layers.has("sensor")) return;
  const [x, y] = toScreen(pose[0], pose[1]);
  const [c, s] = [Math.cos(pose[2]), -Math.sin(pose[2])];
  const at = (along, across) => [x + along * c - across * s, y + along * s + across * c];
  context.strokeStyle = COLOURS.path; context.fillStyle = COLOURS.path; context.lineWidth = 2.5;
  context.lineCap = "round";
  context.beginPath(); context.moveTo(...at(0, 0)); context.lineTo(...at(12, 0)); context.stroke();
  context.beginPath(); context.moveTo(...at(20, 0)); context.lineTo(...at(10, 6)); context.lineTo(...at(10, -6));
  context.closePath(); context.fill();
  stats.drawn.layers.sensor += 1;
  stats.drawn.shapes.sensor = "arrow";
}

// The map's lines, under everything: in the world frame, or in the sensor frame of the scan
// at ``pose`` (the scan view).
function drawMap(context, pose) {
  if (!state.layers.has("map") || !state.map) return;
  const place = pose ? inSensorFrame(pose) : (point) => point;
  const { colour, width } = STROKES.map;
  for (const line of state.map.lines) {
    strokeLine(context, toScreen(...place(line.start)), toScreen(...place(line.end)), colour, width, []);
    stats.drawn.layers.map += 1;
  }
  if (state.map.lines.length) drawnNow("map", width);
  stats.drawn.shapes.map = "line";
}

// The order in which the layers were first drawn (what lies under what) and their widths.
function drawnNow(layer, width) {
  if (!stats.drawn.order.includes(layer)) stats.drawn.order.push(layer);
  stats.drawn.widths[layer] = width;
}

// World point -> the sensor frame of a scan at ``pose`` (x, y, theta).
function inSensorFrame([x0, y0, theta]) {
  const [c, s] = [Math.cos(theta), Math.sin(theta)];
  return ([x, y]) => [c * (x - x0) + s * (y - y0), -s * (x - x0) + c * (y - y0)];
}

// The map is built once, on the first time its layer is switched on (configuration A's
// settings at that time); a failure is said, and switching the layer on again retries.
async function loadMap() {
  if (state.mapState === "building" || state.mapState === "built") return;
  state.mapState = "building";
  showMapState("building map…");
  try {
    state.map = await api("/api/map", { config: configs()[0] });
    state.mapState = "built";
    const { method, preset } = state.map.config;
    showMapState(`${state.map.lines.length} map lines, built with ${method}${preset ? ` ${preset}` : ""} (configuration A then)`);
    draw();
  } catch (error) {
    state.mapState = "failed";
    showMapState(`map: ${error.message || error}`);
    showError(error);
  }
}

function showMapState(text) { $("#map-state").textContent = text; }

function drawWorld(context) {
  const world = state.world;
  if (!world) return;
  const segments = state.layers.has("segments") ? world.segments : [];
  stats.drawn = { world: world.scans, segments: [segments.length], differences: 0,
                  layers: Object.fromEntries(LAYERS.map((layer) => [layer, 0])), shapes: {},
                  order: [], widths: {} };
  drawMap(context);
  drawReturns(context, world.x, world.y, "#b0b4ba", 1.5);
  if (state.layers.has("sensor")) {
    context.strokeStyle = COLOURS.path; context.lineWidth = 1;
    context.beginPath();
    world.path.forEach((pose, k) => { const [x, y] = toScreen(pose[0], pose[1]); k ? context.lineTo(x, y) : context.moveTo(x, y); });
    context.stroke();
  }
  segments.forEach((s, k) => strokeLine(context, toScreen(s[0], s[1]), toScreen(s[2], s[3]), segmentColour(k), STROKES.segments.width, []));
  stats.drawn.layers.segments = segments.length;
  if (segments.length) drawnNow("segments", STROKES.segments.width);
  drawSensor(context, world.path[world.path.length - 1]);
  drawLegend(1);
}

// The legend: one entry per layer drawn, each with the symbol the canvas draws for it.
function drawLegend(results) {
  const svg = (shape, body) => `<svg data-shape="${shape}" viewBox="0 0 22 12">${body}</svg>`;
  const line = (colour, dash = "", width = 3) => svg("line", `<line x1="1" y1="6" x2="21" y2="6" stroke="${colour}" stroke-width="${width}" stroke-dasharray="${dash}"/>`);
  const square = (colour, size) => svg("square", `<rect x="${11 - size / 2}" y="${6 - size / 2}" width="${size}" height="${size}" fill="${colour}"/>`);
  const symbol = (shape, colour) => ({
    circle: svg("circle", `<circle cx="11" cy="6" r="4" fill="${colour}"/>`),
    diamond: svg("diamond", `<polygon points="11,1 16,6 11,11 6,6" fill="${colour}"/>`),
    cross: svg("cross", `<path d="M8 3 L14 9 M14 3 L8 9" stroke="${colour}" stroke-width="1.5"/>`),
  })[shape];
  const arrow = svg("arrow", `<line x1="2" y1="6" x2="12" y2="6" stroke="${COLOURS.path}" stroke-width="2.5" stroke-linecap="round"/><polygon points="20,6 11,1.5 11,10.5" fill="${COLOURS.path}"/>`);
  const on = (layer) => state.layers.has(layer);
  const items = [];
  if (on("map") && state.map) items.push(["map", line(STROKES.map.colour, "", STROKES.map.width), "map lines"]);
  if (on("returns")) items.push(["returns", state.view === "world" ? square("#b0b4ba", 3) : square(COLOURS.returns, 3), "returns"]);
  if (on("segments")) {
    items.push(["segments", line(segmentColour(1)), state.view === "world" ? "segments" : "segments A"]);
    if (results === 2 && state.layout === "overlay") items.push(["segments", line(segmentColour(1), "6 4"), "segments B (dashed)"]);
    if (results === 2 && state.layout === "side") items.push(["segments", line(segmentColour(1)), "segments B (right)"]);
  }
  if (state.view === "scan") {
    for (const [name, colour, shape] of MARKS) if (on(name)) items.push([name, symbol(shape, colour), name]);
    if (results === 2) items.push(["difference", line(COLOURS.difference), "differs between A and B"]);
  } else if (on("sensor")) items.push(["sensor", line(COLOURS.path), "sensor path"]);
  if (on("sensor")) items.push(["sensor", arrow, "sensor pose"]);
  $("#legend").innerHTML = items.map(([layer, icon, text]) => `<li data-layer="${layer}">${icon}${text}</li>`).join("");
}

// -- facts and the selected segment ----------------------------------------------------------

function showFacts() {
  const rows = [];
  if (state.view === "world") {
    const w = state.world;
    rows.push(["scans drawn", `${w.scans} of ${w.first}..${w.last}`], ["segments", w.segments.length]);
  } else {
    const f = state.frame;
    rows.push(["scan (log record)", `${f.index} (${f.record})`],
              ["time", f.timestamp === null ? "-" : `${f.timestamp.toFixed(3)} s`],
              ["beams / returns", `${f.beams} / ${f.returns}`],
              ...noiseRows(f.noise));
    if (f.results.length === 0) rows.push(["features", "extracting…"]);
    f.results.forEach((r, i) => {
      const tag = f.results.length === 2 ? ` ${"AB"[i]}` : "";
      rows.push([`segments${tag}`, r.segments.length, `segments-${i}`],
                [`breakpoints${tag}`, r.breakpoints.length, `breakpoints-${i}`],
                [`corners${tag}`, r.corners.length, `corners-${i}`],
                [`outliers${tag}`, r.outliers.length, `outliers-${i}`],
                [`extraction${tag}`, `${r.extract_ms.toFixed(2)} ms`]);
      if (r.differing_segments) rows.push([`segments only in${tag}`, r.differing_segments.length, `differing-${i}`]);
    });
  }
  $("#facts").innerHTML = rows.map(([what, value, key]) =>
    `<tr><td>${what}</td><td${key ? ` data-fact="${key}"` : ""}>${value}</td></tr>`).join("");
}

// The noise the extraction uses, named: the sensor profile's when there is one (this
// scan's own, not used, beside it), else this scan's own.
function noiseRows(scanNoise) {
  const text = (n) => n === null || n === undefined ? "-" : `${(1000 * n.sigma0).toFixed(1)} mm + ${(100 * n.per_metre).toFixed(2)} % r`;
  const profile = state.log && state.log.profile_noise;
  if (!profile) return [["noise used: this scan's own", text(scanNoise), "noise-used"]];
  return [["noise used: sensor profile", text(profile), "noise-used"],
          ["noise of this scan (not used)", text(scanNoise), "noise-scan"]];
}

function showSelection() {
  const box = $("#selection");
  const s = state.selected && state.frame && state.frame.results[state.selected.which]?.segments[state.selected.k];
  if (!s) { box.textContent = "click a segment"; box.className = "muted"; return; }
  box.className = "";
  const deg = (radians) => (radians * 180 / Math.PI).toFixed(2);
  const c = s.covariance;
  const rows = [["configuration", "AB"[state.selected.which]], ["beams", `${s.first}..${s.last}`],
    ["rho", `${s.rho.toFixed(4)} m`], ["alpha", `${deg(s.alpha)} deg`], ["length", `${s.length.toFixed(3)} m`],
    ["returns", s.n_points], ["rms", `${(1000 * s.rms).toFixed(1)} mm`], ["ends", `${s.start_kind}, ${s.end_kind}`],
    ["var rho", `${c[0][0].toExponential(2)} m²`], ["cov rho alpha", c[0][1].toExponential(2)],
    ["var alpha", `${c[1][1].toExponential(2)} rad²`]];
  box.innerHTML = `<table>${rows.map(([a, b]) => `<tr><td>${a}</td><td>${b}</td></tr>`).join("")}</table>`;
}

function pick(canvas, event) {
  if (state.view !== "scan" || !state.frame) return;
  const rect = canvas.getBoundingClientRect();
  const [px, py] = [event.clientX - rect.left, event.clientY - rect.top];
  const side = canvases().length === 2;
  const candidates = side ? [canvas === $("#view-1 canvas") ? 1 : 0] : state.frame.results.map((_, i) => i);
  let best = null;
  for (const which of candidates) {
    state.frame.results[which].segments.forEach((s, k) => {
      const d = distanceToSegment([px, py], toScreen(...s.start), toScreen(...s.end));
      if (d < 8 && (!best || d < best.d)) best = { which, k, d };
    });
  }
  state.selected = best;
  draw();
  showSelection();
}

function distanceToSegment(p, a, b) {
  const [dx, dy] = [b[0] - a[0], b[1] - a[1]];
  const t = Math.max(0, Math.min(1, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy || 1)));
  return Math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy);
}

// -- zoom, pan, scrub, play ------------------------------------------------------------------

function attachPointer(canvas) {
  let drag = null;
  canvas.addEventListener("wheel", (event) => {
    event.preventDefault();
    const rect = canvas.getBoundingClientRect();
    const [px, py] = [event.clientX - rect.left, event.clientY - rect.top];
    const factor = Math.exp(-event.deltaY * 0.0015);
    const t = state.transform;
    t.x = px - (px - t.x) * factor; t.y = py - (py - t.y) * factor; t.scale *= factor;
    draw();
  }, { passive: false });
  canvas.addEventListener("pointerdown", (event) => { drag = { x: event.clientX, y: event.clientY, moved: false }; });
  canvas.addEventListener("pointermove", (event) => {
    if (!drag) return;
    const [dx, dy] = [event.clientX - drag.x, event.clientY - drag.y];
    if (Math.abs(dx) + Math.abs(dy) > 2) drag.moved = true;
    state.transform.x += dx; state.transform.y += dy;
    drag.x = event.clientX; drag.y = event.clientY;
    if (drag.moved) draw();
  });
  canvas.addEventListener("pointerup", (event) => { if (drag && !drag.moved) pick(canvas, event); drag = null; });
  canvas.addEventListener("dblclick", fitView);
}

// Back to the initial view: the data fitted to the window (the "Fit view" button, or a double-click).
function fitView() { state.transform = null; draw(); }

function goTo(index, event) {
  const last = Math.max(0, state.log.scans - 1);
  state.index = Math.min(Math.max(0, Math.round(index) || 0), last);
  $("#scan-slider").value = state.index;
  $("#scan-index").value = state.index;
  state.selected = null;
  showSelection();
  refresh(event);
}

// The time between two scans of the playback, in milliseconds (from the speed control).
const playInterval = () => 1000 / state.speed;

function togglePlay() {
  if (state.playing) { clearInterval(state.playing); state.playing = null; $("#play").textContent = "Play"; return; }
  $("#play").textContent = "Pause";
  state.playInterval = playInterval();
  state.playing = setInterval(() => {
    if (state.index >= state.log.scans - 1) return togglePlay();
    if (state.drawn === state.requested) goTo(state.index + 1);
  }, state.playInterval);
}

function setSpeed(speed) {
  state.speed = speed;
  if (state.playing) { togglePlay(); togglePlay(); }   // restart at the new interval
}

async function watchLog() {
  state.log = await api("/api/log");
  const reading = !state.log.finished;
  $("#log-name").textContent = state.log.name;
  $("#scan-count").textContent = state.log.scans.toLocaleString();
  $("#scan-slider").max = Math.max(0, state.log.scans - 1);
  $("#scan-index").max = Math.max(0, state.log.scans - 1);
  $("#world-radio").disabled = !state.log.poses;
  showPoseNote();
  const notes = [`${state.log.format} log`, reading ? "reading…" : `${state.log.scans.toLocaleString()} scans`];
  if (!state.log.ready) notes.push("preparing the extractor (measuring the sensor profile)");
  else if (state.log.profile) notes.push(`sensor profile ${state.log.profile}`);
  if (state.log.error) notes.push(`reading stopped: ${state.log.error}`);
  for (const note of (state.log.reader && state.log.reader.notes) || []) notes.push(note);
  $("#log-state").textContent = notes.join(", ");
  if (state.log.error) showError(`reading stopped: ${state.log.error}`);
  if (reading || !state.log.ready) setTimeout(watchLog, 300);
}

// Which poses the world view stands on (corrected, or raw odometry), as the server says.
function showPoseNote() {
  const note = $("#pose-note");
  note.hidden = state.view !== "world" || !state.log || !state.log.poses_note;
  note.textContent = state.log && state.log.poses_note ? state.log.poses_note : "";
  $("#world-radio").parentElement.title = note.textContent;
}

async function start() {
  const returnsDrawn = drawReturnsFirst();   // needs neither the methods nor the log's state
  const [methods] = await Promise.all([api("/api/methods"), watchLog()]);
  for (const method of methods) state.methods.set(method.name, method);
  const initial = state.log.config;
  state.panels = [0, 1].map((k) => new ConfigPanel($(`#config-${k}`), "AB"[k], refresh));
  for (const panel of state.panels) panel.load(initial);
  for (const canvas of document.querySelectorAll(".view canvas")) attachPointer(canvas);

  $("#scan-slider").addEventListener("input", (event) => goTo(Number(event.target.value), event));
  $("#scan-index").addEventListener("change", (event) => goTo(Number(event.target.value), event));
  $("#play").addEventListener("click", togglePlay);
  $("#compare").addEventListener("change", (event) => {
    state.compare = event.target.checked;
    $("#config-1").hidden = !state.compare;
    $("#compare-mode").disabled = !state.compare;
    refresh(event);
  });
  $("#compare-mode").addEventListener("change", (event) => {
    state.layout = event.target.value; state.transform = null; refresh(event);
  });
  for (const radio of document.querySelectorAll("input[name=view]")) {
    radio.addEventListener("change", (event) => {
      state.view = event.target.value; state.transform = null;
      state.selected = null;   // a segment of the scan view is not one of the world's
      showSelection(); showPoseNote(); refresh(event);
    });
  }
  for (const box of document.querySelectorAll("#layers input")) {
    box.addEventListener("change", (event) => {
      if (event.target.checked) state.layers.add(event.target.dataset.layer);
      else state.layers.delete(event.target.dataset.layer);
      if (event.target.checked && event.target.dataset.layer === "map") loadMap();
      draw();
    });
  }
  $("#fit").addEventListener("click", fitView);
  $("#speed").addEventListener("change", (event) => setSpeed(Number(event.target.value)));
  $("#world-span").addEventListener("change", (event) => refresh(event));
  document.addEventListener("keydown", (event) => {
    if (event.target.tagName === "INPUT" || event.target.tagName === "SELECT") return;
    if (event.key === "ArrowRight") goTo(state.index + 1, event);
    if (event.key === "ArrowLeft") goTo(state.index - 1, event);
    if (event.key === " ") { event.preventDefault(); togglePlay(); }
  });
  window.addEventListener("resize", () => draw());
  await returnsDrawn;
  await refresh();
}

start().catch(showError);
