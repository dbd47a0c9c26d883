"""The Model Exchange Jacobians against central differences, one loop for every test that
checks them (test_model_exchange.py, test_drives.py, test_hydraulics.py)."""

import numpy as np


def largest_error(m, x, u, input_vrs, output_vrs, state_steps, input_steps, per_row=False):
    """The largest relative difference between fmi2GetDirectionalDerivative and central
    differences (fmi2GetDerivatives and fmi2GetReal of `output_vrs`, each known moved by
    +-its step) of the derivatives and of the outputs, with respect to every state (`x`,
    steps `state_steps`) and to the inputs `input_vrs` (`u`, steps `input_steps`), at the
    states `x` and the inputs `u` of the PlatformModel `m` (left there). Relative to the
    largest entry of the Jacobian, or of each row (`per_row`: rows of very different sizes,
    pressures' rates beside accelerations)."""
    worst = 0.0
    m.set_states(x)
    m.fmu.setReal(input_vrs, list(u))
    for knowns, at, steps in ((m.all_state_vrs, x, state_steps), (input_vrs, u, input_steps)):
        exact = m.jacobian(m.all_derivative_vrs, knowns)
        exact_out = m.jacobian(output_vrs, knowns)
        fd, fd_out = np.zeros_like(exact), np.zeros_like(exact_out)
        for j in range(len(knowns)):
            values = []
            for sign in (1, -1):
                moved = np.array(at, dtype=float)
                moved[j] += sign * steps[j]
                if knowns is input_vrs:
                    m.fmu.setReal(input_vrs, list(moved))
                else:
                    m.set_states(moved)
                values.append((m.derivatives(), np.array(m.fmu.getReal(output_vrs))))
            m.set_states(x)
            m.fmu.setReal(input_vrs, list(u))
            fd[:, j] = (values[0][0] - values[1][0]) / (2 * steps[j])
            fd_out[:, j] = (values[0][1] - values[1][1]) / (2 * steps[j])
        for a, b in ((exact, fd), (exact_out, fd_out)):
            if per_row:
                rows = np.max(np.abs(a), axis=1, keepdims=True)
                worst = max(worst, float(np.max(np.abs(a - b) / np.maximum(rows, 1e-12))))
            else:
                worst = max(worst, float(np.max(np.abs(a - b))) / max(float(np.max(np.abs(a))), 1e-12))
    return worst
