"""SPEC §12's perception model, written from SPEC alone (an oracle for the StewartCueing FMU's
`perceived.*` outputs): per cabin axis

    otoliths  OTO(s) = (tau_oa s + 1) / ((tau_oL s + 1)(tau_oS s + 1)),  10 s, 5 s, 0.016 s
    canals    SCC(s) = tau_1 tau_a s^2 / ((tau_1 s + 1)(tau_2 s + 1)(tau_a s + 1)),  5.73, 0.005, 80 s

Both are strictly proper with distinct real poles -1/tau_i, so each is a sum of first-order
lags, H(s) = sum_i r_i / (s + a_i), a_i = 1/tau_i, with the residues

    r_i = N(-a_i) / (tau_i prod_{j != i} (1 - tau_j / tau_i))

(N the numerator; D(s) = prod_j (tau_j s + 1) = tau_i (s + a_i) prod_{j != i} (tau_j s + 1)).
That modal form gives everything here in closed form: the frequency response, the step
response sum_i (r_i / a_i)(1 - exp(-a_i t)), the response to sin(omega t), and an exact
simulator for inputs that are linear between samples (a first-order hold: each mode's update
over a step is solved in closed form, no integration error). The step responses are also
written out by hand (`otolith_step`, `canal_step`) from the partial fractions of H(s)/s.

Initial state (SPEC §12): at rest with f = g ez. The otolith filters start at their steady state
for the rest value of their input (g on z, 0 on x and y: each mode x_i = u_rest / a_i, so the
output is u_rest), the canals at zero."""

import math

import numpy as np

#: SPEC §12's time constants, s.
TAU_OA, TAU_OL, TAU_OS = 10.0, 5.0, 0.016
TAU_1, TAU_2, TAU_A = 5.73, 0.005, 80.0


class Lags:
    """A strictly proper N(s) / prod_i (tau_i s + 1) with distinct `taus`, as the sum of its
    first-order modes. `numerator`: N's coefficients, highest power first."""

    def __init__(self, numerator, taus):
        self.numerator = np.asarray(numerator, dtype=float)
        self.taus = np.asarray(taus, dtype=float)
        if len(self.numerator) > len(self.taus):
            raise ValueError("Lags: the transfer function must be strictly proper")
        self.rates = 1.0 / self.taus
        self.residues = np.array([
            np.polyval(self.numerator, -a) / (tau * np.prod([1.0 - t / tau for t in self.taus if t != tau]))
            for a, tau in zip(self.rates, self.taus)])

    def response(self, omega):
        """H(j omega) (complex), from N and D directly (not the modes)."""
        s = 1j * np.asarray(omega, dtype=float)
        den = np.ones_like(s)
        for tau in self.taus:
            den = den * (tau * s + 1.0)
        return np.polyval(self.numerator, s) / den

    def gain_at_rest(self):
        """H(0)."""
        return float(np.polyval(self.numerator, 0.0))

    def step(self, t):
        """The response to a unit step at t = 0 from rest (0 before)."""
        t = np.asarray(t, dtype=float)
        tp = np.maximum(t, 0.0)
        y = sum(r / a * -np.expm1(-a * tp) for r, a in zip(self.residues, self.rates))
        return np.where(t > 0, y, 0.0)

    def sine(self, t, omega):
        """The response to sin(omega t) switched on at t = 0, from rest: per mode the steady
        state Im(exp(j omega t) / (a + j omega)) plus the transient omega exp(-a t)/(a^2 + omega^2)
        that makes it start at zero."""
        t = np.asarray(t, dtype=float)
        tp = np.maximum(t, 0.0)
        y = sum(r * (np.imag(np.exp(1j * omega * tp) / (a + 1j * omega))
                     + omega * np.exp(-a * tp) / (a * a + omega * omega))
                for r, a in zip(self.residues, self.rates))
        return np.where(t > 0, y, 0.0)

    def rest_state(self, u_rest):
        """The modes' steady state for a constant input `u_rest` (output u_rest H(0))."""
        return u_rest / self.rates

    def simulate(self, t, u, x0=None):
        """The output at the sample times `t` for the input `u` linear between samples (a
        first-order hold). A time given twice is a jump of the input there (the modes do not
        move over it). `x0`: the modes' state at t[0] (default zero; `rest_state(u0)` for a
        filter at its steady state). Exact: over a step h with u = u0 + m s, each mode
        x' = -a x + u is x(h) = alpha (1 - e^{-a h}) + beta h + x(0) e^{-a h},
        beta = m / a, alpha = (u0 - beta) / a."""
        t = np.asarray(t, dtype=float)
        u = np.asarray(u, dtype=float)
        if t.shape != u.shape or t.ndim != 1:
            raise ValueError("simulate: t and u must be 1-D arrays of the same length")
        h = np.diff(t)
        if np.any(h < 0):
            raise ValueError("simulate: the times must not decrease")
        x = np.zeros(len(self.rates)) if x0 is None else np.array(x0, dtype=float)
        states = np.empty((len(t), len(self.rates)))
        states[0] = x
        slope = np.divide(np.diff(u), h, out=np.zeros_like(h), where=h > 0)
        for i, a in enumerate(self.rates):
            decay = np.exp(-a * h)
            grow = -np.expm1(-a * h)
            beta = slope / a
            alpha = (u[:-1] - beta) / a
            forced = alpha * grow + beta * h
            xi = x[i]
            column = states[:, i]
            for k in range(len(h)):
                xi = forced[k] + xi * decay[k]
                column[k + 1] = xi
        return states @ self.residues


