// The viewer: a three.js scene of the stand (base, joints glowing red at their angle limits,
// legs drawn as a cylinder coloured by force and a steel rod, platform plate and axes,
// centre-of-mass trail), playback controls and small synchronised plots. Data
// come from `?data=result.csv&stand=stand.json`, from `data/index.json` (a list the Python tools
// write), or from files the user drops or picks. `window.stewartViewer` is the test hook.

import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { Result, checkStand, defaultStand, niceTicks, parseCsv, plotRange } from "./result.js";

const $ = (id) => document.getElementById(id);
const state = { result: null, index: 0, playing: false, speed: 1, time: 0, error: null, notice: null, ready: false };

// ----- scene -------------------------------------------------------------------------------

const host = $("scene");
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
host.prepend(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf4f5f7);
const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 100);
camera.up.set(0, 0, 1); // the model's z is up
camera.position.set(4.5, -4.5, 3.2);
const controls = new OrbitControls(camera, renderer.domElement);
controls.target.set(0, 0, 1.2);
controls.update();
scene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.5);
sun.position.set(3, -2, 6);
scene.add(sun);
const grid = new THREE.GridHelper(6, 12, 0xbbbbbb, 0xdddddd);
grid.rotation.x = Math.PI / 2;
scene.add(grid);

const world = new THREE.Group();
scene.add(world);

function resize() {
  const w = host.clientWidth || 800;
  const h = host.clientHeight || 500;
  renderer.setSize(w, h, false);
  renderer.domElement.style.width = `${w}px`;
  renderer.domElement.style.height = `${h}px`;
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
}
window.addEventListener("resize", resize);

// Force colours: blue (pull) .. grey (0) .. red (push), scaled to the result's working range
// (`forceScale`: the 98th percentile of |F|); beyond it, the end colours.
function forceColour(f, limit) {
  if (!Number.isFinite(f)) return new THREE.Color(0x888888);
  const m = limit || 1;
  const x = Math.max(-1, Math.min(1, f / m));
  return x >= 0 ? new THREE.Color(0.55 + 0.45 * x, 0.55 - 0.4 * x, 0.55 - 0.4 * x) : new THREE.Color(0.55 + 0.4 * x, 0.55 + 0.1 * x, 0.55 - 0.45 * x);
}

const parts = {};

function build(result) {
  world.clear();
  const s = result.stand;
  const scale = Math.max(...s.B.map((b) => Math.hypot(b[0], b[1])));
  const jointRadius = 0.035 * scale;
  const base = new THREE.Mesh(new THREE.CylinderGeometry(1.1 * scale, 1.1 * scale, 0.04 * scale, 48),
    new THREE.MeshStandardMaterial({ color: 0x9aa5b1 }));
  base.rotation.x = Math.PI / 2;
  base.position.z = -0.02 * scale;
  world.add(base);
  const joint = () => {
    const j = new THREE.Mesh(new THREE.SphereGeometry(jointRadius, 16, 12), new THREE.MeshStandardMaterial({ color: JOINT_COLOUR }));
    world.add(j);
    return j;
  };
  parts.baseJoints = s.B.map((b) => {
    const j = joint();
    j.position.set(...b);
    return j;
  });
  // Each leg is two bodies (docs/model.md §8): the cylinder hinged at B_k, coloured by the
  // leg's force, and the thinner steel rod hinged at A_k, sliding in it.
  const tube = (radius, colour) => {
    const mesh = new THREE.Mesh(new THREE.CylinderGeometry(radius, radius, 1, 16), new THREE.MeshStandardMaterial({ color: colour }));
    world.add(mesh);
    return mesh;
  };
  parts.cylinders = s.B.map(() => tube(0.04 * scale, 0x888888));
  parts.rods = s.B.map(() => tube(0.02 * scale, 0xc8ccd0));
  parts.joints = s.A.map(() => joint());
  // The platform plate through the six platform joints (a fan of triangles about their centre).
  parts.plate = new THREE.Mesh(new THREE.BufferGeometry(), new THREE.MeshStandardMaterial({ color: 0x3e7cb1, side: THREE.DoubleSide, transparent: true, opacity: 0.75 }));
  parts.plate.geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(6 * 9), 3));
  world.add(parts.plate);
  parts.axes = new THREE.AxesHelper(0.5 * scale);
  parts.axes.matrixAutoUpdate = false;
  world.add(parts.axes);
  const trailPositions = new Float32Array(result.rows * 3);
  for (let i = 0; i < result.rows; i++) {
    const { r } = result.pose(i);
    trailPositions.set(r, 3 * i);
  }
  const trail = new THREE.BufferGeometry();
  trail.setAttribute("position", new THREE.BufferAttribute(trailPositions, 3));
  parts.trail = new THREE.Line(trail, new THREE.LineBasicMaterial({ color: 0xe67e22 }));
  world.add(parts.trail);
  legend(result);
}

