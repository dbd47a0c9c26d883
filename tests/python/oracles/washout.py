"""SPEC §11's classical washout, written from SPEC alone (an oracle for the StewartCueing FMU,
cueing.method = 0), with the IDEAL tilt rate limiter, integrated by scipy's solve_ivp (DOP853,
rtol 1e-10, atol 1e-12) with event location for the limiter's switches.

The model, in SPEC §11's words and symbols (vehicle/cabin axes x forward, y left, z up;
g_vec = (0, 0, -g), ez = (0, 0, 1); angles the 1-2-3 sequence R = Rx(roll) Ry(pitch) Rz(yaw)):

- f_s = clip(K_f (f - g ez), -fmax, fmax) + g ez, omega_s = clip(K_w omega, -omegamax, omegamax)
  per component. The inputs are a table linearly interpolated in time, so f_s and omega_s are
  piecewise linear too once the clips' crossings are added as breakpoints (done exactly here).
- Tilt coordination: f_l = W_l(s) f_s,xy, W_l = w_l^2/(s^2 + 2 zeta_l w_l s + w_l^2) (state f_l,
  f_l'); target roll* = asin(clip(f_l,y/g)), pitch* = -asin(clip(f_l,x/(g cos roll*))), both
  arguments clipped to +-sin(tilt.max). Ideal rate limiter per angle: while tracking, the tilt
  equals its target (and its rate the target's rate, |target'| <= tilt.rateLimit); when
  |target'| exceeds the limit the tilt slews at +-tilt.rateLimit (the sign of target') until it
  meets the target again, then tracks. Events: |target'| = L (tracking -> slewing), tilt = target
  (slewing -> tracking), and the clips' boundaries |argument| = sin(tilt.max) (a kink of the
  target: the integration restarts there).
- Rotation: u = E(beta)^-1 omega_s with omega_body = E(beta) beta' for the 1-2-3 sequence; each
  u_i through W_r = s^2/(s^2 + 2 zeta_r w_r s + w_r^2) to a rate rho_i, integrated to an angle
  a_i. State per axis: z_i and a_i = z_i' with z_i'' + 2 zeta_r w_r z_i' + w_r^2 z_i = u_i, so
  a_i = (s/(s^2 + ...)) u_i and rho_i = a_i' = W_r u_i = u_i - 2 zeta_r w_r a_i - w_r^2 z_i.
  beta = a + (tilt roll, tilt pitch, 0); R_sim = R(beta).
- Translation: a_I = R_sim f_s + g_vec per inertial axis through
  W_t = s^3/((s^2 + 2 zeta_t w_t s + w_t^2)(s + w_b)) gives the head's acceleration; integrated
  twice, its velocity and displacement from neutral. State per axis: q, d = q', v = q'' with
  (D^2 + 2 zeta_t w_t D + w_t^2)(D + w_b) q = a_I, so d = W_t/s^2 a_I, v = d', P'' = v' = q'''.
- The head P = neutral + head + d (the head's neutral position: the centre of mass at
  `neutral`, no rotation); the centre of mass r = P - R_sim head, r' = P' - R_sim (w x head),
  r'' = P'' - R_sim (w x (w x head) + w' x head), w = E(beta) beta' (body axes).
- fsim = R_sim^T (P'' - g_vec), omegasim = E(beta) beta'.
- pose.angleAccelerations = beta'' "with the inputs held" (SPEC): the derivative of the rates
  with omega_s' = 0. With inputs that follow a ramp (a first-order hold) the true derivative
  adds E^-1 omega_s' through W_r's feedthrough; both are returned (`...Accelerations` held,
  `...Accelerations.ramp` with the input's slope to the right of t), and the same for pose.a.

All states start at zero (rest: neutral pose, zero filter states, the tilt tracking its target 0).
The workspace limiter is not modelled: the caller checks that the FMU's workspace.scale stays 1.
"""

import math

import numpy as np
from fmpy import read_model_description
from scipy.integrate import solve_ivp