#: SPEC §12's otolith model, per axis (specific force, gravity included; unit gain at rest).
OTOLITH = Lags([TAU_OA, 1.0], [TAU_OL, TAU_OS])
#: SPEC §12's semicircular canal model, per axis (angular velocity).
CANAL = Lags([TAU_1 * TAU_A, 0.0, 0.0], [TAU_1, TAU_2, TAU_A])


def otolith_step(t):
    """OTO's unit step response from rest, by hand: OTO(s)/s = 1/s + B/(s + 1/tau_oL) +
    C/(s + 1/tau_oS) with B = (tau_oa - tau_oL)/(tau_oL - tau_oS) and
    C = (tau_oa - tau_oS)/(tau_oS - tau_oL) (1 + B + C = 0: it starts at 0)."""
    t = np.asarray(t, dtype=float)
    b = (TAU_OA - TAU_OL) / (TAU_OL - TAU_OS)
    c = (TAU_OA - TAU_OS) / (TAU_OS - TAU_OL)
    tp = np.maximum(t, 0.0)
    return np.where(t > 0, 1.0 + b * np.exp(-tp / TAU_OL) + c * np.exp(-tp / TAU_OS), 0.0)


def canal_step(t):
    """SCC's unit step response from rest, by hand: SCC(s)/s = tau_1 tau_a s / prod (tau_i s + 1)
    has the residue -tau_1 tau_a / prod_{j != i}(tau_i - tau_j) at -1/tau_i, so the response is
    -tau_1 tau_a sum_i exp(-t/tau_i) / prod_{j != i}(tau_i - tau_j) (0 at t = 0, slope 1/tau_2)."""
    t = np.asarray(t, dtype=float)
    tp = np.maximum(t, 0.0)
    taus = (TAU_1, TAU_2, TAU_A)
    y = 0.0
    for i, ti in enumerate(taus):
        others = [tj for j, tj in enumerate(taus) if j != i]
        y = y + np.exp(-tp / ti) / ((ti - others[0]) * (ti - others[1]))
    return np.where(t > 0, -TAU_1 * TAU_A * y, 0.0)


def perceive_f(t, f, rest=(0.0, 0.0, 9.81)):
    """The otoliths' output for the specific force `f` (rows: samples, columns x, y, z) linear
    between the times `t`, the filters starting at their steady state for `rest` (SPEC: g ez)."""
    f = np.asarray(f, dtype=float)
    return np.column_stack([OTOLITH.simulate(t, f[:, k], OTOLITH.rest_state(rest[k])) for k in range(3)])


def perceive_omega(t, omega):
    """The canals' output for the angular velocity `omega` (rows: samples) linear between the
    times `t`, from zero."""
    omega = np.asarray(omega, dtype=float)
    return np.column_stack([CANAL.simulate(t, omega[:, k]) for k in range(3)])


def l1_norm(lags, t_end=2000.0):
    """The integral of |impulse response| (the bound on |output| per unit of |input|), by a
    fine quadrature on a log grid."""
    t = np.concatenate([[0.0], np.logspace(-6, math.log10(t_end), 200001)])
    h = np.abs(sum(r * np.exp(-a * t) for r, a in zip(lags.residues, lags.rates)))
    return float(np.sum(0.5 * (h[1:] + h[:-1]) * np.diff(t)))