function legend(result) {
  const el = $("legend");
  if (!result.colour) {
    el.textContent = "leg forces: not in the file (legs grey)";
    return;
  }
  const { what, unit, low, high } = result.colour;
  const { limit, peak, clipped } = result.forceScale;
  const c = document.createElement("canvas");
  c.width = 160;
  c.height = 12;
  const g = c.getContext("2d");
  for (let x = 0; x < c.width; x++) {
    g.fillStyle = `#${forceColour(-limit + (2 * limit * x) / (c.width - 1), limit).getHexString()}`;
    g.fillRect(x, 0, 1, c.height);
  }
  const scale = document.createElement("div");
  scale.id = "force-scale";
  scale.textContent = clipped
    ? `${low} \u2264 ${(-limit).toPrecision(3)} .. 0 .. \u2265 ${limit.toPrecision(3)} ${high}`
    : `${low} ${(-limit).toPrecision(3)} .. 0 .. ${limit.toPrecision(3)} ${high}`;
  const note = document.createElement("div");
  note.id = "force-clipped";
  note.textContent = clipped
    ? `clipped at the 98th percentile of its magnitude: peaks up to ${peak.toPrecision(3)} ${unit} take the end colours (legs beyond it named below the plots)`
    : `the scale spans every value in the file`;
  el.replaceChildren(`cylinder colour: ${what} (${unit})`, c, scale, note, "a glowing cylinder is at an end stop, a red joint at its angle limit");
}

const yUp = new THREE.Vector3(0, 1, 0);
const JOINT_COLOUR = 0x323f4b;
const LIMIT_COLOUR = 0xd0021b;

// A unit cylinder mesh stretched between two points.
function stretch(mesh, from, to) {
  const a = new THREE.Vector3(...from);
  const dir = new THREE.Vector3(...to).sub(a);
  mesh.position.copy(a).addScaledVector(dir, 0.5);
  mesh.scale.set(1, dir.length(), 1);
  mesh.quaternion.setFromUnitVectors(yUp, dir.clone().normalize());
}

function highlight(mesh, atLimit) {
  mesh.material.color.setHex(atLimit ? LIMIT_COLOUR : JOINT_COLOUR);
  mesh.material.emissive.setHex(atLimit ? 0x700010 : 0x000000);
  mesh.scale.setScalar(atLimit ? 1.5 : 1);
}

