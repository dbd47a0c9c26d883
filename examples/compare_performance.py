"""Performance side by side with the alternatives, in one run (issue: performance).

Same stand (docs/model.md §3), same force law for everyone: a leg-length feedback around sinusoidal
programme lengths, sampled at every 1 ms communication point and held over the step,

    u_k = 0.2005 M g + G (l_k^p(t) - l_k) - D ldot_k,   l_k^p = l_0 + 0.02 sin(2 t + k),

with G = 2e5 N/m, D = 2e4 N s/m (open-loop forces would tip the platform over within
seconds). Measured:

- the reference: an independent Newton-Euler model (unit quaternion + Euler's equations)
  integrated with scipy's DOP853 at rtol 1e-12 over each 1 ms step with the forces held;
- our FMU natively (examples/native_host.rs through dlopen): RK4 at several internal steps,
  Dormand-Prince 5(4) at several tolerances; cost per step and error at 3 s;
- our FMU and a trivial FMU (same interface, no physics; the host's floor) under
  fmpy.simulate_fmu (replaying the reference's forces) and under a minimal FMU2Slave loop;
- a MuJoCo model of the same stand (free body; legs as two light bodies with a slide joint and
  a force actuator on ball joints; upper ends closed with connect equality constraints,
  solref 0.002 1, solimp near 1), with RK4 and Euler at 1 ms. Its cost is taken two ways and
  both are printed: per `mj_step` call from Python in the closed loop (the force law computed in
  Python between calls, which is where its error comes from), and in MuJoCo's own C loop,
  `mj_step(model, data, nstep=N)` with the forces held (the fair figure next to our native
  loop; the work-precision plot uses it).

Prints one table (medians of repeated runs, ratios) and writes work_precision.png and
performance.csv to the output folder.

    python examples/compare_performance.py [output-folder]
"""

import csv
import json
import math
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
from stewart_fmu import EQUILIBRIUM_FORCE, PLATFORM_FMU, Platform, default_stand

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "output")
TRIVIAL_FMU = PLATFORM_FMU.parent / "bench" / "TrivialPlatform.fmu"
NATIVE_HOST = ROOT / "target" / "release" / "examples" / "native_host"
H = 1e-3
T_END = 3.0
STEPS = int(round(T_END / H))
# The default stand, the FMU's (its model description's start values), for every engine.
STAND = default_stand()
MASS, INERTIA, GRAVITY, NEUTRAL_Z = STAND["M"], STAND["J"], STAND["g"], STAND["r0"][2]
U0 = EQUILIBRIUM_FORCE * MASS * GRAVITY
GAIN, DAMPING = 2.0e5, 2.0e4
REPEATS = 5

B = [np.array(b) for b in STAND["B"]]
A = [np.array(a) for a in STAND["A"]]
L0 = float(np.linalg.norm(np.array([0, 0, NEUTRAL_Z]) + A[0] - B[0]))


def force_law(t, l, ldot):
    return [U0 + GAIN * (L0 + 0.02 * math.sin(2.0 * t + k) - l[k]) - DAMPING * ldot[k] for k in range(6)]


# ----- reference: Newton-Euler with scipy DOP853 -------------------------------------------

