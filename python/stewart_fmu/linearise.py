"""Linearisation of the Stewart platform through the FMU's exact directional derivatives
(fmi2GetDirectionalDerivative, Model Exchange interface): why the loaded platform is unstable
and how much feedback it needs.

About an operating point (default: the neutral equilibrium with the equilibrium leg forces,
in the paper's non-dimensional units) it

1. builds the 24x24 Jacobian of the special-form derivatives and the 24x6 input matrix from
   directional derivatives, and the output matrices of the leg lengths and rates;
2. reduces the 24 redundant states to the 12 of the six degrees of freedom: position r,
   small rotation phi (e_a -> e_a + phi x e_a), velocity v and angular velocity Omega
   (inertial components), x_12 = (r, phi, v, Omega);
3. prints A, B, C (leg lengths), D, the eigenvalues with their mode shapes named;
4. closes the paper's loop u = u_eq + G (l^p - l) + D_rate (ldot^p - ldot) and prints the
   closed-loop eigenvalues, the critical gain (largest real part <= 1e-9 above it), and
   writes a root-locus plot of the eigenvalues against G.

    python examples/linearise.py [--si] [--gain G] [--damping D] [--output folder]

`linearise()` is also used by tests/python/test_linearisation.py.
"""

import argparse
import json
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model

from .core import EQUILIBRIUM_FORCE, LEGS, PLATFORM_FMU, default_stand, fmu_file, set_values, stand_parameters

DOF = ["surge x", "sway y", "heave z", "roll", "pitch", "yaw"]