function place(i) {
  const result = state.result;
  const ends = result.legEndpoints(i);
  const bodies = result.legBodies(i);
  const limits = result.jointsAtLimit(i);
  const { r, R } = result.pose(i);
  ends.forEach(([, a], k) => {
    const cylinder = parts.cylinders[k];
    stretch(cylinder, ...bodies[k].cylinder);
    stretch(parts.rods[k], ...bodies[k].rod);
    const atStop = result.stopForce(k, i) !== 0;
    cylinder.material.color = forceColour(result.colourValue(k, i), result.forceScale && result.forceScale.limit);
    cylinder.material.emissive = new THREE.Color(atStop ? 0x8a6d00 : 0x000000);
    parts.joints[k].position.set(...a);
    highlight(parts.baseJoints[k], limits.base[k]);
    highlight(parts.joints[k], limits.platform[k]);
  });
  const positions = parts.plate.geometry.attributes.position;
  const centre = ends.reduce((c, [, a]) => c.map((x, j) => x + a[j] / 6), [0, 0, 0]);
  for (let k = 0; k < 6; k++) {
    const a = ends[k][1];
    const b = ends[(k + 1) % 6][1];
    positions.array.set([...centre, ...a, ...b], 9 * k);
  }
  positions.needsUpdate = true;
  parts.plate.geometry.computeVertexNormals();
  parts.axes.matrix.set(R[0][0], R[0][1], R[0][2], r[0], R[1][0], R[1][1], R[1][2], r[1], R[2][0], R[2][1], R[2][2], r[2], 0, 0, 0, 1);
  parts.trail.geometry.setDrawRange(0, i + 1);
  $("clock").textContent = `t = ${result.time[i].toFixed(3)}`;
  const stops = ends.map((_, k) => result.stopForce(k, i)).filter((f) => f !== 0).length;
  const atLimit = (list, what) => list.map((x, k) => (x ? `${what} ${k + 1}` : null)).filter(Boolean);
  const joints = [...atLimit(limits.base, "base"), ...atLimit(limits.platform, "platform")];
  const s = result.stand;
  const legs = s.cylinderMass || s.rodMass ? `legs of ${s.cylinderMass || 0} kg + ${s.rodMass || 0} kg` : "massless legs";
  const limit = result.forceScale ? result.forceScale.limit : Infinity;
  const beyond = ends.map((_, k) => (Math.abs(result.colourValue(k, i)) > limit ? `${k + 1}` : null)).filter(Boolean);
  const clippedText = beyond.length ? `; legs beyond the colour scale: ${beyond.join(", ")}` : "";
  $("info").textContent = `row ${i + 1} of ${result.rows}; legs at an end stop: ${stops}; joints at their angle limit: ${joints.length ? joints.join(", ") : "none"}${clippedText}; ${legs}; stand: ${s.source || "from file"}`;
  drawPlots(i);
}

// ----- plots -------------------------------------------------------------------------------

const PLOT_COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b"];
// Each plot: its series' names (the key under it) and the smallest vertical span it shows, in
// the file's units (m or rad; deg for the joints), so that round-off stays a flat line.
const PLOTS = {
  "plot-heave": { key: ["r[3]"], minSpan: 1e-3 },
  "plot-angles": { key: ["roll", "pitch", "yaw"], minSpan: 1e-3 },
  "plot-legs": { key: ["1", "2", "3", "4", "5", "6"], minSpan: 1e-3 },
  "plot-joints": { key: ["thetaB (largest)", "thetaA (largest)", "base limit", "platform limit"], minSpan: 0.1 },
  "plot-pressures": { key: ["1", "2", "3", "4", "5", "6"], minSpan: 1e-3 },
  "plot-valves": { key: ["1", "2", "3", "4", "5", "6"], minSpan: 1e-3 },
  "plot-supply": { key: ["supply pressure, MPa", "accumulator oil, L"], minSpan: 1e-3 },
  // Pairs: the vehicle solid, the simulator dashed, in one colour per axis.
  "plot-force-cues": { key: ["vehicle x", "simulator x", "vehicle y", "simulator y", "vehicle z - g", "simulator z - g"], minSpan: 1e-3, pairs: true },
  "plot-rate-cues": { key: ["vehicle x", "simulator x", "vehicle y", "simulator y", "vehicle z", "simulator z"], minSpan: 1e-4, pairs: true },
};
// The colour of series j of a plot (pairs share the colour of their axis).
const seriesColour = (plot, j) => PLOT_COLOURS[(plot.pairs ? j >> 1 : j) % PLOT_COLOURS.length];
let plotSeries = null;
const plotLayout = {};

