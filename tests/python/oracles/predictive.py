"""The predictive motion cueing of the StewartCueing FMU (cueing.method = 1), written from SPEC
§12 and docs/cueing.md ("What the driver perceives", "Predictive cueing") alone, without the
FMU's source: an oracle for its Co-Simulation outputs.

The method, in the docs' words and symbols (angles and E(beta) as in §11: R = Rx Ry Rz,
w_body = E(beta) beta'; the perception model of §12 as in `oracles.perception`):

- The commanded motion: six channels c (the head's displacement P from neutral, inertial x, y,
  z; the attitude beta: roll, pitch, yaw), each a triple integrator (position, rate,
  acceleration) driven by its jerk, the jerk held between solves; integrated exactly here (a
  cubic over each step). The pose command is r = neutral + head + P - R(beta) head,
  r' = P' - R (w x head), r'' = P'' - R (w x (w x head) + w' x head), w = E beta',
  w' = E' beta' + E beta''; the angles beta, beta', beta''; the cues fsim = R^T (P'' + g ez),
  omegasim = E beta'.
- The perception: per cabin axis the otolith's lags (tau_oL, tau_oS) and the canal's (tau_1,
  tau_2, tau_a), x' = (y - x)/tau, each weighed by its partial-fraction coefficient (the
  residue of `oracles.perception` at -1/tau times tau: the docs' c_L, c_S, c_i); the perceived
  cue is sum c_i x_i. Over a step h with y linear each lag advances exactly:
  x1 = e x0 + (1 - e - q) y0 + q y1, e = exp(-h/tau), q = 1 - tau (1 - e)/h. The vehicle's
  lags see f and omega as the test drives them (linear over each communication step: held, or
  following their chord); the simulator's see fsim and omegasim linear between the ends of
  each of the step's equal sub-steps of at most solver.maxStep, the step's length taken as
  a step exceeding a multiple of it by round-off taking no extra one (`Predictive.substeps`:
  one for h = solver.maxStep = 1 ms; the FMU does the same). Start: the otolith lags at g ez, the canal lags at 0.
  Beside that rule the oracle also carries the simulator's lags integrated finely (`fine`
  sub-steps of the exact cubic motion per step, the chord error 1/fine^2 of the 1 ms one,
  not fed back into the solves): the outputs `perceived.fsim.fine[k]`,
  `perceived.omegasim.fine[k]`.
- A solve at t_k = k mpc.period (t from 0), at the start of the communication step from t_k,
  with the inputs set at t_k:
  1. the grid: N = 20 steps h_j = h_0 1.1^j summing to mpc.horizon, points tau_0 = 0,
     tau_j = h_0 + ... + h_{j-1};
  2. the unknowns: a jerk correction du[b][c] per block b (steps {0}, {1, 2}, {3..6},
     {7..19}) and channel c: 24;
  3. the nominal plan: step j takes the mean of the last plan's jerks over
     [tau_j, tau_{j+1}] + mpc.period on the last grid (0 beyond the horizon; all 0 at the
     first solve); the plan after the solve is the nominal jerk plus the step's block's
     correction; the command moves with the plan's step 0 until the next solve;
  4. the prediction: the nominal motion integrated exactly over the grid from the command now;
     at each point the cues linearised about it, y_j = y(nominal_j) + J_j (motion_j -
     nominal_j), the deviation linear in du (each block's unit jerk propagated over the grid);
     the simulator's lags advanced over each grid step with the cues linear between the
     points, from their values now; the vehicle's lags from their values now with f and omega
     guessed at the points from the inputs now and their change since the last solve (no
     preview file; `mpc.trend`, `Predictive.guess`), linear between the points;
  5. the objective 1/2 sum w r^2 over the residuals r:
     - points j = 1..20, cabin axis i: perceived simulator minus perceived vehicle cue, weight
       h_{j-1} exp(-tau_j / mpc.trust) mpc.weight.f[i] / thr_f[i]^2 (and .omega, with the
       thresholds 3.0, 3.6, 2.6 deg/s in rad/s);
     - points j = 1..20, channels P x, y, z and yaw: the position and the rate (times 1 s),
       weight h_{j-1} mpc.weight.neutral, plus 10 mpc.weight.neutral at j = 20;
     - steps j = 0..19, each channel: the plan's jerk (the angular ones times g), weight
       h_j mpc.weight.input;
  6. the inequalities at points 1, 3, 7, 20, linearised about the nominal motion: the legs
     within 90 % of the stroke from the neutral length towards lmin + margin and
     lmax - margin; the legs' speeds J (P', beta') within mpc.legSpeed; the roll and pitch
     rates (cabin axes, omegasim 1 and 2) within tilt.rateLimit plus the vehicle's own; the
     roll and the pitch within tilt.max; each softened by a shared slack sigma >= 0 of cost
     1e4 sigma + sigma^2 / 2.

How the oracle solves the QP: WITHOUT the inequalities. The objective is a strictly convex
quadratic in du (the jerk rows alone make its Hessian positive definite), so its minimiser
solves H du = -grad (Cholesky, scipy). It then evaluates every linearised inequality row at
that du, with sigma = 0. If every row holds strictly, the pair (du, sigma = 0) is the QP's
solution: it minimises the objective over a larger set, it is feasible, and for any feasible
(du', sigma') the objective is at least the unconstrained minimum plus 1e4 sigma'. A row that
does not hold strictly raises `ConstraintActive` (unless `allow_active`); each solve records
the rows' smallest margins per kind, in the slack's units (a leg's centimetre, 5 cm/s of leg
speed, a degree per second, a degree). Where the docs leave a reading open, both readings are
checked: the rate rows as |omegasim_i| <= rateLimit + |omega_i| ("tilt rate") and as
|omegasim_i - omega_i| <= rateLimit ("tilt rate (relative)"); the speed rows with J frozen at
the nominal pose ("leg speed") and as the speed's full linearisation, J's change with the pose
included ("leg speed (full)").

The workspace limiter's net behind the plan is not modelled: the caller checks that the FMU's
workspace.scale stays 1.
"""

