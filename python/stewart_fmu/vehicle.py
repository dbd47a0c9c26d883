"""Vehicle motions for the cueing FMU (docs/cueing.md): a truck's specific force and angular
velocity at the driver's head, in the units and axes of SPEC §11 (m/s2 and rad/s, cabin axes x
forward, y left, z up; f = (0, 0, g) at rest), from a simple model documented here.

The model: a kinematic single-track vehicle (no tyre slip) on a road that may have bumps. The
manoeuvre prescribes the longitudinal acceleration a_x(t) (jerk-limited ramps) and the path
curvature kappa(t); speed u = integral of a_x, yaw rate r = u kappa, lateral acceleration
a_y = u r. The cabin sits on a suspension: its pitch and roll follow -k_pitch a_x and
k_roll a_y through a second-order lag (braking dips the nose, a left turn lifts the left side),
its heave follows the road profile under the front axle through a second-order lag. The cabin's
attitude is the heading (yaw about the vertical) followed by R_v = Rx(roll) Ry(pitch); the
head's specific force is f = R_v^T (a + g ez) (the heading frame's acceleration a), its angular
velocity omega = roll' (cos pitch, 0, sin pitch) + pitch' (0, 1, 0) + R_v^T (0, 0, yaw rate).
The head's lever arm from the cabin's rotation centre is neglected (the cabin's angles stay
below a degree or two)."""

import csv
import math
from pathlib import Path

import numpy as np

from .core import GRAVITY as G
#: Cabin suspension: pitch and roll per m/s2 of acceleration (rad), natural frequency (rad/s)
#: and damping of their lag; heave's natural frequency and damping.
K_PITCH, K_ROLL = math.radians(0.4), math.radians(0.6)
ATTITUDE_OMEGA, ATTITUDE_DAMPING = 6.0, 0.7
HEAVE_OMEGA, HEAVE_DAMPING = 9.0, 0.35
#: The sample interval of the manoeuvres, s.
DT = 0.01
COLUMNS = ["time", "f[1]", "f[2]", "f[3]", "omega[1]", "omega[2]", "omega[3]"]