function preparePlots(result) {
  const n = result.rows;
  const stride = Math.max(1, Math.floor(n / 600));
  const idx = [];
  for (let i = 0; i < n; i += stride) idx.push(i);
  const times = idx.map((i) => result.time[i]);
  // The time axis spans the whole run (the plotted rows are every stride-th).
  const t0 = result.time[0];
  const t1 = result.time[n - 1] > t0 ? result.time[n - 1] : t0 + 1;
  const heave = [idx.map((i) => result.pose(i).r[2])];
  const angles = [0, 1, 2].map((a) => idx.map((i) => result.angles(i)[a]));
  const legs = [0, 1, 2, 3, 4, 5].map((k) => idx.map((i) => result.legLengths(i)[k]));
  const deg = 180 / Math.PI;
  const largest = (side) => idx.map((i) => deg * Math.max(...result.jointAngles(i)[side]));
  const s = result.stand;
  const limit = (value) => (s.joints !== false && Number.isFinite(value) ? [idx.map(() => deg * value)] : []);
  const joints = result.jointAngles(0) ? [largest("base"), largest("platform"), ...limit(s.baseMaxAngle), ...limit(s.platformMaxAngle)] : null;
  const pressures = result.loadPressures ? result.loadPressures.map((s) => idx.map((i) => s[i])) : null;
  const valves = result.spools ? result.spools.map((s) => idx.map((i) => s[i])) : null;
  const sampled = (all) => (all ? all.map((s) => idx.map((i) => s[i])) : null);
  plotSeries = { times, "plot-heave": heave, "plot-angles": angles, "plot-legs": legs, "plot-joints": joints,
    "plot-pressures": pressures, "plot-valves": valves, "plot-supply": sampled(result.supply),
    "plot-force-cues": sampled(result.forceCues),
    "plot-rate-cues": sampled(result.rateCues) };
  for (const [id, plot] of Object.entries(PLOTS)) {
    const series = plotSeries[id];
    // The plots of what not every result has (hydraulics, motion cueing) show only when it does.
    const box = document.getElementById(`box-${id}`);
    if (box) box.hidden = !series;
    const key = $(`key-${id}`);
    key.replaceChildren();
    (series ? plot.key.slice(0, series.length) : []).forEach((name, j) => {
      const item = document.createElement("span");
      item.className = "key-item";
      item.style.color = seriesColour(plot, j);
      item.textContent = `${plot.pairs && j % 2 ? "\u2504" : "\u2014"} ${name}`;
      key.append(item);
    });
    const [lo, hi] = series ? plotRange(series, plot.minSpan) : [0, 1];
    plotLayout[id] = { lo, hi, t0, t1, ticks: niceTicks(t0, t1), key: [...key.children].map((e) => e.textContent.slice(2)) };
  }
}

const MARGIN = { left: 52, right: 6, top: 6, bottom: 18 };

function drawPlot(id, t) {
  const c = $(id);
  const g = c.getContext("2d");
  const series = plotSeries[id];
  const { times } = plotSeries;
  g.clearRect(0, 0, c.width, c.height);
  g.font = "10px system-ui, sans-serif";
  if (!series) {
    g.fillStyle = "#555";
    g.fillText("not in the file", 4, 14);
    return;
  }
  const { lo, hi, t0, t1, ticks } = plotLayout[id];
  const w = c.width - MARGIN.left - MARGIN.right;
  const h = c.height - MARGIN.top - MARGIN.bottom;
  const x = (tt) => MARGIN.left + (w * (tt - t0)) / (t1 - t0);
  const y = (v) => MARGIN.top + h - (h * (v - lo)) / (hi - lo);
  // Axes: the value range on the left, the time axis with its ticks below.
  g.strokeStyle = "#999";
  g.strokeRect(MARGIN.left, MARGIN.top, w, h);
  g.fillStyle = "#444";
  g.textAlign = "right";
  g.fillText(hi.toPrecision(4), MARGIN.left - 3, MARGIN.top + 8);
  g.fillText(lo.toPrecision(4), MARGIN.left - 3, MARGIN.top + h);
  g.textAlign = "center";
  for (const tick of ticks) {
    g.beginPath();
    g.moveTo(x(tick), MARGIN.top + h);
    g.lineTo(x(tick), MARGIN.top + h + 3);
    g.stroke();
    g.fillText(`${+tick.toPrecision(6)}`, x(tick), c.height - 4);
  }
  g.textAlign = "right";
  g.fillText("t, s", MARGIN.left - 3, c.height - 4);
  g.textAlign = "left";
  g.save();
  g.beginPath();
  g.rect(MARGIN.left, MARGIN.top, w, h);
  g.clip();
  series.forEach((s, j) => {
    g.strokeStyle = seriesColour(PLOTS[id], j);
    g.setLineDash(PLOTS[id].pairs && j % 2 ? [4, 3] : []);
    g.beginPath();
    s.forEach((v, i) => (i ? g.lineTo(x(times[i]), y(v)) : g.moveTo(x(times[i]), y(v))));
    g.stroke();
  });
  g.setLineDash([]);
  g.strokeStyle = "#000";
  g.beginPath();
  g.moveTo(x(t), MARGIN.top);
  g.lineTo(x(t), MARGIN.top + h);
  g.stroke();
  g.restore();
}