class PlatformModel:
    """A Model Exchange instance of StewartPlatform at a fixed operating point."""

    def __init__(self, parameters, forces, fmu=PLATFORM_FMU):
        fmu = fmu_file(fmu)
        self.md = read_model_description(fmu)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.fmu = FMU2Model(guid=self.md.guid, unzipDirectory=extract(str(fmu)),
                             modelIdentifier=self.md.modelExchange.modelIdentifier, instanceName="linearise")
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        set_values(self.fmu, self.md, parameters)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.fmu.newDiscreteStates()
        self.fmu.enterContinuousTimeMode()
        self.force_vrs = [self.vr[f"F[{k}]"] for k in LEGS]
        self.fmu.setReal(self.force_vrs, [float(f) for f in forces])
        # The 24 special-form states; the FMU's last two states, work.F and work.dissipated,
        # are quadratures that do not act back on the motion.
        self.nx = len(self.md.derivatives)
        self.all_state_vrs = [d.variable.derivative.valueReference for d in self.md.derivatives]
        self.all_derivative_vrs = [d.variable.valueReference for d in self.md.derivatives]
        self.state_vrs = self.all_state_vrs[:24]
        self.derivative_vrs = self.all_derivative_vrs[:24]

    def states(self):
        from ctypes import c_double
        x = (c_double * self.nx)()
        self.fmu.getContinuousStates(x, self.nx)
        return np.array(x)

    def set_states(self, x):
        from ctypes import c_double
        self.fmu.setContinuousStates((c_double * self.nx)(*x), self.nx)

    def derivatives(self):
        from ctypes import c_double
        dx = (c_double * self.nx)()
        self.fmu.getDerivatives(dx, self.nx)
        return np.array(dx)

    def jacobian(self, unknowns, knowns):
        """Columns of d(unknowns)/d(knowns), one directional derivative per known."""
        return np.column_stack([self.fmu.getDirectionalDerivative(unknowns, [k], [1.0]) for k in knowns])

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def skew(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def reduction(x):
    """T (24x12) maps (dr, phi, dv, dOmega) to a change of the redundant state at x, P (12x24)
    maps back; P T = I on an orthonormal frame."""
    e = [x[6 + 3 * a: 9 + 3 * a] for a in range(3)]
    d = [x[15 + 3 * a: 18 + 3 * a] for a in range(3)]
    omega = 0.5 * sum(np.cross(e[a], d[a]) for a in range(3))  # d_a = Omega x e_a
    t = np.zeros((24, 12))
    p = np.zeros((12, 24))
    t[0:3, 0:3] = np.eye(3)
    t[3:6, 6:9] = np.eye(3)
    p[0:3, 0:3] = np.eye(3)
    p[6:9, 3:6] = np.eye(3)
    for a in range(3):
        rows_e, rows_d = slice(6 + 3 * a, 9 + 3 * a), slice(15 + 3 * a, 18 + 3 * a)
        t[rows_e, 3:6] = -skew(e[a])                   # de_a = phi x e_a
        t[rows_d, 3:6] = -skew(omega) @ skew(e[a])     # dd_a = Omega x (phi x e_a) + dOmega x e_a
        t[rows_d, 9:12] = -skew(e[a])
        p[3:6, rows_e] = 0.5 * skew(e[a])              # phi = 1/2 sum e_a x de_a
        p[9:12, rows_d] = 0.5 * skew(e[a])             # dOmega = 1/2 sum e_a x (dd_a - Omega x de_a)
        p[9:12, rows_e] = -0.5 * skew(e[a]) @ skew(omega)
    return t, p


def mode_name(vector):
    """Name a mode from the position part of its eigenvector (r, phi), lengths and angles in
    comparable units near the default stand."""
    amplitude = np.abs(vector[:6])
    if amplitude.max() == 0:
        return "-"
    weights = amplitude / amplitude.max()
    parts = [DOF[i] for i in np.argsort(-weights) if weights[i] > 0.3]
    return " + ".join(parts[:3])


def linearise(nondimensional=True, fmu=PLATFORM_FMU):
    """The 12-state linear model about the neutral equilibrium."""
    parameters = stand_parameters(nondimensional=nondimensional)
    stand = default_stand()
    u_eq = EQUILIBRIUM_FORCE * (1.0 if nondimensional else stand["M"] * stand["g"])
    model = PlatformModel(parameters, [u_eq] * 6, fmu=fmu)
    x0 = model.states()[:24]
    residual = np.max(np.abs(model.derivatives()[:24]))
    j = model.jacobian(model.derivative_vrs, model.state_vrs)
    b_full = model.jacobian(model.derivative_vrs, model.force_vrs)
    leg_vrs = [model.vr[f"l[{k}]"] for k in LEGS]
    rate_vrs = [model.vr[f"ldot[{k}]"] for k in LEGS]
    c_legs_full = model.jacobian(leg_vrs, model.state_vrs)
    c_rates_full = model.jacobian(rate_vrs, model.state_vrs)
    d_legs = model.jacobian(leg_vrs, model.force_vrs)
    model.free()
    t, p = reduction(x0)
    return {
        "A": p @ j @ t,
        "B": p @ b_full,
        "C": c_legs_full @ t,
        "C_rates": c_rates_full @ t,
        "D": d_legs,
        "x0": x0,
        "equilibrium_residual": residual,
        "u_eq": u_eq,
    }


def closed_loop(lin, gain, damping=0.0):
    """A of u = u_eq + G (l^p - l) + D (ldot^p - ldot) about the same point."""
    return lin["A"] - lin["B"] @ (gain * lin["C"] + damping * lin["C_rates"])


def max_real_part(a):
    return float(np.max(np.linalg.eigvals(a).real))


def critical_gain(lin, damping=0.0, lo=0.0, hi=10.0, threshold=1e-9):
    """Smallest G with every real part <= threshold (bisection; stable above it)."""
    assert max_real_part(closed_loop(lin, lo, damping)) > threshold
    assert max_real_part(closed_loop(lin, hi, damping)) <= threshold
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if max_real_part(closed_loop(lin, mid, damping)) > threshold:
            lo = mid
        else:
            hi = mid
    return hi


def eigen_table(a):
    values, vectors = np.linalg.eig(a)
    order = np.argsort(-values.real)
    return [(values[i], mode_name(vectors[:, i])) for i in order]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--si", action="store_true", help="SI units instead of the paper's non-dimensional units")
    parser.add_argument("--gain", type=float, default=2.0, help="feedback gain G for the closed-loop table")
    parser.add_argument("--damping", type=float, default=0.0, help="rate gain D for the closed-loop table")
    parser.add_argument("--output", default="output", help="folder for the root-locus plot and linearisation.json")
    args = parser.parse_args()
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    units = "SI" if args.si else "non-dimensional (R_b, M g, sqrt(R_b/g))"
    lin = linearise(nondimensional=not args.si)
    np.set_printoptions(precision=4, suppress=True, linewidth=160)
    print(f"operating point: neutral pose, every leg at the equilibrium force {lin['u_eq']:.6g}; units {units}")
    print(f"|dx/dt| at the operating point: {lin['equilibrium_residual']:.1e}")
    print("state x = (x, y, z, phi_x, phi_y, phi_z, vx, vy, vz, Omega_x, Omega_y, Omega_z), inputs u = leg forces")
    print("A =\n", lin["A"])
    print("B =\n", lin["B"])
    print("C (leg lengths) =\n", lin["C"])
    print("D =\n", lin["D"])
    print("\nopen loop (constant leg forces): eigenvalues and modes")
    for value, name in eigen_table(lin["A"]):
        print(f"  {value.real:+.6f} {value.imag:+.6f}i   {name}")
    g_c = critical_gain(lin, damping=args.damping)
    print(f"\ncritical gain (D = {args.damping}): G_c = {g_c:.6f}")
    print(f"closed loop with G = {args.gain}, D = {args.damping}: eigenvalues and modes")
    for value, name in eigen_table(closed_loop(lin, args.gain, args.damping)):
        print(f"  {value.real:+.6f} {value.imag:+.6f}i   {name}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    gains = np.linspace(0.0, 3.0 * g_c, 241)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    for g in gains:
        ev = np.linalg.eigvals(closed_loop(lin, g, args.damping))
        ax.scatter(ev.real, ev.imag, c=[[g / gains[-1], 0.2, 1 - g / gains[-1]]] * len(ev), s=4)
    ev = np.linalg.eigvals(closed_loop(lin, g_c, args.damping))
    ax.scatter(ev.real, ev.imag, c="k", s=16, label=f"G = G_c = {g_c:.3f}")
    ax.axvline(0.0, color="grey", lw=0.8)
    ax.set(xlabel="real part", ylabel="imaginary part",
           title=f"Root locus, G from 0 (blue) to {gains[-1]:.2f} (red), D = {args.damping}")
    ax.legend()
    for damping in sorted({0.0, args.damping, 0.5}):
        ax2.plot(gains, [max_real_part(closed_loop(lin, g, damping)) for g in gains], label=f"D = {damping}")
    ax2.axvline(g_c, color="k", ls="--", lw=0.8, label=f"G_c = {g_c:.3f} (D = {args.damping})")
    ax2.axhline(0.0, color="grey", lw=0.8)
    ax2.set(xlabel="feedback gain G", ylabel="largest real part of the closed-loop eigenvalues",
            title="Stability against the gain")
    ax2.legend()
    fig.tight_layout()
    fig.savefig(out / "root_locus.png", dpi=120)
    (out / "linearisation.json").write_text(json.dumps({
        "units": units,
        "open_loop": [[v.real, v.imag, n] for v, n in eigen_table(lin["A"])],
        "critical_gain": g_c,
        "A": lin["A"].tolist(),
        "B": lin["B"].tolist(),
        "C": lin["C"].tolist(),
    }, indent=1))
    print(f"\nwrote {out / 'root_locus.png'} and {out / 'linearisation.json'}")


if __name__ == "__main__":
    main()