RTOL, ATOL = 1e-10, 1e-12
EZ = np.array([0.0, 0.0, 1.0])
#: The state's layout: the tilt low-pass (f_l,x, f_l,x', f_l,y, f_l,y'), the slewing tilt
#: (roll, pitch), the rotational filters (z[3], a[3]), the translational filters (q[3], d[3], v[3]).
FL, DFL, TILT = [0, 2], [1, 3], slice(4, 6)
Z, ANG = slice(6, 9), slice(9, 12)
Q, D, V = slice(12, 15), slice(15, 18), slice(18, 21)
N_STATES = 21


def start_values(fmu):
    """The FMU's Real parameters' start values from its modelDescription.xml, by name."""
    return {v.name: float(v.start) for v in read_model_description(str(fmu)).modelVariables
            if v.causality == "parameter" and v.type == "Real" and v.start is not None}


def rotation(angles):
    """R = Rx(roll) Ry(pitch) Rz(yaw) (SPEC §1, counter-clockwise positive), body -> inertial."""
    a, b, c = angles
    ca, sa, cb, sb, cc, sc = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, ca, -sa], [0.0, sa, ca]])
    ry = np.array([[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]])
    rz = np.array([[cc, -sc, 0.0], [sc, cc, 0.0], [0.0, 0.0, 1.0]])
    return rx @ ry @ rz


def euler_matrix(angles):
    """E with w_body = E beta' for the 1-2-3 sequence: w = Rz^T Ry^T ex roll' + Rz^T ey pitch' +
    ez yaw', i.e. columns (cos p cos y, -cos p sin y, sin p), (sin y, cos y, 0), (0, 0, 1)."""
    _, b, c = angles
    cb, sb, cc, sc = math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    return np.array([[cb * cc, sc, 0.0], [-cb * sc, cc, 0.0], [sb, 0.0, 1.0]])


def euler_rates(angles, w):
    """E^-1 w: the 1-2-3 angle rates of the body angular velocity w (solving the rows of E:
    roll' cos p = cos y w1 - sin y w2, pitch' = sin y w1 + cos y w2, yaw' = w3 - sin p roll')."""
    _, b, c = angles
    cc, sc = math.cos(c), math.sin(c)
    droll = (cc * w[0] - sc * w[1]) / math.cos(b)
    return np.array([droll, sc * w[0] + cc * w[1], w[2] - math.sin(b) * droll])


def cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def euler_matrix_rate(angles, rates):
    """dE/dt = pitch' dE/dpitch + yaw' dE/dyaw."""
    _, b, c = angles
    _, db, dc = rates
    cb, sb, cc, sc = math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    d_pitch = np.array([[-sb * cc, 0.0, 0.0], [sb * sc, 0.0, 0.0], [cb, 0.0, 0.0]])
    d_yaw = np.array([[-cb * sc, cc, 0.0], [-cb * cc, -sc, 0.0], [0.0, 0.0, 0.0]])
    return db * d_pitch + dc * d_yaw