function drawPlots(i) {
  const t = state.result.time[i];
  for (const id of Object.keys(PLOTS)) drawPlot(id, t);
}

// ----- loading -----------------------------------------------------------------------------

function showError(message) {
  state.error = message;
  $("message").textContent = message;
}

function load(csvText, stand) {
  try {
    const result = new Result(parseCsv(csvText), stand ? checkStand(stand) : defaultStand());
    state.result = result;
    state.error = null;
    state.notice = result.notice;
    $("message").textContent = result.notice || "";
    $("slider").max = String(result.rows - 1);
    build(result);
    preparePlots(result);
    seekIndex(0);
    fitCamera(result);
  } catch (e) {
    showError(e.message);
  }
  state.ready = true;
}

function fitCamera(result) {
  const scale = Math.max(...result.stand.B.map((b) => Math.hypot(b[0], b[1])));
  const z = result.pose(0).r[2];
  controls.target.set(0, 0, 0.6 * z);
  camera.position.set(3 * scale, -3 * scale, 1.4 * z + 1.5 * scale);
  camera.near = 0.01 * scale;
  camera.far = 100 * scale;
  camera.updateProjectionMatrix();
  controls.update();
}

function seekIndex(i) {
  if (!state.result) return;
  state.index = Math.max(0, Math.min(state.result.rows - 1, i));
  state.time = state.result.time[state.index];
  $("slider").value = String(state.index);
  place(state.index);
}

// A file's path (as written in data/index.json or ?data=) as a URL: each segment encoded, so
// that names with spaces, '#', '?' or '%' load; full URLs are taken as they are.
function fileUrl(path) {
  if (/^[a-z][a-z0-9+.-]*:/i.test(path)) return path;
  return path.split("/").map(encodeURIComponent).join("/");
}

async function fetchText(path) {
  const response = await fetch(fileUrl(path));
  if (!response.ok) throw new Error(`${path}: HTTP ${response.status}`);
  return response.text();
}

async function loadUrls(dataUrl, standUrl) {
  try {
    const [csv, stand] = await Promise.all([fetchText(dataUrl), standUrl ? fetchText(standUrl).then(JSON.parse) : null]);
    load(csv, stand);
  } catch (e) {
    showError(e.message);
    state.ready = true;
  }
}

async function loadFiles(files) {
  const list = [...files];
  const csv = list.find((f) => f.name.toLowerCase().endsWith(".csv"));
  const json = list.find((f) => f.name.toLowerCase().endsWith(".json"));
  if (!csv) {
    showError("no CSV among the files: give a result CSV (and optionally its stand JSON)");
    return;
  }
  try {
    load(await csv.text(), json ? JSON.parse(await json.text()) : null);
  } catch (e) {
    showError(e.message);
  }
}

// ----- controls ----------------------------------------------------------------------------

