"""The whole workspace through the packaged FMUs with FMPy (issue 9): end stops and singular
leg arrangements, scenarios 1-6 of tests/python/workspace.py, each checked against an
independent statement of what must happen."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from stewart_fmu import workspace as ws
from oracles.stand import BASE_AZIMUTHS, GRAVITY, H_C, INERTIA, MASS, NEUTRAL_Z, PLATFORM_AZIMUTHS, R_B, R_P

pytestmark = pytest.mark.quick

MGRB = MASS * GRAVITY * R_B  # energy scale, J


def horizontal_leg_projection():
    pb, pp = math.radians(BASE_AZIMUTHS[0]), math.radians(PLATFORM_AZIMUTHS[0])
    return math.hypot(R_P * math.cos(pp) - R_B * math.cos(pb), R_P * math.sin(pp) - R_B * math.sin(pb))


def test_power_loss_lands_on_the_lower_stops_at_the_static_rest_pose():
    lmin, _, stiffness, _ = ws.stop_defaults()
    d = ws.power_loss()
    z_static, l_static = ws.static_rest_height(stiffness, lmin)
    # Free fall from the neutral pose until the legs are lmin long.
    d_h = horizontal_leg_projection()
    fall = math.sqrt(2.0 * ((NEUTRAL_Z - H_C) - math.sqrt(lmin**2 - d_h**2)) / GRAVITY)
    onsets = [e for e in d["events"] if e[2] == "reached" and e[3] == "lower"]
    first = min(e[0] for e in onsets)
    balance = d["E"] - d["E"][0] - (d["work.F"] - d["work.dissipated"])
    penetration = lmin - np.min([d[f"l[{k}]"] for k in ws.LEGS])
    peak = np.max(d["der(v[3])"])
    stop_forces = [d[f"Fstop[{k}]"][-1] for k in ws.LEGS]
    print(f"power loss at 0.5 s: contact at t = {first:.9f} s (free fall predicts {0.5 + fall:.9f} s), "
          f"peak deceleration {peak:.1f} m/s2 ({peak / GRAVITY:.1f} g), max penetration {penetration * 1e3:.2f} mm; "
          f"at 5 s: z = {d['r[3]'][-1]:.10f} m against the static solution {z_static:.10f} m "
          f"(difference {d['r[3]'][-1] - z_static:.1e} m), legs {d['l[1]'][-1]:.7f} m ({l_static:.7f}), "
          f"stop forces {stop_forces[0]:.1f} N each; energy balance residual {np.max(np.abs(balance)):.1e} J, "
          f"{d['work.dissipated'][-1]:.1f} J dissipated")
    assert len({e[1] for e in onsets}) == 6, "all six legs land"
    assert abs(first - (0.5 + fall)) < 1e-6
    assert abs(d["r[3]"][-1] - z_static) < 1e-6
    assert abs(d["v[3]"][-1]) < 1e-5 and abs(d["r[1]"][-1]) < 1e-9 and abs(d["r[2]"][-1]) < 1e-9
    assert np.ptp(stop_forces) < 1e-6 * stop_forces[0]
    assert 0 < penetration < 0.03
    assert GRAVITY < peak < 50 * GRAVITY
    assert np.max(np.abs(balance)) < 1e-8 * MGRB
    # At rest the stops carry the weight: sum of the vertical stop force components = M g.
    h_rest = z_static - H_C
    assert abs(sum(stop_forces) * h_rest / l_static - MASS * GRAVITY) < 1e-6 * MASS * GRAVITY


def test_elastic_stops_conserve_energy_over_ten_bounces_and_keep_the_tolerance_through_contacts():
    tight = ws.elastic_bounces(6.0, 1e-12)
    landings = [e for e in tight["events"] if e[1] == 1 and e[2] == "reached"]
    drift = np.max(np.abs(tight["E"] - tight["E"][0])) / abs(tight["E"][0])
    # Five bounces (3 s): until then the tilt that round-off seeds (amplified about 30x by
    # every landing: the bouncing platform is unstable in tilt) is invisible in the heave.
    ref = ws.elastic_bounces(3.0, 1e-12)
    loose = ws.elastic_bounces(3.0, 1e-10)
    difference = np.max(np.abs(loose["r[3]"] - ref["r[3]"]))
    print(f"elastic stops: {len(landings)} bounces in 6 s, relative energy drift {drift:.1e} (relTol 1e-12); "
          f"first five bounces: max |z(relTol 1e-10) - z(relTol 1e-12)| = {difference:.1e} m; "
          f"tilt at 6 s {np.max(np.abs(tight['angles[1]'][-10:])):.1e} rad")
    assert len(landings) >= 10
    assert drift < 1e-9
    assert difference < 1e-8


def test_start_up_lifts_the_parked_platform_off_its_stops_and_then_tracks_the_heave_programme():
    d = ws.start_up(t_end=12.0, duration=3.0)
    releases = [e for e in d["events"] if e[2] == "left" and e[3] == "lower"]
    touches = [e for e in d["events"] if e[2] == "reached"]
    initial_stop_force = [d[f"Fstop[{k}]"][0] for k in ws.LEGS]
    heave = d["time"] > 4.0
    print(f"start-up from z = {d['z_rest']:.6f} m on the lower stops: stop forces at the first step "
          f"{np.round(initial_stop_force, 1)} N; legs leave their stops at t = "
          f"{[round(e[0], 6) for e in releases]} s; later contacts {touches}; max |l - l^p| during the heave "
          f"programme {np.max(d['error'][heave]) * 1e3:.4f} mm; z range {np.ptp(d['r[3]'][heave]):.3f} m")
    assert d["status"] == "ok"
    assert sorted(e[1] for e in releases) == list(ws.LEGS)
    assert not touches
    assert max(e[0] for e in releases) < 0.5
    assert np.max(d["error"][heave]) < 1e-4
    assert np.ptp(d["r[3]"][heave]) > 0.5  # the heave programme runs (+-0.3 m)


def test_actuator_failure_tilts_the_platform_onto_its_stops_and_no_host_step_is_lost():
    d = ws.actuator_failure(t_fail=1.0, t_end=5.0)
    hits = [e for e in d["events"] if e[2] == "reached"]
    print("actuator failure of leg 1 at t = 1 s under feedback: " + "; ".join(
        f"t = {t:.4f} s leg {k} {what} its {stop} stop" for t, k, what, stop in d["events"][:12])
        + f" ... ({len(d['events'])} contact events); final roll {d['angles[1]'][-1]:.3f} rad, "
          f"pitch {d['angles[2]'][-1]:.3f} rad, leg 1 {d['l[1]'][-1]:.4f} m")
    assert d["status"] == "ok"
    assert hits and all(t > 1.0 for t, *_ in hits)
    assert (1, "lower") in {(k, stop) for _, k, _, stop in hits}
    assert abs(d["l[1]"][-1] - 1.45) < 0.01
    assert max(abs(d["angles[1]"][-1]), abs(d["angles[2]"][-1])) > 0.05


def newton_euler_held(forces_of_t, t_end, h):
    """Independent reference: centre-of-mass theorem + Euler's equations in body axes, unit
    quaternion, scipy DOP853 over each step with the forces held; docs/model.md §3 geometry."""
    base = [np.array([R_B * math.cos(math.radians(a)), R_B * math.sin(math.radians(a)), 0.0]) for a in BASE_AZIMUTHS]
    plat = [np.array([R_P * math.cos(math.radians(a)), R_P * math.sin(math.radians(a)), -H_C])
            for a in PLATFORM_AZIMUTHS]
    j = np.array(INERTIA)

    def rot(q):
        w, x, y, z = q / np.linalg.norm(q)
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])

    def rhs(_t, s, u):
        r, v, q, w = s[0:3], s[3:6], s[6:10], s[10:13]
        big_r = rot(q)
        force = np.array([0.0, 0.0, -MASS * GRAVITY])
        moment = np.zeros(3)
        for k in range(6):
            arm = big_r @ plat[k]
            leg = r + arm - base[k]
            f = leg / np.linalg.norm(leg) * u[k]
            force += f
            moment += np.cross(arm, f)
        wd = (big_r.T @ moment - np.cross(w, j * w)) / j
        qw, qx, qy, qz = q
        qd = 0.5 * np.array([-qx * w[0] - qy * w[1] - qz * w[2], qw * w[0] + qy * w[2] - qz * w[1],
                             qw * w[1] + qz * w[0] - qx * w[2], qw * w[2] + qx * w[1] - qy * w[0]])
        return np.concatenate([v, force / MASS, qd, wd])

    s = np.array([0, 0, NEUTRAL_Z, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0], dtype=float)
    out = []
    for i in range(int(round(t_end / h))):
        sol = solve_ivp(rhs, (i * h, (i + 1) * h), s, method="DOP853", rtol=1e-13, atol=1e-15,
                        args=(forces_of_t(i * h),))
        s = sol.y[:, -1]
        s[6:10] /= np.linalg.norm(s[6:10])
        out.append((s[0:3].copy(), rot(s[6:10])))
    return out


def test_tumble_through_singular_arrangements_without_a_discard_matches_newton_euler():
    d = ws.tumble(t_end=3.0, h=1e-2)
    reference = newton_euler_held(ws.tumble_forces, 3.0, 1e-2)
    dr = max(np.linalg.norm([d["r[1]"][i + 1] - r[0], d["r[2]"][i + 1] - r[1], d["r[3]"][i + 1] - r[2]])
             for i, (r, _) in enumerate(reference))
    drot = max(np.max(np.abs(np.array([[d[f"R[{a},{b}]"][i + 1] for b in range(1, 4)] for a in range(1, 4)]) - m))
               for i, (_, m) in enumerate(reference))
    print(f"tumble, no end stops, 3 s at 10 ms: singular arrangements passed at t = "
          f"{[round(t, 4) for t in d['singular']]} s; kappa up to {np.max(d['kappa']):.2e}; "
          f"max |r - r_NE| = {dr:.1e} m, max |R - R_NE| = {drot:.1e}")
    assert len(d["time"]) == 301, "no discard"
    assert len(d["singular"]) >= 3
    assert dr < 1e-9 and drot < 1e-9


def test_power_loss_through_model_exchange_reaches_the_same_rest_pose_with_located_contacts():
    cs = ws.power_loss()
    me, events = ws.power_loss_model_exchange()
    cs_first = min(e[0] for e in cs["events"] if e[2] == "reached")
    me_onsets = [e for e in events if e[2] == "reached"]
    balance = me["E"] - me["E"][0] - (me["work.F"] - me["work.dissipated"])
    print(f"power loss through FMPy Model Exchange (CVODE rtol 1e-8): rest z = {me['r[3]'][-1]:.10f} m "
          f"(Co-Simulation {cs['r[3]'][-1]:.10f} m), first contact at t = {me_onsets[0][0]:.9f} s located by the "
          f"event indicators (Co-Simulation {cs_first:.9f} s), {len(me_onsets)} contact onsets, "
          f"energy balance residual {np.max(np.abs(balance)):.1e} J")
    assert abs(me["r[3]"][-1] - cs["r[3]"][-1]) < 1e-4
    assert len({e[1] for e in me_onsets}) == 6
    assert abs(me_onsets[0][0] - cs_first) < 1e-6
    assert np.max(np.abs(balance)) < 1e-4 * MGRB