def quat_to_matrix(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def legs_ne(s):
    r, v, q, w = s[0:3], s[3:6], s[6:10], s[10:13]
    rot = quat_to_matrix(q)
    omega = rot @ w
    l, ld, n, arm = [], [], [], []
    for k in range(6):
        a = rot @ A[k]
        d = r + a - B[k]
        lk = np.linalg.norm(d)
        nk = d / lk
        l.append(lk)
        n.append(nk)
        arm.append(a)
        ld.append(nk @ (v + np.cross(omega, a)))
    return l, ld, n, arm, rot


def rhs_ne(_t, s, u):
    l, ld, n, arm, rot = legs_ne(s)
    force = np.array([0.0, 0.0, -MASS * GRAVITY])
    moment = np.zeros(3)
    for k in range(6):
        f = n[k] * u[k]
        force += f
        moment += np.cross(arm[k], f)
    q, w = s[6:10], s[10:13]
    j = np.array(INERTIA)
    w_dot = (rot.T @ moment - np.cross(w, j * w)) / j
    qw, qx, qy, qz = q
    q_dot = 0.5 * np.array([-qx * w[0] - qy * w[1] - qz * w[2], qw * w[0] + qy * w[2] - qz * w[1],
                            qw * w[1] - qx * w[2] + qz * w[0], qw * w[2] + qx * w[1] - qy * w[0]])
    return np.concatenate([s[3:6], force / MASS, q_dot, w_dot])


def reference():
    from scipy.integrate import solve_ivp
    s = np.array([0, 0, NEUTRAL_Z, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0], dtype=float)
    positions, forces = [], []
    for i in range(STEPS):
        t = i * H
        l, ld, *_ = legs_ne(s)
        u = force_law(t, l, ld)
        forces.append(u)
        sol = solve_ivp(rhs_ne, (t, t + H), s, method="DOP853", rtol=1e-12, atol=1e-14, args=(u,))
        s = sol.y[:, -1]
        s[6:10] /= np.linalg.norm(s[6:10])
        positions.append(s[0:3].copy())
    return np.array(positions), np.array(forces), quat_to_matrix(s[6:10])


# ----- our FMU natively -------------------------------------------------------------------

def native(method, fixed_step=None, rel_tol=None):
    cmd = [str(NATIVE_HOST), str(PLATFORM_FMU), method, "--t-end", str(T_END), "--json"]
    if fixed_step:
        cmd += ["--fixed-step", repr(fixed_step)]
    if rel_tol:
        cmd += ["--rel-tol", repr(rel_tol)]
    run = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
    return run["us_per_step_median"], np.array(run["r"]), run["max_rss_kib"]


# ----- FMPy loops ---------------------------------------------------------------------------

def fmpy_loop(fmu, feedback=True):
    """Minimal FMU2Slave loop: set 6 forces, doStep, get 12 leg values; the law in Python.
    Without feedback (the trivial FMU, whose outputs are not legs) the law gets the neutral
    legs: the same work per step."""
    costs = []
    final = None
    for _ in range(1):
        pl = Platform(fmu=fmu)
        legs = (pl.vector("l", 6), pl.vector("ldot", 6)) if feedback else ([L0] * 6, [0.0] * 6)
        vr_f = [pl.vr[f"F[{k}]"] for k in range(1, 7)]
        vr_l = [pl.vr[f"l[{k}]"] for k in range(1, 7)] + [pl.vr[f"ldot[{k}]"] for k in range(1, 7)]
        slave = pl.slave
        t = 0.0
        start = time.perf_counter()
        for i in range(STEPS):
            l, ld = legs
            slave.setReal(vr_f, force_law(t, l, ld))
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=H)
            t += H
            values = slave.getReal(vr_l)
            legs = (values[:6], values[6:]) if feedback else ([L0] * 6, [0.0] * 6)
        costs.append((time.perf_counter() - start) / STEPS * 1e6)
        final = pl.vector("r", 3)
        pl.free()
    return float(np.median(costs)), final


def fmpy_simulate(fmu, forces):
    from fmpy import simulate_fmu
    t = np.arange(STEPS) * H
    signals = np.array([(ti,) + tuple(f) for ti, f in zip(t, forces)],
                       dtype=[("time", float)] + [(f"F[{k}]", float) for k in range(1, 7)])
    costs = []
    for _ in range(1):
        start = time.perf_counter()
        simulate_fmu(str(fmu), stop_time=T_END - H, output_interval=H, input=signals)
        costs.append((time.perf_counter() - start) / (STEPS - 1) * 1e6)
    return float(np.median(costs))


# ----- MuJoCo -----------------------------------------------------------------------------

def quat_z_to(n):
    z = np.array([0.0, 0.0, 1.0])
    axis = np.cross(z, n)
    s = np.linalg.norm(axis)
    angle = math.atan2(s, z @ n)
    axis = axis / s if s > 0 else np.array([1.0, 0.0, 0.0])
    return np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * axis])


def mjcf(integrator, dt):
    r0 = np.array([0.0, 0.0, NEUTRAL_Z])
    legs, eqs, acts, sites = [], [], [], []
    for k in range(6):
        d = r0 + A[k] - B[k]
        q = quat_z_to(d / np.linalg.norm(d))
        legs.append(f"""
    <body name="lower{k}" pos="{B[k][0]} {B[k][1]} {B[k][2]}" quat="{q[0]} {q[1]} {q[2]} {q[3]}">
      <joint name="ball{k}" type="ball"/>
      <inertial pos="0 0 0" mass="1e-3" diaginertia="1e-6 1e-6 1e-6"/>
      <body name="upper{k}">
        <joint name="slide{k}" type="slide" axis="0 0 1"/>
        <inertial pos="0 0 {L0 / 2}" mass="1e-3" diaginertia="1e-6 1e-6 1e-6"/>
        <site name="tip{k}" pos="0 0 {L0}"/>
      </body>
    </body>""")
        sites.append(f'<site name="joint{k}" pos="{A[k][0]} {A[k][1]} {A[k][2]}"/>')
        eqs.append(f'<connect name="close{k}" body1="upper{k}" body2="platform" anchor="0 0 {L0}" '
                   f'solref="0.002 1" solimp="0.9999 0.9999 0.001 0.5 2"/>')
        acts.append(f'<motor name="u{k}" joint="slide{k}" gear="1"/>')
    return f"""<mujoco model="stewart">
  <option timestep="{dt}" integrator="{integrator}" gravity="0 0 {-GRAVITY}"/>
  <worldbody>
    <body name="platform" pos="0 0 {NEUTRAL_Z}">
      <freejoint/>
      <inertial pos="0 0 0" mass="{MASS}" diaginertia="{INERTIA[0]} {INERTIA[1]} {INERTIA[2]}"/>
      {''.join(sites)}
    </body>{''.join(legs)}
  </worldbody>
  <equality>{''.join(eqs)}</equality>
  <actuator>{''.join(acts)}</actuator>
</mujoco>"""