def smooth_step(t, t0, duration):
    """0 before t0, 1 after t0 + duration, a cosine ramp between (jerk-limited)."""
    x = np.clip((np.asarray(t) - t0) / duration, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(math.pi * x)


def _lag(signal, omega, damping, dt):
    """`signal` through omega^2/(s^2 + 2 damping omega s + omega^2), from rest (semi-implicit
    Euler on a fine grid): the value and its first and second derivatives."""
    x, v = float(signal[0]), 0.0
    out = np.empty((len(signal), 3))
    for i, u in enumerate(signal):
        a = omega * omega * (u - x) - 2 * damping * omega * v
        out[i] = (x, v, a)
        v += a * dt
        x += v * dt
    return out


def motion(t, a_x, kappa, road=None, u0=0.0):
    """The head's specific force and angular velocity for the manoeuvre (arrays over the
    uniform times `t`): longitudinal acceleration `a_x` (m/s2), path curvature `kappa` (1/m),
    `road` height under the front axle (m; None: flat), initial speed `u0` (m/s). Returns the
    columns of COLUMNS as a dict, with the vehicle's speed `u` (m/s) beside them."""
    dt = float(t[1] - t[0])
    u = np.maximum(u0 + np.concatenate([[0.0], np.cumsum(0.5 * (a_x[1:] + a_x[:-1]) * dt)]), 0.0)
    a_x = np.where(u > 0.0, a_x, np.maximum(a_x, 0.0))
    yaw_rate = u * kappa
    a_y = u * yaw_rate
    pitch = _lag(-K_PITCH * a_x, ATTITUDE_OMEGA, ATTITUDE_DAMPING, dt)
    roll = _lag(K_ROLL * a_y, ATTITUDE_OMEGA, ATTITUDE_DAMPING, dt)
    heave = _lag(np.zeros_like(t) if road is None else road, HEAVE_OMEGA, HEAVE_DAMPING, dt)
    f, omega = np.empty((len(t), 3)), np.empty((len(t), 3))
    for i in range(len(t)):
        phi, theta = roll[i, 0], pitch[i, 0]
        cp, sp, ct, st = math.cos(phi), math.sin(phi), math.cos(theta), math.sin(theta)
        rx = np.array([[1, 0, 0], [0, cp, -sp], [0, sp, cp]])
        ry = np.array([[ct, 0, st], [0, 1, 0], [-st, 0, ct]])
        a = np.array([a_x[i], a_y[i], heave[i, 2] + G])
        f[i] = (rx @ ry).T @ a
        d_roll, d_pitch, d_yaw = roll[i, 1], pitch[i, 1], yaw_rate[i]
        omega[i] = (d_roll * ct - st * cp * d_yaw, d_pitch + sp * d_yaw, d_roll * st + ct * cp * d_yaw)
    columns = {"time": np.asarray(t, float)}
    for k in range(3):
        columns[f"f[{k + 1}]"] = f[:, k]
        columns[f"omega[{k + 1}]"] = omega[:, k]
    columns["u"] = u
    return columns


def _times(duration):
    return np.arange(int(round(duration / DT)) + 1) * DT


def accelerate(duration=20.0, acceleration=1.0, start=1.0):
    """From rest to a steady acceleration (a loaded truck pulling away), held."""
    t = _times(duration)
    return motion(t, acceleration * smooth_step(t, start, 1.0), np.zeros_like(t))


def brake(duration=20.0, deceleration=3.0, speed=15.0, start=1.0):
    """Braking from `speed` to a stop at `deceleration` (m/s2), the stop's jerk included."""
    t = _times(duration)
    # The ramps in (1 s) and out (0.5 s) take half and a quarter of their length's speed, so the
    # speed reaches 0 as the ramp out ends.
    stop = start + 0.75 + speed / deceleration
    a_x = -deceleration * (smooth_step(t, start, 1.0) - smooth_step(t, stop - 0.5, 0.5))
    return motion(t, a_x, np.zeros_like(t), u0=speed)


def lane_change(duration=12.0, speed=20.0, lateral=2.0, peak=2.0, start=1.0):
    """A single lane change at `speed` (m/s) with a lateral acceleration of up to `peak`
    (m/s2): one period of a sine in the lateral acceleration, over the time a lateral shift of
    `lateral` (m) takes."""
    t = _times(duration)
    period = math.sqrt(2 * math.pi * lateral / peak)
    x = np.clip((t - start) / period, 0.0, 1.0)
    a_y = peak * np.sin(2 * math.pi * x) * ((t >= start) & (t <= start + period))
    return motion(t, np.zeros_like(t), a_y / speed ** 2, u0=speed)


def curve(duration=25.0, speed=15.0, lateral=2.0, start=2.0, entry=3.0, arc=10.0):
    """Into a curve at constant `speed` with a steady lateral acceleration `lateral` (m/s2),
    through a clothoid entry and exit of `entry` seconds."""
    t = _times(duration)
    shape = smooth_step(t, start, entry) - smooth_step(t, start + entry + arc, entry)
    return motion(t, np.zeros_like(t), shape * lateral / speed ** 2, u0=speed)


def bumps(duration=12.0, speed=12.0, height=0.03, spacing=6.0, start=1.0, count=5):
    """A road with `count` half-sine bumps of `height` (m), each a metre long, `spacing` apart,
    at constant `speed`."""
    t = _times(duration)
    x = speed * (t - start)
    road = np.zeros_like(t)
    for b in range(count):
        s = (x - b * spacing) / 1.0
        road += height * np.where((s > 0) & (s < 1), np.sin(math.pi * np.clip(s, 0, 1)) ** 2, 0.0)
    return motion(t, np.zeros_like(t), np.zeros_like(t), road=road, u0=speed)


def pothole(duration=8.0, speed=15.0, depth=0.06, length=0.5, start=2.0):
    """A pothole of `depth` (m) and `length` (m) at `speed` (a harsh heave input)."""
    t = _times(duration)
    s = (speed * (t - start)) / length
    road = -depth * np.where((s > 0) & (s < 1), np.sin(math.pi * np.clip(s, 0, 1)) ** 2, 0.0)
    return motion(t, np.zeros_like(t), np.zeros_like(t), road=road, u0=speed)


def slalom(duration=20.0, speed=15.0, peak=2.5, frequency=0.4, start=1.0):
    """A slalom at constant `speed` (m/s): the lateral acceleration a sinusoid of `peak` (m/s2)
    at `frequency` (Hz), faded in over its first second (the yaw rate follows)."""
    t = _times(duration)
    a_y = peak * np.sin(2 * math.pi * frequency * (t - start)) * smooth_step(t, start, 1.0)
    return motion(t, np.zeros_like(t), a_y / speed ** 2, u0=speed)


#: The manoeuvres the main job writes (examples/cueing_manoeuvres.py), by file name.
MANOEUVRES = {
    "accelerate": accelerate,
    "brake": brake,
    "lane_change": lane_change,
    "curve": curve,
    "bumps": bumps,
    "slalom": slalom,
}
#: Harsh manoeuvres: the workspace limiter's cases.
HARSH = {
    "emergency_stop": lambda: brake(deceleration=6.0, speed=20.0),
    "lane_change_05g": lambda: lane_change(peak=0.5 * G, lateral=3.5, speed=25.0),
    "pothole": pothole,
}


def random_manoeuvre(seed, duration=12.0, f_limit=8.0, omega_limit=0.5, dt=DT):
    """A fuzzed vehicle motion for the limiter's tests: per axis a sum of two smoothed steps
    and two sinusoids (0.1 to 10 rad/s) of random amplitudes, the specific force's deviation
    from rest within +-`f_limit` (m/s2) and the angular velocity within +-`omega_limit`
    (rad/s). Seeded: the same `seed` gives the same motion."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration / dt)) + 1) * dt
    columns = {"time": t}
    for name, limit, rest in (("f", f_limit, (0.0, 0.0, G)), ("omega", omega_limit, (0.0, 0.0, 0.0))):
        for k in range(3):
            x = np.zeros_like(t)
            for _ in range(2):
                x += rng.uniform(-1, 1) * smooth_step(t, rng.uniform(0, duration), rng.uniform(0.05, 2.0))
                x += rng.uniform(-0.5, 0.5) * np.sin(10 ** rng.uniform(-1, 1) * t + rng.uniform(0, 2 * math.pi))
            scale = limit / max(1.0, float(np.max(np.abs(x))))
            columns[f"{name}[{k + 1}]"] = rest[k] + scale * x
    return columns


def write_csv(columns, path):
    """Writes the manoeuvre's COLUMNS (SI units: s, m/s2, rad/s) to `path`."""
    path = Path(path)
    with path.open("w", newline="") as out:
        w = csv.writer(out)
        w.writerow(COLUMNS)
        for row in zip(*(columns[c] for c in COLUMNS)):
            w.writerow([f"{x:.9g}" for x in row])
    return path


def read_csv(path):
    """A manoeuvre written by `write_csv`, as a dict of arrays; ValueError naming a missing
    column."""
    with Path(path).open() as f:
        rows = list(csv.reader(f))
    header = rows[0]
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise ValueError(f"{path}: the columns {missing} are missing (expected {COLUMNS}: s, m/s2, rad/s)")
    data = np.array(rows[1:], dtype=float)
    return {c: data[:, header.index(c)] for c in COLUMNS}


def at(columns, t):
    """The vehicle's `f` and `omega` at time `t`, linearly interpolated (held after the end)."""
    time = columns["time"]
    return (np.array([np.interp(t, time, columns[f"f[{k}]"]) for k in (1, 2, 3)]),
            np.array([np.interp(t, time, columns[f"omega[{k}]"]) for k in (1, 2, 3)]))