import math

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from . import perception
from .washout import cross, start_values  # noqa: F401  (start_values: for the callers)

EZ = np.array([0.0, 0.0, 1.0])
#: SPEC §12's thresholds: specific force (m/s2) and angular velocity (rad/s) per cabin axis.
THRESHOLD_F = np.array([0.17, 0.17, 0.28])
THRESHOLD_OMEGA = np.radians([3.0, 3.6, 2.6])
#: The docs' grid and blocks.
STEPS, RATIO = 20, 1.1
BLOCKS = (1, 2, 4, 13)
#: The points where the inequalities hold (the blocks' ends).
CONSTRAINED_POINTS = np.array([1, 3, 7, 20])
#: The stroke share the plan's legs may use, and the slack's units per row kind.
STROKE_SHARE = 0.9
SLACK_UNIT = {"leg": 0.01, "leg speed": 0.05, "leg speed (full)": 0.05, "tilt rate": math.radians(1.0),
              "tilt rate (relative)": math.radians(1.0), "tilt": math.radians(1.0)}
#: The channels pulled back to neutral: P x, y, z and the yaw.
NEUTRAL_CHANNELS = (0, 1, 2, 5)
N_CHANNELS, N_BLOCKS = 6, len(BLOCKS)
N_UNKNOWNS = N_CHANNELS * N_BLOCKS
#: The perception's 15 lags: per cue (fsim x, y, z: the otolith's 2; omegasim x, y, z: the
#: canal's 3) their time constants, weights c_i = r_i tau_i (a mode r_i / (s + 1/tau_i) is
#: r_i tau_i / (tau_i s + 1)) and the cue each belongs to.
LAG_TAU = np.concatenate([perception.OTOLITH.taus] * 3 + [perception.CANAL.taus] * 3)
LAG_WEIGHT = np.concatenate([perception.OTOLITH.residues * perception.OTOLITH.taus] * 3
                            + [perception.CANAL.residues * perception.CANAL.taus] * 3)
LAG_CUE = np.repeat(np.arange(6), [2, 2, 2, 3, 3, 3])
#: perceived = LAG_SUM @ lags
LAG_SUM = np.zeros((6, len(LAG_TAU)))
LAG_SUM[LAG_CUE, np.arange(len(LAG_TAU))] = LAG_WEIGHT


class ConstraintActive(RuntimeError):
    """An inequality of the QP is active (or violated) at the unconstrained minimiser."""


def lags_at_rest(g):
    """The 15 lags at rest under f = g ez: the otolith lags of z at g, all others 0."""
    x = np.zeros(len(LAG_TAU))
    x[LAG_CUE == 2] = g
    return x