$("slider").addEventListener("input", (e) => seekIndex(Number(e.target.value)));
$("play").addEventListener("click", () => {
  state.playing = !state.playing;
  $("play").textContent = state.playing ? "pause" : "play";
});
$("speed").addEventListener("change", (e) => (state.speed = Number(e.target.value)));
$("files").addEventListener("change", (e) => loadFiles(e.target.files));
host.addEventListener("dragover", (e) => {
  e.preventDefault();
  $("drop").classList.add("active");
});
host.addEventListener("dragleave", () => $("drop").classList.remove("active"));
host.addEventListener("drop", (e) => {
  e.preventDefault();
  $("drop").classList.remove("active");
  loadFiles(e.dataTransfer.files);
});
$("datasets").addEventListener("change", (e) => {
  const d = JSON.parse(e.target.value);
  loadUrls(d.data, d.stand);
});

let last = performance.now();
function frame(now) {
  const dt = (now - last) / 1000;
  last = now;
  if (state.playing && state.result) {
    const t = state.time + dt * state.speed;
    const end = state.result.time[state.result.rows - 1];
    const i = state.result.indexAt(t > end ? state.result.time[0] : t);
    state.time = t > end ? state.result.time[0] : t;
    if (i !== state.index) {
      state.index = i;
      $("slider").value = String(i);
      place(i);
    }
  }
  controls.update();
  renderer.render(scene, camera);
  requestAnimationFrame(frame);
}

// ----- start -------------------------------------------------------------------------------

window.stewartViewer = {
  isReady: () => state.ready,
  error: () => state.error,
  load: (csvText, stand) => load(csvText, stand || null),
  seek: (t) => seekIndex(state.result ? state.result.indexAt(t) : 0),
  time: () => state.time,
  rows: () => (state.result ? state.result.rows : 0),
  legEndpoints: () => (state.result ? state.result.legEndpoints(state.index) : null),
  legBodies: () => (state.result ? state.result.legBodies(state.index) : null),
  jointsAtLimit: () => (state.result ? state.result.jointsAtLimit(state.index) : null),
  // What the scene shows: the joints drawn in the limit colour.
  highlightedJoints: () => (parts.joints ? {
    base: parts.baseJoints.map((j) => j.material.color.getHex() === LIMIT_COLOUR),
    platform: parts.joints.map((j) => j.material.color.getHex() === LIMIT_COLOUR),
  } : null),
  pose: () => (state.result ? state.result.pose(state.index) : null),
  // The message line (an error, or a notice such as rows cut at a NaN pose).
  message: () => $("message").textContent,
  forceScale: () => (state.result ? state.result.forceScale : null),
  legend: () => ({ scale: $("force-scale")?.textContent ?? null, clipped: $("force-clipped")?.textContent ?? null }),
  info: () => $("info").textContent,
  // Each plot's vertical range, time ticks and key, as drawn.
  plots: () => plotLayout,
  datasets: () => [...$("datasets").options].map((o) => ({ ...JSON.parse(o.value), selected: o.selected })),
};

resize();
requestAnimationFrame(frame);
const query = new URLSearchParams(window.location.search);
// The dataset menu lists data/index.json whatever the address names; a result named by
// `?data=` is selected (and added when the list does not have it).
fetch("data/index.json")
  .then((r) => (r.ok ? r.json() : []))
  .catch(() => [])
  .then((datasets) => {
    const select = $("datasets");
    const wanted = query.get("data");
    const list = Array.isArray(datasets) ? datasets.filter((d) => d && typeof d.data === "string") : [];
    if (wanted && !list.some((d) => d.data === wanted)) list.unshift({ title: `${wanted} (from the address)`, data: wanted, stand: query.get("stand") });
    for (const d of list) {
      const option = document.createElement("option");
      option.value = JSON.stringify(d);
      option.textContent = d.title || d.data;
      option.selected = d.data === wanted;
      select.append(option);
    }
    if (wanted) loadUrls(wanted, query.get("stand"));
    else if (list.length) loadUrls(list[0].data, list[0].stand);
    else {
      showError("no result loaded: open or drop a result CSV (and its stand JSON), or pass ?data=...&stand=...");
      state.ready = true;
    }
  });