def platform_legs(qpos, qvel):
    """Leg lengths and rates from MuJoCo's free-body state (position, quaternion; linear
    velocity in world, angular velocity in body axes)."""
    r, rot = qpos[0:3], quat_to_matrix(np.asarray(qpos[3:7]))
    v, omega = qvel[0:3], rot @ qvel[3:6]
    l, ld = [], []
    for k in range(6):
        arm = rot @ A[k]
        d = r + arm - B[k]
        lk = float(np.linalg.norm(d))
        l.append(lk)
        ld.append(float(d @ (v + np.cross(omega, arm)) / lk))
    return l, ld


def mujoco_run(integrator, ref_positions, dt=H):
    import mujoco
    model = mujoco.MjModel.from_xml_string(mjcf(integrator, dt))
    substeps = int(round(H / dt))
    costs, path_error, gap, final = [], 0.0, 0.0, None
    for rep in range(1):
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        t, step_time, path_error, gap = 0.0, 0.0, 0.0, 0.0
        for i in range(STEPS):
            # Legs measured on the platform (pose and twist of the free body), not on the slide
            # joints: the connect constraints are soft, so the slides differ from the true
            # geometry by the constraint gap.
            l, ld = platform_legs(data.qpos, data.qvel)
            data.ctrl[:] = force_law(t, l, ld)
            start = time.perf_counter()
            for _ in range(substeps):
                mujoco.mj_step(model, data)
            step_time += time.perf_counter() - start
            t += H
            path_error = max(path_error, float(np.linalg.norm(data.qpos[0:3] - ref_positions[i])))
            if rep == 0 and i % 10 == 0:
                for k in range(6):
                    gap = max(gap, float(np.linalg.norm(data.site(f"tip{k}").xpos - data.site(f"joint{k}").xpos)))
        costs.append(step_time / STEPS * 1e6)
        final = data.qpos[0:3].copy()
    # The same model in MuJoCo's own C loop: the equilibrium forces held, STEPS steps in one call.
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    data.ctrl[:] = U0
    start = time.perf_counter()
    mujoco.mj_step(model, data, nstep=STEPS * substeps)
    c_loop = (time.perf_counter() - start) / STEPS * 1e6
    return float(np.median(costs)), final, path_error, gap, c_loop