def lag_coefficients(h, tau=LAG_TAU):
    """(e, 1 - e - q, q) per lag for a step h with the cue linear over it."""
    e = np.exp(-h / tau)
    q = 1.0 - tau * -np.expm1(-h / tau) / h
    return e, 1.0 - e - q, q


def cubic_step(h):
    """The triple integrator over h with the jerk held: x1 = Phi x0 + Gamma u, x = (position,
    rate, acceleration)."""
    phi = np.array([[1.0, h, h * h / 2], [0.0, 1.0, h], [0.0, 0.0, 1.0]])
    gamma = np.array([h ** 3 / 6, h * h / 2, h])
    return phi, gamma


def kinematics(beta):
    """For angles beta (n, 3): R (n, 3, 3), dR/dbeta_i (n, 3, 3, 3; i last but two: [n, i]),
    E (n, 3, 3) and dE/dbeta_i (n, 3, 3, 3), for R = Rx(roll) Ry(pitch) Rz(yaw) and
    w_body = E beta' (columns of E: (cos p cos y, -cos p sin y, sin p), (sin y, cos y, 0),
    (0, 0, 1))."""
    beta = np.atleast_2d(beta)
    n = len(beta)
    ca, sa = np.cos(beta[:, 0]), np.sin(beta[:, 0])
    cb, sb = np.cos(beta[:, 1]), np.sin(beta[:, 1])
    cc, sc = np.cos(beta[:, 2]), np.sin(beta[:, 2])

    def matrix(*rows):
        m = np.empty((n, 3, 3))
        for i, row in enumerate(rows):
            for j, value in enumerate(row):
                m[:, i, j] = value
        return m

    rx = matrix((1.0, 0.0, 0.0), (0.0, ca, -sa), (0.0, sa, ca))
    ry = matrix((cb, 0.0, sb), (0.0, 1.0, 0.0), (-sb, 0.0, cb))
    rz = matrix((cc, -sc, 0.0), (sc, cc, 0.0), (0.0, 0.0, 1.0))
    drx = matrix((0.0, 0.0, 0.0), (0.0, -sa, -ca), (0.0, ca, -sa))
    dry = matrix((-sb, 0.0, cb), (0.0, 0.0, 0.0), (-cb, 0.0, -sb))
    drz = matrix((-sc, -cc, 0.0), (cc, -sc, 0.0), (0.0, 0.0, 0.0))
    r = rx @ ry @ rz
    dr = np.stack([drx @ ry @ rz, rx @ dry @ rz, rx @ ry @ drz], axis=1)
    e = matrix((cb * cc, sc, 0.0), (-cb * sc, cc, 0.0), (sb, 0.0, 1.0))
    de = np.zeros((n, 3, 3, 3))
    de[:, 1] = matrix((-sb * cc, 0.0, 0.0), (sb * sc, 0.0, 0.0), (cb, 0.0, 0.0))
    de[:, 2] = matrix((-cb * sc, cc, 0.0), (-cb * cc, -sc, 0.0), (0.0, 0.0, 0.0))
    return r, dr, e, de


