// The viewer: a three.js scene of the stand (base, joints glowing red at their angle limits,
// legs drawn as a cylinder coloured by force and a steel rod, platform plate and axes,
// centre-of-mass trail), playback controls and small synchronised plots. Data
// come from `?data=result.csv&stand=stand.json`, from `data/index.json` (a list the Python tools
// write), or from files the user drops or picks. `window.stewartViewer` is the test hook.

import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { Result, checkStand, defaultStand, parseCsv } from "./result.js";

const $ = (id) => document.getElementById(id);
const state = { result: null, index: 0, playing: false, speed: 1, time: 0, error: null, ready: false };

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

// Force colours: blue (pull) .. grey (0) .. red (push), scaled to the result's force range.
function forceColour(f, [lo, hi]) {
  if (!Number.isFinite(f)) return new THREE.Color(0x888888);
  const m = Math.max(Math.abs(lo), Math.abs(hi)) || 1;
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
  const [lo, hi] = result.forceRange;
  const el = $("legend");
  if (!result.forces) {
    el.innerHTML = "leg forces: not in the file (legs grey)";
    return;
  }
  const c = document.createElement("canvas");
  c.width = 160;
  c.height = 12;
  const g = c.getContext("2d");
  const m = Math.max(Math.abs(lo), Math.abs(hi));
  for (let x = 0; x < c.width; x++) {
    g.fillStyle = `#${forceColour(-m + (2 * m * x) / (c.width - 1), [lo, hi]).getHexString()}`;
    g.fillRect(x, 0, 1, c.height);
  }
  el.innerHTML = "";
  el.append("cylinder colour: leg force F (N), pull", c, `${(-m).toPrecision(3)} .. 0 .. ${m.toPrecision(3)} push; a glowing cylinder is at an end stop, a red joint at its angle limit`);
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
    cylinder.material.color = forceColour(result.force(k, i), result.forceRange);
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
  $("info").textContent = `row ${i + 1} of ${result.rows}; legs at an end stop: ${stops}; joints at their angle limit: ${joints.length ? joints.join(", ") : "none"}; ${legs}; stand: ${s.source || "from file"}`;
  drawPlots(i);
}

// ----- plots -------------------------------------------------------------------------------

const PLOT_COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b"];
let plotSeries = null;

function preparePlots(result) {
  const n = result.rows;
  const stride = Math.max(1, Math.floor(n / 600));
  const idx = [];
  for (let i = 0; i < n; i += stride) idx.push(i);
  const times = idx.map((i) => result.time[i]);
  const heave = [idx.map((i) => result.pose(i).r[2])];
  const angles = [0, 1, 2].map((a) => idx.map((i) => result.angles(i)[a]));
  const legs = [0, 1, 2, 3, 4, 5].map((k) => idx.map((i) => result.legLengths(i)[k]));
  const deg = 180 / Math.PI;
  const largest = (side) => idx.map((i) => deg * Math.max(...result.jointAngles(i)[side]));
  const s = result.stand;
  const limit = (value) => (s.joints !== false && Number.isFinite(value) ? [idx.map(() => deg * value)] : []);
  const joints = result.jointAngles(0) ? [largest("base"), largest("platform"), ...limit(s.baseMaxAngle), ...limit(s.platformMaxAngle)] : null;
  plotSeries = { times, heave, angles, legs, joints };
}

function drawPlot(id, series, t) {
  const c = $(id);
  const g = c.getContext("2d");
  const { times } = plotSeries;
  g.clearRect(0, 0, c.width, c.height);
  if (!series) {
    g.fillStyle = "#555";
    g.fillText("not in the file", 4, 14);
    return;
  }
  const all = series.flat().filter(Number.isFinite);
  let lo = Math.min(...all);
  let hi = Math.max(...all);
  if (!(hi > lo)) {
    lo -= 1e-9 + Math.abs(lo) * 1e-3;
    hi += 1e-9 + Math.abs(hi) * 1e-3;
  }
  const t0 = times[0];
  const t1 = times[times.length - 1] || t0 + 1;
  const x = (tt) => 4 + ((c.width - 8) * (tt - t0)) / (t1 - t0 || 1);
  const y = (v) => c.height - 14 - ((c.height - 20) * (v - lo)) / (hi - lo);
  series.forEach((s, j) => {
    g.strokeStyle = PLOT_COLOURS[j % PLOT_COLOURS.length];
    g.beginPath();
    s.forEach((v, i) => (i ? g.lineTo(x(times[i]), y(v)) : g.moveTo(x(times[i]), y(v))));
    g.stroke();
  });
  g.fillStyle = "#555";
  g.fillText(`${lo.toPrecision(4)} .. ${hi.toPrecision(4)}`, 4, c.height - 2);
  g.strokeStyle = "#000";
  g.beginPath();
  g.moveTo(x(t), 0);
  g.lineTo(x(t), c.height - 12);
  g.stroke();
}

function drawPlots(i) {
  const t = state.result.time[i];
  drawPlot("plot-heave", plotSeries.heave, t);
  drawPlot("plot-angles", plotSeries.angles, t);
  drawPlot("plot-legs", plotSeries.legs, t);
  drawPlot("plot-joints", plotSeries.joints, t);
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
    $("message").textContent = "";
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

async function fetchText(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
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
};

resize();
requestAnimationFrame(frame);
const query = new URLSearchParams(window.location.search);
if (query.get("data")) {
  loadUrls(query.get("data"), query.get("stand"));
} else {
  fetch("data/index.json")
    .then((r) => (r.ok ? r.json() : []))
    .catch(() => [])
    .then((datasets) => {
      const select = $("datasets");
      for (const d of datasets) {
        const option = document.createElement("option");
        option.value = JSON.stringify(d);
        option.textContent = d.title || d.data;
        select.append(option);
      }
      if (datasets.length) loadUrls(datasets[0].data, datasets[0].stand);
      else {
        showError("no result loaded: open or drop a result CSV (and its stand JSON), or pass ?data=...&stand=...");
        state.ready = true;
      }
    });
}
