// A platform result and its stand, as plain numbers: parsing, checks and the geometry the
// scene draws (no three.js here). Conventions as in docs/model.md §1: R is body -> inertial,
// column b is e_b; the platform joint k is at a_k = r + R A_k; R = Rx(roll) Ry(pitch) Rz(yaw).

import DEFAULT_STAND from "./default_stand.json" with { type: "json" };

const LEGS = [1, 2, 3, 4, 5, 6];
const ROTATION = [1, 2, 3].flatMap((a) => [1, 2, 3].map((b) => `R[${a},${b}]`));
const ANGLES = ["angles[1]", "angles[2]", "angles[3]"];

/**
 * The default stand of docs/model.md §3 (SI), drawn when no stand file is given: the platform
 * FMU's start values of B, A, lmin and lmax, written from its model description into
 * default_stand.json (tests/python/test_viewer.py holds the two equal and rewrites the file).
 */
export function defaultStand() {
  return { ...structuredClone(DEFAULT_STAND), units: "m", source: "default stand (docs/model.md §3)" };
}

/**
 * Checks a stand object ({B: 6x3, A: 6x3, optional lmin, lmax, the legs' cylinderCoM, rodCoM,
 * cylinderMass, rodMass, and the joint limits joints, baseMaxAngle, platformMaxAngle in rad});
 * returns it or throws naming the bad field.
 */
export function checkStand(stand) {
  const matrix = (m, name) => {
    if (!Array.isArray(m) || m.length !== 6 || m.some((row) => !Array.isArray(row) || row.length !== 3 || row.some((x) => !Number.isFinite(x)))) {
      throw new Error(`the stand file's ${name} must be 6 rows of 3 finite numbers`);
    }
  };
  matrix(stand.B, "B");
  matrix(stand.A, "A");
  for (const name of ["cylinderCoM", "rodCoM", "cylinderMass", "rodMass", "baseMaxAngle", "platformMaxAngle", "bore", "rod"]) {
    if (name in stand && !(Number.isFinite(stand[name]) && stand[name] >= 0)) {
      throw new Error(`the stand file's ${name} must be a number >= 0 (got ${JSON.stringify(stand[name])})`);
    }
  }
  return stand;
}

/**
 * The drawn lengths of a leg's cylinder and rod: uniform bodies, twice the distance of each
 * body's centre of mass from its joint (docs/model.md §8's d_c, d_r; 0.5 m by default), both
 * lengthened in proportion where needed so that the rod still reaches 5 % into the barrel at
 * the longest leg (a drawing, not part of the model).
 */
export function legBodyLengths(stand) {
  const cylinder = 2 * (stand.cylinderCoM ?? 0.5);
  const rod = 2 * (stand.rodCoM ?? 0.5);
  const longest = Math.max(...(stand.lmax || []), 0);
  const scale = Math.max(1, (1.05 * longest) / (cylinder + rod || 1));
  return { cylinder: cylinder * scale, rod: rod * scale };
}