def machine():
    cpu = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Linux {platform.release()}, Python {platform.python_version()}"


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    print(f"machine: {machine()}")
    print("reference (Newton-Euler, DOP853 rtol 1e-12, forces held over each 1 ms) ...")
    ref_positions, ref_forces, _ = reference()
    ref_final = ref_positions[-1]
    rows = []

    def add(name, cost_us, final, note=""):
        err = float(np.linalg.norm(np.asarray(final) - ref_final)) if final is not None else float("nan")
        rows.append({"name": name, "us_per_step": cost_us, "us_per_simulated_s": cost_us / H, "error_at_3s_m": err,
                     "note": note})

    # Every measurement is repeated REPEATS times, interleaved (one round of everything, then
    # the next), so that a slow moment of this shared machine hits all of them alike; the
    # table shows medians.
    jobs = []
    for fixed in (1e-3, 5e-4, 2.5e-4):
        jobs.append((f"ours, native, RK4 step {fixed * 1e3:g} ms", "ours RK4", lambda fixed=fixed: native("rk4", fixed_step=fixed)))
    for tol in (1e-4, 1e-6, 1e-8, 1e-10, 1e-12):
        jobs.append((f"ours, native, DOPRI5 relTol {tol:g}", "ours DOPRI5", lambda tol=tol: native("dopri5", rel_tol=tol)))
    for integrator in ("RK4", "Euler"):
        jobs.append((f"MuJoCo {integrator}, 1 ms, per Python call", "MuJoCo",
                     lambda integrator=integrator: mujoco_run(integrator, ref_positions)))
    jobs.append(("ours, FMU2Slave loop (default DOPRI5)", None, lambda: fmpy_loop(PLATFORM_FMU)))
    jobs.append(("trivial FMU, FMU2Slave loop", None, lambda: fmpy_loop(TRIVIAL_FMU, feedback=False)))
    jobs.append(("ours, fmpy.simulate_fmu (default DOPRI5)", None, lambda: (fmpy_simulate(PLATFORM_FMU, ref_forces), None)))
    jobs.append(("trivial FMU, fmpy.simulate_fmu", None, lambda: (fmpy_simulate(TRIVIAL_FMU, ref_forces), None)))
    results = {name: [] for name, _, _ in jobs}
    for _ in range(REPEATS):
        for name, _, job in jobs:
            results[name].append(job())
    notes = {
        "trivial FMU, FMU2Slave loop": "host floor",
        "trivial FMU, fmpy.simulate_fmu": "host floor",
        "ours, fmpy.simulate_fmu (default DOPRI5)": "replays the reference forces",
    }
    work_precision = {"ours RK4": [], "ours DOPRI5": [], "MuJoCo": []}
    for name, curve, _ in jobs:
        runs = results[name]
        cost = float(np.median([r[0] for r in runs]))
        first = runs[0]
        final = first[1] if len(first) > 1 and not name.startswith("trivial") else None
        note = notes.get(name, "")
        if name.startswith("MuJoCo"):
            note = f"path error {first[2]:.1e} m, constraint gap {first[3] * 1e3:.2f} mm"
        add(name, cost, final, note)
        if curve == "MuJoCo":
            c_loop = float(np.median([r[4] for r in runs]))
            error = rows[-1]["error_at_3s_m"]
            add(name.replace("per Python call", "C loop (nstep)"), c_loop, first[1],
                "mj_step(model, data, nstep) with the forces held; error of the closed loop above")
            work_precision[curve].append((c_loop / H, error, name.split()[1].rstrip(","), cost / H))
        elif curve:
            work_precision[curve].append((cost / H, rows[-1]["error_at_3s_m"]))
    loop_ours = rows[[r["name"] for r in rows].index("ours, FMU2Slave loop (default DOPRI5)")]["us_per_step"]
    loop_trivial = rows[[r["name"] for r in rows].index("trivial FMU, FMU2Slave loop")]["us_per_step"]
    sim_ours = rows[[r["name"] for r in rows].index("ours, fmpy.simulate_fmu (default DOPRI5)")]["us_per_step"]
    sim_trivial = rows[[r["name"] for r in rows].index("trivial FMU, fmpy.simulate_fmu")]["us_per_step"]

    mujoco_rk4 = next(r for r in rows if r["name"].startswith("MuJoCo RK4") and "C loop" in r["name"])
    mujoco_rk4_call = next(r for r in rows if r["name"].startswith("MuJoCo RK4") and "Python call" in r["name"])
    ours_rk4 = rows[0]
    print()
    print(f"{'':44} {'us/step':>10} {'us per sim. s':>14} {'error at 3 s':>13}  notes")
    for r in rows:
        print(f"{r['name']:44} {r['us_per_step']:10.3f} {r['us_per_simulated_s']:14.0f} {r['error_at_3s_m']:13.2e}  {r['note']}")
    print()
    print(f"MuJoCo RK4 / ours native RK4 (1 ms), cost per simulated second, both in C loops: "
          f"{mujoco_rk4['us_per_step'] / ours_rk4['us_per_step']:.0f}x; MuJoCo per Python call: "
          f"{mujoco_rk4_call['us_per_step'] / ours_rk4['us_per_step']:.0f}x "
          f"(error {mujoco_rk4['error_at_3s_m']:.1e} m vs {ours_rk4['error_at_3s_m']:.1e} m)")
    print(f"under FMPy, ours / trivial FMU per step: FMU2Slave loop {loop_ours / loop_trivial:.2f}x, "
          f"simulate_fmu {sim_ours / sim_trivial:.2f}x")

    with open(OUT / "performance.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 5))
    floor = 1e-16
    for name, marker in (("ours RK4", "o-"), ("ours DOPRI5", "s-")):
        pts = work_precision[name]
        ax.loglog([p[0] for p in pts], [max(p[1], floor) for p in pts], marker, label=name)
    for cost, err, integrator, per_call in work_precision["MuJoCo"]:
        line, = ax.loglog([cost], [err], "^", markersize=9, label=f"MuJoCo {integrator} (C loop)")
        ax.loglog([per_call], [err], "^", markersize=9, markerfacecolor="none", color=line.get_color(),
                  label=f"MuJoCo {integrator} (per Python call)")
    ax.set(xlabel="cost per simulated second (us)", ylabel="position error at 3 s (m)",
           title="Work-precision, 1 ms communication steps, default stand")
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(OUT / "work_precision.png", dpi=120)
    print(f"wrote {OUT / 'performance.csv'} and {OUT / 'work_precision.png'}")


if __name__ == "__main__":
    main()