class Washout:
    """SPEC §11's classical washout for the parameters `p` (a dict by the FMU's names, e.g.
    `start_values(fmu)`)."""

    def __init__(self, p):
        self.g = p["g"]
        vec = lambda name: np.array([p[f"{name}[{k}]"] for k in (1, 2, 3)])  # noqa: E731
        self.k_f, self.k_w = vec("scale.f"), vec("scale.omega")
        self.fmax, self.omegamax = p["fmax"], p["omegamax"]
        w_t, z_t, w_b = vec("hp.f.omega"), vec("hp.f.damping"), vec("hp.f.break")
        # (s^2 + 2 z w s + w^2)(s + w_b) = s^3 + c2 s^2 + c1 s + c0
        self.c2, self.c1, self.c0 = 2 * z_t * w_t + w_b, w_t ** 2 + 2 * z_t * w_t * w_b, w_t ** 2 * w_b
        self.w_l, self.z_l = p["tilt.omega"], p["tilt.damping"]
        self.rate_limit, self.sin_max = p["tilt.rateLimit"], math.sin(p["tilt.max"])
        self.w_r, self.z_r = vec("hp.w.omega"), vec("hp.w.damping")
        self.head, self.neutral = vec("head"), vec("neutral")

    # -- the inputs ---------------------------------------------------------------------------
    def scaled_table(self, time, f, omega):
        """f_s and omega_s on the input's times plus the times where a clip starts or stops
        acting (exact for linear interpolation): (times, f_s rows, omega_s rows)."""
        time = np.asarray(time, dtype=float)
        if np.any(np.diff(time) <= 0):
            raise ValueError("the input table's times must increase")
        dev_f = self.k_f * (np.asarray(f, dtype=float) - self.g * EZ)
        dev_w = self.k_w * np.asarray(omega, dtype=float)
        extra = []
        for dev, limit in ((dev_f, self.fmax), (dev_w, self.omegamax)):
            for level in (-limit, limit):
                x0, x1 = dev[:-1] - level, dev[1:] - level
                i, k = np.nonzero(x0 * x1 < 0)
                extra.extend(time[i] + x0[i, k] / (x0[i, k] - x1[i, k]) * (time[i + 1] - time[i]))
        times = np.union1d(time, np.array(extra))
        interp = lambda dev: np.column_stack([np.interp(times, time, dev[:, k]) for k in range(3)])  # noqa: E731
        f_s = np.clip(interp(dev_f), -self.fmax, self.fmax) + self.g * EZ
        w_s = np.clip(interp(dev_w), -self.omegamax, self.omegamax)
        return times, f_s, w_s

    # -- the tilt coordination ------------------------------------------------------------------
    def targets(self, fl, dfl, ddfl, clipped):
        """(roll*, pitch*), their first and second derivatives (the arguments' derivatives from
        f_l's), the arcsines' arguments; `clipped[i]`: whether angle i's argument is clipped
        (its target then stands still)."""
        g, s_max = self.g, self.sin_max
        sr, dsr, ddsr = fl[1] / g, dfl[1] / g, ddfl[1] / g
        if clipped[0]:
            roll, droll, ddroll = math.asin(math.copysign(s_max, sr)), 0.0, 0.0
        else:
            c = math.sqrt(1.0 - sr * sr)
            roll, droll, ddroll = math.asin(sr), dsr / c, ddsr / c + sr * dsr * dsr / c ** 3
        cr, sn = math.cos(roll), math.sin(roll)
        sp = fl[0] / (g * cr)
        dsp = (dfl[0] / cr + fl[0] * sn * droll / cr ** 2) / g
        ddsp = (ddfl[0] / cr + 2 * dfl[0] * sn * droll / cr ** 2
                + fl[0] * ((cr * droll ** 2 + sn * ddroll) / cr ** 2 + 2 * sn * sn * droll ** 2 / cr ** 3)) / g
        if clipped[1]:
            pitch, dpitch, ddpitch = -math.asin(math.copysign(s_max, sp)), 0.0, 0.0
        else:
            c = math.sqrt(1.0 - sp * sp)
            pitch, dpitch, ddpitch = -math.asin(sp), -dsp / c, -(ddsp / c + sp * dsp * dsp / c ** 3)
        return (np.array([roll, pitch]), np.array([droll, dpitch]), np.array([ddroll, ddpitch]),
                np.array([sr, sp]))

    # -- the whole washout at one instant -------------------------------------------------------
    def evaluate(self, t, y, segment, modes, clipped, outputs=False):
        """The state's derivative at (t, y) on the input `segment` (t0, t1, f_s0, f_s1, w_s0,
        w_s1) with the limiter's `modes` (0 tracking, +1/-1 slewing up/down) and the clips'
        state; with `outputs`, a dict of the outputs too."""
        t0, t1, fs0, fs1, ws0, ws1 = segment
        h = t1 - t0
        fs_slope, ws_slope = (fs1 - fs0) / h, (ws1 - ws0) / h
        fs = fs0 + (t - t0) * fs_slope
        ws = ws0 + (t - t0) * ws_slope
        fl, dfl = y[FL], y[DFL]
        ddfl = self.w_l ** 2 * (fs[:2] - fl) - 2 * self.z_l * self.w_l * dfl
        target, dtarget, ddtarget, _ = self.targets(fl, dfl, ddfl, clipped)
        tracking = modes == 0
        tilt = np.where(tracking, target, y[TILT])
        dtilt = np.where(tracking, dtarget, modes * self.rate_limit)
        ddtilt = np.where(tracking, ddtarget, 0.0)
        z, ang = y[Z], y[ANG]
        beta = ang + np.array([tilt[0], tilt[1], 0.0])
        e = euler_matrix(beta)
        u = euler_rates(beta, ws)
        rho = u - 2 * self.z_r * self.w_r * ang - self.w_r ** 2 * z
        rot = rotation(beta)
        a_inertial = rot @ fs - self.g * EZ
        q, d, v = y[Q], y[D], y[V]
        acc = a_inertial - self.c2 * v - self.c1 * d - self.c0 * q
        dy = np.empty(N_STATES)
        dy[FL], dy[DFL] = dfl, ddfl
        dy[TILT] = dtilt
        dy[Z], dy[ANG] = ang, rho
        dy[Q], dy[D], dy[V] = d, v, acc
        if not outputs:
            return dy
        dbeta = rho + np.array([dtilt[0], dtilt[1], 0.0])
        e_rate = euler_matrix_rate(beta, dbeta)
        w = e @ dbeta
        out = {"beta": beta, "dbeta": dbeta, "tilt": tilt, "target": target, "fsim": rot.T @ (acc + self.g * EZ),
               "omegasim": w}
        p = self.neutral + self.head + d
        out["r"], out["v"] = p - rot @ self.head, v - rot @ cross(w, self.head)
        for variant, dws in (("", np.zeros(3)), (".ramp", ws_slope)):
            du = euler_rates(beta, dws - e_rate @ u)  # d/dt (E^-1 w_s) = E^-1 (w_s' - E' E^-1 w_s)
            drho = du - 2 * self.z_r * self.w_r * rho - self.w_r ** 2 * ang
            ddbeta = drho + np.array([ddtilt[0], ddtilt[1], 0.0])
            dw = e_rate @ dbeta + e @ ddbeta
            out["ddbeta" + variant] = ddbeta
            out["a" + variant] = acc - rot @ (cross(w, cross(w, self.head)) + cross(dw, self.head))
        return dy, out

    # -- the limiter's events -----------------------------------------------------------------
    def _target_of(self, y, clipped):
        fl, dfl = y[FL], y[DFL]
        return self.targets(fl, dfl, np.zeros(2), clipped)

    def _events(self, modes, clipped):
        """The event functions for the present modes and clips, each with its kind and angle;
        directions chosen so that the switch just made is not found again at the start."""
        events = []
        for i in (0, 1):
            if modes[i] == 0:
                def fn(t, y, i=i):
                    return abs(self._target_of(y, clipped)[1][i]) - self.rate_limit
                fn.direction = 1.0
                fn.kind = "start slewing"
            else:
                sign = modes[i]

                def fn(t, y, i=i, sign=sign):
                    return sign * (self._target_of(y, clipped)[0][i] - y[TILT][i])
                fn.direction = -1.0
                fn.kind = "caught up"
            fn.terminal, fn.angle = True, i
            events.append(fn)

            def clip(t, y, i=i):
                return abs(self._target_of(y, clipped)[3][i]) - self.sin_max
            clip.direction = -1.0 if clipped[i] else 1.0
            clip.terminal, clip.angle, clip.kind = True, i, "clip"
            events.append(clip)
        return events

    def _start_slewing_if_needed(self, t, y, modes, clipped, switches):
        """A tracking angle whose target moves faster than the limit starts slewing (after a
        catch-up or a clip's release, where the target's rate may jump)."""
        target, dtarget, _, _ = self._target_of(y, clipped)
        for i in (0, 1):
            if modes[i] == 0 and abs(dtarget[i]) > self.rate_limit:
                modes[i] = 1 if dtarget[i] > 0 else -1
                y[4 + i] = target[i]
                switches.append((t, i + 1, "slew up" if modes[i] > 0 else "slew down"))

    # -- a run --------------------------------------------------------------------------------
    def simulate(self, time, f, omega, t_out, rtol=RTOL, atol=ATOL):
        """The washout on the input table (`time`, `f` rows, `omega` rows; linear in between)
        from rest; returns a dict of arrays at `t_out` by the FMU's output names
        (pose.r[k], pose.v[k], pose.a[k], pose.angles[k], pose.angleRates[k],
        pose.angleAccelerations[k], fsim[k], omegasim[k]), the `.ramp` variants of pose.a and
        pose.angleAccelerations, washout.tilt[1..2], the targets (`target[1..2]`), and
        `switches`: [(time, angle 1 or 2, what)] of the limiter and the clips."""
        times, f_s, w_s = self.scaled_table(time, f, omega)
        y = np.zeros(N_STATES)
        modes, clipped = np.zeros(2, dtype=int), [False, False]
        pieces, switches = [], []
        for k in range(len(times) - 1):
            segment = (times[k], times[k + 1], f_s[k], f_s[k + 1], w_s[k], w_s[k + 1])
            start = times[k]
            while True:
                self._start_slewing_if_needed(start, y, modes, clipped, switches)
                m, c = modes.copy(), list(clipped)
                events = self._events(m, c)
                sol = solve_ivp(lambda t, x: self.evaluate(t, x, segment, m, c), (start, times[k + 1]), y,
                                method="DOP853", rtol=rtol, atol=atol, events=events, dense_output=True)
                if sol.status < 0:
                    raise RuntimeError(f"washout oracle: {sol.message} at t = {start}")
                pieces.append((start, sol.t[-1], segment, m, c, sol.sol))
                y = sol.y[:, -1].copy()
                if sol.status == 0:
                    break
                start = sol.t[-1]
                target = self._target_of(y, clipped)[0]
                for fn, hit in zip(events, sol.t_events):
                    if len(hit) and hit[-1] == start:
                        i = fn.angle
                        if fn.kind == "clip":
                            clipped[i] = not clipped[i]
                            switches.append((start, i + 1, "clip " + ("on" if clipped[i] else "off")))
                        elif fn.kind == "start slewing":
                            dtarget = self._target_of(y, c)[1][i]
                            modes[i] = 1 if dtarget > 0 else -1
                            y[4 + i] = target[i]
                            switches.append((start, i + 1, "slew up" if modes[i] > 0 else "slew down"))
                        else:
                            modes[i] = 0
                            y[4 + i] = target[i]
                            switches.append((start, i + 1, "track"))
                if start >= times[k + 1]:
                    break
        return self._outputs(pieces, np.asarray(t_out, dtype=float), switches)

    def _outputs(self, pieces, t_out, switches):
        starts = np.array([p[0] for p in pieces])
        names = {"r": "pose.r", "v": "pose.v", "a": "pose.a", "a.ramp": "pose.a.ramp", "beta": "pose.angles",
                 "dbeta": "pose.angleRates", "ddbeta": "pose.angleAccelerations",
                 "ddbeta.ramp": "pose.angleAccelerations.ramp", "fsim": "fsim", "omegasim": "omegasim"}
        rows = {key: np.empty((len(t_out), 3)) for key in names}
        tilt, target = np.empty((len(t_out), 2)), np.empty((len(t_out), 2))
        for j, t in enumerate(t_out):
            i = min(max(int(np.searchsorted(starts, t, side="right")) - 1, 0), len(pieces) - 1)
            start, end, segment, modes, clipped, sol = pieces[i]
            if t > end + 1e-9:
                raise ValueError(f"t = {t} is after the simulated time {end}")
            _, out = self.evaluate(t, sol(t), segment, modes, clipped, outputs=True)
            for key in names:
                rows[key][j] = out[key]
            tilt[j], target[j] = out["tilt"], out["target"]
        result = {"time": t_out, "switches": switches}
        for key, name in names.items():
            for k in range(3):
                result[f"{name}[{k + 1}]"] = rows[key][:, k]
        for k in range(2):
            result[f"washout.tilt[{k + 1}]"] = tilt[:, k]
            result[f"target[{k + 1}]"] = target[:, k]
        return result