/** Parses a result CSV (FMPy's write_csv: quoted names; or plain names). */
export function parseCsv(text) {
  const lines = text.split(/\r?\n/).filter((l) => l.trim().length > 0);
  if (lines.length < 2) throw new Error("not a platform result: the file has no data rows");
  // Names may be quoted and contain commas (FMPy writes "R[1,1]").
  const names = [...lines[0].matchAll(/\s*(?:"([^"]*)"|([^,]*))\s*(?:,|$)/g)]
    .filter((m) => m.index < lines[0].length)
    .map((m) => (m[1] !== undefined ? m[1] : m[2]).trim());
  const columns = {};
  names.forEach((n) => (columns[n] = new Float64Array(lines.length - 1)));
  for (let i = 1; i < lines.length; i++) {
    const cells = lines[i].split(",");
    for (let j = 0; j < names.length; j++) {
      const v = cells[j] === undefined ? NaN : cells[j].trim() === "True" ? 1 : cells[j].trim() === "False" ? 0 : Number(cells[j]);
      columns[names[j]][i - 1] = v;
    }
  }
  return { names, columns, rows: lines.length - 1 };
}

/** Checks that a parsed CSV is a platform result; throws naming every missing column. */
export function checkResult(csv) {
  const has = (n) => n in csv.columns;
  const missing = ["time", "r[1]", "r[2]", "r[3]"].filter((n) => !has(n));
  const hasRotation = ROTATION.every(has);
  const hasAngles = ANGLES.every(has);
  if (!hasRotation && !hasAngles) missing.push(...ROTATION.filter((n) => !has(n)));
  if (missing.length) {
    throw new Error(`not a platform result: missing columns ${missing.join(", ")}${!hasRotation && !hasAngles ? " (or angles[1..3])" : ""}`);
  }
  return csv;
}

/** Rotation matrix (rows) from 1-2-3 angles: Rx(roll) Ry(pitch) Rz(yaw). */
export function rotationFromAngles(roll, pitch, yaw) {
  const [c1, s1, c2, s2, c3, s3] = [Math.cos(roll), Math.sin(roll), Math.cos(pitch), Math.sin(pitch), Math.cos(yaw), Math.sin(yaw)];
  return [
    [c2 * c3, -c2 * s3, s2],
    [c1 * s3 + s1 * s2 * c3, c1 * c3 - s1 * s2 * s3, -s1 * c2],
    [s1 * s3 - c1 * s2 * c3, s1 * c3 + c1 * s2 * s3, c1 * c2],
  ];
}

/**
 * The vertical range of a small plot: the data's range, widened about its middle to at least
 * `minSpan`, so that round-off (1e-16 rad) stays a flat line instead of filling the plot.
 * Returns [lo, hi].
 */
export function plotRange(series, minSpan) {
  let lo = Infinity;
  let hi = -Infinity;
  for (const s of series) {
    for (const v of s) {
      if (Number.isFinite(v)) {
        lo = Math.min(lo, v);
        hi = Math.max(hi, v);
      }
    }
  }
  if (!(lo <= hi)) return [0, 1];
  const span = Math.max(hi - lo, minSpan, 1e-12 * Math.max(Math.abs(lo), Math.abs(hi)));
  const middle = 0.5 * (lo + hi);
  return [middle - 0.5 * span, middle + 0.5 * span];
}

/** About `n` round tick values covering [t0, t1]. */
export function niceTicks(t0, t1, n = 5) {
  const span = t1 - t0;
  if (!(span > 0)) return [t0];
  const raw = span / n;
  const magnitude = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * magnitude).find((s) => s >= raw);
  const ticks = [];
  for (let t = Math.ceil(t0 / step) * step; t <= t1 + 1e-9 * span; t += step) ticks.push(Math.abs(t) < 1e-12 * span ? 0 : t);
  return ticks;
}

/** The q-quantile (0..1) of finite values, by linear interpolation between order statistics. */
export function quantile(values, q) {
  const v = values.filter(Number.isFinite).sort((a, b) => a - b);
  if (!v.length) return NaN;
  const x = q * (v.length - 1);
  const i = Math.floor(x);
  return i + 1 < v.length ? v[i] + (x - i) * (v[i + 1] - v[i]) : v[i];
}