class Predictive:
    """The predictive cueing of docs/cueing.md for the parameters `p` (a dict by the FMU's
    names, e.g. `start_values(fmu)`)."""

    def __init__(self, p):
        self.g = p["g"]
        vec = lambda name: np.array([p[f"{name}[{k}]"] for k in (1, 2, 3)])  # noqa: E731
        self.head, self.neutral = vec("head"), vec("neutral")
        self.base = np.array([[p[f"B[{k},{i}]"] for i in (1, 2, 3)] for k in range(1, 7)])
        self.platform = np.array([[p[f"A[{k},{i}]"] for i in (1, 2, 3)] for k in range(1, 7)])
        lmin = np.array([p[f"lmin[{k}]"] for k in range(1, 7)])
        lmax = np.array([p[f"lmax[{k}]"] for k in range(1, 7)])
        self.rate_limit, self.tilt_max = p["tilt.rateLimit"], p["tilt.max"]
        self.period, self.horizon, self.trust = p["mpc.period"], p["mpc.horizon"], p["mpc.trust"]
        self.trend = p["mpc.trend"]
        self.leg_speed, self.max_step = p["mpc.legSpeed"], p["solver.maxStep"]
        # The grid, the blocks, and per channel the deviation (position, rate, acceleration)
        # at each point per block's unit jerk.
        self.h = self.horizon * (RATIO - 1.0) / (RATIO ** STEPS - 1.0) * RATIO ** np.arange(STEPS)
        self.tau = np.concatenate([[0.0], np.cumsum(self.h)])
        self.block = np.repeat(np.arange(N_BLOCKS), BLOCKS)
        self.steps = [cubic_step(hj) for hj in self.h]
        self.sens = np.zeros((STEPS + 1, 3, N_BLOCKS))
        for j, (phi, gamma) in enumerate(self.steps):
            self.sens[j + 1] = phi @ self.sens[j]
            self.sens[j + 1, :, self.block[j]] += gamma
        self.grid_lags = [lag_coefficients(hj) for hj in self.h]
        # The legs' neutral lengths and the plan's bounds on them.
        l0 = np.linalg.norm(self.neutral + self.platform - self.base, axis=1)
        self.leg_low = l0 - STROKE_SHARE * (l0 - lmin - p["margin"])
        self.leg_high = l0 + STROKE_SHARE * (lmax - p["margin"] - l0)
        # The perceived errors' weights (points 1..20 x cues).
        w_f, w_omega = vec("mpc.weight.f"), vec("mpc.weight.omega")
        self.w_cue = np.outer(self.h * np.exp(-self.tau[1:] / self.trust),
                              np.concatenate([w_f / THRESHOLD_F ** 2, w_omega / THRESHOLD_OMEGA ** 2]))
        # The rows that do not depend on the motion: back to neutral (position and rate of P
        # and the yaw at the points 1..20) and the jerks (steps 0..19); their values do.
        rows, weights, self.neutral_index = [], [], []
        w_neutral = self.h * p["mpc.weight.neutral"]
        w_neutral[-1] += 10.0 * p["mpc.weight.neutral"]
        for c in NEUTRAL_CHANNELS:
            for d in (0, 1):
                for j in range(1, STEPS + 1):
                    row = np.zeros((N_BLOCKS, N_CHANNELS))
                    row[:, c] = self.sens[j, d]
                    rows.append(row.ravel())
                    weights.append(w_neutral[j - 1])
                    self.neutral_index.append((j, c, d))
        self.jerk_scale = np.array([1.0, 1.0, 1.0, self.g, self.g, self.g])
        for j in range(STEPS):
            for c in range(N_CHANNELS):
                row = np.zeros((N_BLOCKS, N_CHANNELS))
                row[self.block[j], c] = self.jerk_scale[c]
                rows.append(row.ravel())
                weights.append(self.h[j] * p["mpc.weight.input"])
        self.fixed_rows, self.fixed_weights = np.array(rows), np.array(weights)
        self.fixed_hessian = self.fixed_rows.T @ (self.fixed_weights[:, None] * self.fixed_rows)
        self.neutral_index = tuple(np.array(self.neutral_index).T)

    # -- the commanded motion ----------------------------------------------------------------
    def cues(self, x, jacobian=False):
        """fsim, omegasim (n, 6) at the motions x (n, 6 channels, 3 orders) and, with
        `jacobian`, their Jacobian (n, 6 cues, 6 channels, 3 orders)."""
        x = np.asarray(x).reshape(-1, N_CHANNELS, 3)
        r, dr, e, de = kinematics(x[:, 3:, 0])
        specific = x[:, :3, 2] + self.g * EZ
        dbeta = x[:, 3:, 1]
        y = np.concatenate([np.einsum("nji,nj->ni", r, specific), np.einsum("nij,nj->ni", e, dbeta)], axis=1)
        if not jacobian:
            return y
        jac = np.zeros((len(x), 6, N_CHANNELS, 3))
        jac[:, :3, :3, 2] = np.transpose(r, (0, 2, 1))
        jac[:, 3:, 3:, 1] = e
        jac[:, :3, 3:, 0] = np.einsum("nkji,nj->nik", dr, specific)
        jac[:, 3:, 3:, 0] = np.einsum("nkij,nj->nik", de, dbeta)
        return y, jac

    def legs(self, x):
        """At the motions x (n, 6, 3): the leg lengths (n, 6), their gradient with respect to
        the channels' positions (n, 6 legs, 6) and the legs' speeds J (P', beta') (n, 6)."""
        r, dr, _, _ = kinematics(x[:, 3:, 0])
        arm = self.platform - self.head  # from the head, body frame
        vec = (self.neutral + self.head - self.base)[None] + x[:, None, :3, 0] + np.einsum("nij,kj->nki", r, arm)
        length = np.linalg.norm(vec, axis=2)
        unit = vec / length[..., None]
        grad = np.concatenate([unit, np.einsum("nki,nmij,kj->nkm", unit, dr, arm)], axis=2)
        return length, grad, np.einsum("nkc,nc->nk", grad, x[:, :, 1])

    def outputs(self, x):
        """The FMU's outputs of the command x (6, 3): pose.r, .v, .a, .angles, .angleRates,
        .angleAccelerations, fsim, omegasim (three values each)."""
        p, dp, ddp = x[:3, 0], x[:3, 1], x[:3, 2]
        beta, dbeta, ddbeta = x[3:, 0], x[3:, 1], x[3:, 2]
        r, _, e, de = kinematics(beta)
        r, e, de = r[0], e[0], de[0]
        w = e @ dbeta
        dw = np.einsum("i,ijk,k->j", dbeta, de, dbeta) + e @ ddbeta
        head = self.head
        return {"pose.r": self.neutral + head + p - r @ head, "pose.v": dp - r @ cross(w, head),
                "pose.a": ddp - r @ (cross(w, cross(w, head)) + cross(dw, head)),
                "pose.angles": beta, "pose.angleRates": dbeta, "pose.angleAccelerations": ddbeta,
                "fsim": r.T @ (ddp + self.g * EZ), "omegasim": w}

    # -- one solve -----------------------------------------------------------------------------
    def nominal(self, plan):
        """The last plan (steps x channels) shifted by the period, each step the mean of the
        last plan's jerks over it; zeros for none."""
        out = np.zeros((STEPS, N_CHANNELS))
        if plan is not None:
            for j in range(STEPS):
                a, b = self.tau[j] + self.period, self.tau[j + 1] + self.period
                overlap = np.clip(np.minimum(b, self.tau[1:]) - np.maximum(a, self.tau[:-1]), 0.0, None)
                out[j] = overlap @ plan / (self.tau[j + 1] - self.tau[j])
        return out

    def guess(self, f, omega, rate):
        """The vehicle's inputs (f, omega) at the grid's points, guessed as docs/cueing.md says
        (`mpc.trend`): f[1], f[2], omega go on at `rate` (their change over the last solve
        period, per second), by rate T (1 - exp(-tau/T)) within 8 m/s2 and 0.5 rad/s; f[3]
        held; T = 0 holds them all."""
        held = np.concatenate([f, omega])
        if not self.trend > 0.0:
            return np.tile(held, (STEPS + 1, 1))
        reach = self.trend * (1.0 - np.exp(-self.tau / self.trend))
        limit = np.array([8.0, 8.0, 0.0, 0.5, 0.5, 0.5])
        return held + np.clip(np.outer(reach, rate), -limit, limit)

    def solve(self, x, sim_lags, vehicle_lags, f, omega, plan=None, rate=np.zeros(6)):
        """A solve at the command x (6, 3) with the lags now (15 each) and the vehicle's inputs
        now, from the last plan. Returns (plan, info): the new plan (steps x channels of jerks)
        and the correction du (blocks x channels), the objective at du, the inequalities'
        smallest margins per kind (slack units; > 0 inside)."""
        u_nom = self.nominal(plan)
        xs = np.empty((STEPS + 1, N_CHANNELS, 3))
        xs[0] = x
        for j, (phi, gamma) in enumerate(self.steps):
            xs[j + 1] = xs[j] @ phi.T + np.outer(u_nom[j], gamma)
        y, jac = self.cues(xs, jacobian=True)
        dy = np.einsum("nkcd,ndb->nkbc", jac, self.sens).reshape(STEPS + 1, 6, N_UNKNOWNS)
        # The perceived errors at the points 1..20: the simulator's lags on the linearised cues
        # (affine in du), the vehicle's on its guessed inputs (linear between the points).
        guessed = self.guess(f, omega, rate)[:, LAG_CUE]
        sim, dsim, veh = sim_lags.copy(), np.zeros((len(LAG_TAU), N_UNKNOWNS)), vehicle_lags.copy()
        values, rows = np.empty((STEPS, 6)), np.empty((STEPS, 6, N_UNKNOWNS))
        for j, (e, a, b) in enumerate(self.grid_lags):
            sim = e * sim + a * y[j, LAG_CUE] + b * y[j + 1, LAG_CUE]
            dsim = e[:, None] * dsim + a[:, None] * dy[j, LAG_CUE] + b[:, None] * dy[j + 1, LAG_CUE]
            veh = e * veh + a * guessed[j] + b * guessed[j + 1]
            values[j], rows[j] = LAG_SUM @ (sim - veh), LAG_SUM @ dsim
        cue_rows, cue_values, cue_weights = rows.reshape(-1, N_UNKNOWNS), values.ravel(), self.w_cue.ravel()
        fixed_values = np.concatenate([xs[self.neutral_index], (self.jerk_scale * u_nom).ravel()])
        hessian = self.fixed_hessian + cue_rows.T @ (cue_weights[:, None] * cue_rows)
        gradient = cue_rows.T @ (cue_weights * cue_values) + self.fixed_rows.T @ (self.fixed_weights * fixed_values)
        du = cho_solve(cho_factor(hessian), -gradient)
        objective = 0.5 * (np.sum(cue_weights * (cue_values + cue_rows @ du) ** 2)
                           + np.sum(self.fixed_weights * (fixed_values + self.fixed_rows @ du) ** 2))
        du = du.reshape(N_BLOCKS, N_CHANNELS)
        return u_nom + du[self.block], {"du": du, "objective": objective, "hessian": hessian, "gradient": gradient,
                                        "margins": self.margins(xs, y, dy, du, omega)}

    def margins(self, xs, y, dy, du, omega):
        """The smallest margin of each kind of linearised inequality at the correction du, in
        the slack's units, over the constrained points."""
        d = np.einsum("jdb,bc->jcd", self.sens, du)  # the motion's deviation (21, 6, 3)
        at = CONSTRAINED_POINTS
        length, grad, _ = self.legs(xs[at])
        lin = length + np.einsum("nkc,nc->nk", grad, d[at, :, 0])
        speed = np.einsum("nkc,nc->nk", grad, xs[at, :, 1] + d[at, :, 1])
        # The speed's full linearisation: J's directional derivative along the deviation
        # (central differences of J (P', beta') with the rates held).
        eps = 1e-6
        moved = xs[at].copy()
        moved[:, :, 0] += eps * d[at, :, 0]
        up = self.legs(moved)[2]
        moved[:, :, 0] -= 2 * eps * d[at, :, 0]
        full = speed + (up - self.legs(moved)[2]) / (2 * eps)
        rates = y[at, 3:5] + dy[at, 3:5] @ du.ravel()
        angles = xs[at, 3:5, 0] + d[at, 3:5, 0]
        margin = {"leg": np.min(np.minimum(lin - self.leg_low, self.leg_high - lin)),
                  "leg speed": self.leg_speed - np.max(np.abs(speed)),
                  "leg speed (full)": self.leg_speed - np.max(np.abs(full)),
                  "tilt rate": np.min(self.rate_limit + np.abs(omega[:2]) - np.abs(rates)),
                  "tilt rate (relative)": np.min(self.rate_limit - np.abs(rates - omega[:2])),
                  "tilt": self.tilt_max - np.max(np.abs(angles))}
        return {kind: float(value / SLACK_UNIT[kind]) for kind, value in margin.items()}

    # -- a run in Co-Simulation ----------------------------------------------------------------
    def substeps(self, t_i, h):
        """The sub-steps of the simulator's perception over the communication step from t_i of
        length h: equal, of at most solver.maxStep, a step that exceeds a multiple of it by
        round-off (1e-12 relative) taking no extra one: one for h = solver.maxStep = 1 ms."""
        return max(1, math.ceil(h / self.max_step * (1 - 1e-12)))

    def simulate(self, t, inputs, hold=False, allow_active=False, perturb=None, fine=8, substeps=None):
        """The FMU's Co-Simulation run over the communication points `t` (uniform from 0; the
        period a whole number of steps) with the vehicle's inputs `inputs` (rows: f[1..3],
        omega[1..3]) set at each point and, unless `hold`, following their chord to the next.
        `perturb(k, info)`: returns the correction to use instead of solve k's du (info: its
        `du`, `hessian`, `gradient`; to measure how an inexact solver moves the outputs).
        `fine`: sub-steps of the reference simulator perception. `substeps(t_i, h)`: the number
        of sub-steps of the simulator's perception over the step from t_i (default:
        `Predictive.substeps`). Returns a dict of arrays by the FMU's output names at the
        points (and `perceived.fsim.fine[k]`, `perceived.omegasim.fine[k]`), `lags` (rows: the
        vehicle's 15 lags, the simulator's, the fine ones), `solves` (each solve's info and
        time) and `margins` (per kind the smallest over the run)."""
        t = np.asarray(t, dtype=float)
        inputs = np.asarray(inputs, dtype=float)
        h = t[1] - t[0]
        if abs(t[0]) > 0 or np.max(np.abs(np.diff(t) - h)) > 1e-12:
            raise ValueError("simulate: the points must be uniform from 0")
        every = int(round(self.period / h))
        if abs(every * h - self.period) > 1e-12:
            raise ValueError("simulate: mpc.period must be a whole number of communication steps")
        if substeps is None:
            substeps = self.substeps
        x = np.zeros((N_CHANNELS, 3))
        sim, sim_fine, veh = lags_at_rest(self.g), lags_at_rest(self.g), lags_at_rest(self.g)
        plan, solves, margins = None, [], {}
        names = ["pose.r", "pose.v", "pose.a", "pose.angles", "pose.angleRates", "pose.angleAccelerations",
                 "fsim", "omegasim"]
        rows = {n: np.empty((len(t), 3)) for n in names}
        perceived = np.empty((len(t), 18))
        lags = np.empty((len(t), 45))
        coefficients = {}

        def coefficient(length):
            if length not in coefficients:
                coefficients[length] = lag_coefficients(length)
            return coefficients[length]

        def record(i):
            for n, value in self.outputs(x).items():
                rows[n][i] = value
            perceived[i] = np.concatenate([LAG_SUM @ veh, LAG_SUM @ sim, LAG_SUM @ sim_fine])
            lags[i] = np.concatenate([veh, sim, sim_fine])

        def along(x0, jerk, n):
            """The motion at the n equal sub-steps' ends of the step, and their cues."""
            phi, gamma = cubic_step(h / n)
            points = np.empty((n + 1, N_CHANNELS, 3))
            points[0] = x0
            for k in range(n):
                points[k + 1] = points[k] @ phi.T + np.outer(jerk, gamma)
            return self.cues(points)

        record(0)
        for i in range(len(t) - 1):
            if i % every == 0:
                # The inputs' change since the last solve, per second (none at the first).
                rate = (inputs[i] - inputs[i - every]) / self.period if i >= every else np.zeros(6)
                plan, info = self.solve(x, sim, veh, inputs[i, :3], inputs[i, 3:], plan, rate)
                if perturb is not None:
                    du = perturb(len(solves), info)
                    plan = plan + (du - info["du"])[self.block]
                info["time"] = t[i]
                solves.append(info)
                for kind, value in info["margins"].items():
                    margins[kind] = min(margins.get(kind, np.inf), value)
                tight = {k: v for k, v in info["margins"].items() if v <= 0}
                if tight and not allow_active:
                    raise ConstraintActive(f"t = {t[i]:.3f} s: inequalities active at the unconstrained minimiser "
                                           f"(margins in slack units): {tight}")
            fine_cues = along(x, plan[0], fine)
            n = substeps(t[i], h)
            cues = fine_cues[::fine // n] if fine % n == 0 else along(x, plan[0], n)
            for lag_name, m, c in (("sim", n, cues), ("fine", fine, fine_cues)):
                e, a, b = coefficient(h / m)
                lag = sim if lag_name == "sim" else sim_fine
                for k in range(m):
                    lag = e * lag + a * c[k, LAG_CUE] + b * c[k + 1, LAG_CUE]
                if lag_name == "sim":
                    sim = lag
                else:
                    sim_fine = lag
            phi, gamma = cubic_step(h)
            x = x @ phi.T + np.outer(plan[0], gamma)
            then = inputs[i] if hold else inputs[i + 1]
            e, a, b = coefficient(h)
            veh = e * veh + a * inputs[i, LAG_CUE] + b * then[LAG_CUE]
            record(i + 1)
        result = {"time": t, "solves": solves, "margins": margins, "lags": lags}
        for n in names:
            for k in range(3):
                result[f"{n}[{k + 1}]"] = rows[n][:, k]
        for j, n in enumerate(["f", "omega", "fsim", "omegasim", "fsim.fine", "omegasim.fine"]):
            for k in range(3):
                result[f"perceived.{n}[{k + 1}]"] = perceived[:, 3 * j + k]
        return result