/** A result ready to play: times, poses, forces, and the stand. */
export class Result {
  constructor(csv, stand) {
    this.csv = checkResult(csv);
    this.stand = checkStand(stand);
    this.time = csv.columns["time"];
    this.rows = csv.rows;
    this.hasRotation = ROTATION.every((n) => n in csv.columns);
    const col = (n) => csv.columns[n];
    this.forces = LEGS.every((k) => `F[${k}]` in csv.columns) ? LEGS.map((k) => col(`F[${k}]`)) : null;
    this.stopForces = LEGS.every((k) => `Fstop[${k}]` in csv.columns) ? LEGS.map((k) => col(`Fstop[${k}]`)) : null;
    this.thetaB = LEGS.every((k) => `thetaB[${k}]` in csv.columns) ? LEGS.map((k) => col(`thetaB[${k}]`)) : null;
    this.thetaA = LEGS.every((k) => `thetaA[${k}]` in csv.columns) ? LEGS.map((k) => col(`thetaA[${k}]`)) : null;
    // Hydraulic legs (docs/model.md §10): the chamber pressures give each leg's load pressure
    // p_L = pA - (A_B/A_A) pB (MPa), which colours the cylinders; the spools feed a plot.
    const all = (name) => LEGS.every((k) => `${name}[${k}]` in csv.columns);
    const bore = stand.bore ?? 0.063;
    const rod = stand.rod ?? 0.036;
    this.areaRatio = (bore * bore - rod * rod) / (bore * bore);
    this.loadPressures = all("pA") && all("pB")
      ? LEGS.map((k) => Float64Array.from(col(`pA[${k}]`), (pa, i) => (pa - this.areaRatio * col(`pB[${k}]`)[i]) / 1e6))
      : null;
    this.spools = all("spool") ? LEGS.map((k) => col(`spool[${k}]`)) : null;
    // The power unit (§10b): the supply pressure (MPa) and the accumulator's oil (L).
    this.supply = "supply.pressure" in csv.columns && "accumulator.oilVolume" in csv.columns
      ? [Float64Array.from(col("supply.pressure"), (p) => p / 1e6), Float64Array.from(col("accumulator.oilVolume"), (v) => v * 1e3)]
      : null;
    // Motion cueing (docs/cueing.md): the vehicle's and the simulator's specific force (gravity's
    // g taken off the vertical) and angular velocity, pair by pair (x, y, z).
    const all3 = (name) => [1, 2, 3].every((k) => `${name}[${k}]` in csv.columns);
    const g = stand.g ?? 9.81;
    const pairs = (vehicle, simulator, offsets) => [0, 1, 2].flatMap((j) => [vehicle, simulator].map(
      (name) => Float64Array.from(col(`${name}[${j + 1}]`), (v) => v - offsets[j])));
    this.forceCues = all3("f") && all3("fsim") ? pairs("f", "fsim", [0, 0, g]) : null;
    this.rateCues = all3("omega") && all3("omegasim") ? pairs("omega", "omegasim", [0, 0, 0]) : null;
    // What colours the cylinders: the load pressure with hydraulic legs, else the leg force.
    this.colour = this.loadPressures
      ? { what: "load pressure pA - (A_B/A_A) pB", unit: "MPa", low: "pull", high: "push", series: this.loadPressures }
      : this.forces ? { what: "leg force F", unit: "N", low: "pull", high: "push", series: this.forces } : null;
    this.bodyLengths = legBodyLengths(this.stand);
    // Rows from the first whose pose is not a number (a failed run) are left out, with a message.
    this.notice = null;
    const poseColumns = ["r[1]", "r[2]", "r[3]", ...(this.hasRotation ? ROTATION : ANGLES)];
    for (let i = 0; i < csv.rows; i++) {
      const bad = poseColumns.find((n) => !Number.isFinite(csv.columns[n][i]));
      if (bad) {
        const where = `column ${bad}, row ${i + 1} of ${csv.rows} (t = ${this.time[i]})`;
        if (i === 0) throw new Error(`the pose is not a number (NaN) from the first row: ${where}`);
        this.rows = i;
        this.notice = `the pose is not a number (NaN) from ${where}: showing the ${i} rows before it`;
        break;
      }
    }
    this.forceScale = this.colour ? forceScale(this.colour.series, this.rows) : null;
  }

  /** Index of the last row at or before time t (rows are not interpolated). */
  indexAt(t) {
    let lo = 0;
    let hi = this.rows - 1;
    if (t <= this.time[0]) return 0;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (this.time[mid] <= t) lo = mid;
      else hi = mid - 1;
    }
    return lo;
  }

  pose(i) {
    const c = this.csv.columns;
    const r = [c["r[1]"][i], c["r[2]"][i], c["r[3]"][i]];
    const R = this.hasRotation
      ? [1, 2, 3].map((a) => [1, 2, 3].map((b) => c[`R[${a},${b}]`][i]))
      : rotationFromAngles(c["angles[1]"][i], c["angles[2]"][i], c["angles[3]"][i]);
    return { r, R };
  }

  /** The twelve leg end points at row i: [B_k, a_k] for k = 1..6, metres (or the file's units). */
  legEndpoints(i) {
    const { r, R } = this.pose(i);
    return this.stand.A.map((A, k) => {
      const a = [0, 1, 2].map((row) => r[row] + R[row][0] * A[0] + R[row][1] * A[1] + R[row][2] * A[2]);
      return [this.stand.B[k].slice(), a];
    });
  }

  /**
   * The leg bodies at row i: for each leg the cylinder [B_k, B_k + L_c n_k] and the rod
   * [a_k - L_r n_k, a_k] (`legBodyLengths`), each as [from, to].
   */
  legBodies(i) {
    const { cylinder, rod } = this.bodyLengths;
    return this.legEndpoints(i).map(([b, a]) => {
      const d = [0, 1, 2].map((j) => a[j] - b[j]);
      const l = Math.hypot(...d) || 1;
      const n = d.map((x) => x / l);
      return { cylinder: [b, b.map((x, j) => x + cylinder * n[j])], rod: [a.map((x, j) => x - rod * n[j]), a] };
    });
  }

  /** Joint angles at row i, rad: {base: thetaB[1..6], platform: thetaA[1..6]}, or null. */
  jointAngles(i) {
    if (!this.thetaB || !this.thetaA) return null;
    return { base: this.thetaB.map((c) => c[i]), platform: this.thetaA.map((c) => c[i]) };
  }

  /**
   * Which joints are beyond their angle limit at row i (in contact: theta > thetaMax), from the
   * result's joint angles and the stand's limits: {base: [6 booleans], platform: [6 booleans]},
   * all false when the stand has the limits off or the file has no joint angles.
   */
  jointsAtLimit(i) {
    const angles = this.jointAngles(i);
    const s = this.stand;
    const on = angles && s.joints !== false && Number.isFinite(s.baseMaxAngle) && Number.isFinite(s.platformMaxAngle);
    return {
      base: LEGS.map((_, k) => Boolean(on && angles.base[k] > s.baseMaxAngle)),
      platform: LEGS.map((_, k) => Boolean(on && angles.platform[k] > s.platformMaxAngle)),
    };
  }

  force(k, i) {
    return this.forces ? this.forces[k][i] : NaN;
  }

  /** The value that colours leg k's cylinder at row i (`colour`: load pressure or force). */
  colourValue(k, i) {
    return this.colour ? this.colour.series[k][i] : NaN;
  }

  stopForce(k, i) {
    return this.stopForces ? this.stopForces[k][i] : 0;
  }

  angles(i) {
    const c = this.csv.columns;
    if (ANGLES.every((n) => n in c)) return ANGLES.map((n) => c[n][i]);
    const { R } = this.pose(i);
    // Inverse of Rx Ry Rz: pitch from R[0][2], roll and yaw from the rest.
    return [Math.atan2(-R[1][2], R[2][2]), Math.asin(Math.max(-1, Math.min(1, R[0][2]))), Math.atan2(-R[0][1], R[0][0])];
  }

  legLengths(i) {
    const c = this.csv.columns;
    if (LEGS.every((k) => `l[${k}]` in c)) return LEGS.map((k) => c[`l[${k}]`][i]);
    return this.legEndpoints(i).map(([b, a]) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]));
  }
}

/**
 * The colour scale of the leg forces: symmetric about 0, up to the 98th percentile of |F| over
 * all legs and rows (the working range), so that an impact peak does not turn every working
 * force grey; forces beyond it are drawn at the scale's end colour and counted as clipped.
 * Returns {limit, peak, clipped}.
 */
export function forceScale(forces, rows) {
  const magnitudes = [];
  for (const series of forces) for (let i = 0; i < rows; i++) magnitudes.push(Math.abs(series[i]));
  const peak = Math.max(0, ...magnitudes.filter(Number.isFinite));
  let limit = quantile(magnitudes, 0.98);
  if (!(limit > 0)) limit = peak > 0 ? peak : 1;
  return { limit, peak, clipped: peak > limit };
}
