"""The electric drives (docs/model.md §9) through the packaged FMUs: holding on the static
model's voltage, dynamic braking after a power loss against the quasi-static descent computed
independently, the heave programme with the controller in voltage mode (Python master and
libcosim on StewartSystemDrives.ssp), a shorted drive under feedback, FMI 3 = FMI 2 bit for bit,
Model Exchange against Co-Simulation, exact directional derivatives with respect to the
currents and voltages."""

import math

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from stewart_fmu import PLATFORM_FMU, Platform
from stewart_fmu import drives as dr
from stewart_fmu.cosim import CONTROLLER_FMU, SYSTEM_DRIVES_SSP
from stewart_fmu.workspace import static_rest_height, stop_defaults
from oracles import drives as oracle
from test_fmi3 import PLATFORM3, Fmu3
from central_differences import largest_error

pytestmark = pytest.mark.quick

P = dr.drive_parameters()
I_HOLD, U_HOLD = oracle.holding(P)


def balance(c):
    return c["E"] - c["E"][0] - (c["work.F"] + c["work.electric"] - c["work.dissipated"])


def test_the_holding_voltage_holds_the_stand_at_the_static_models_current():
    c, _, status = dr.holding_run((I_HOLD, U_HOLD), 3.0)
    drift = np.max(np.abs(c["r[3]"] - c["r[3]"][0]))
    current = max(np.max(np.abs(c[f"I[{k}]"] - I_HOLD)) for k in dr.LEGS)
    print(f"holding at U = {U_HOLD:.6f} V: drift {drift:.1e} m over 3 s, currents within {current:.1e} A of the static "
          f"model's {I_HOLD:.6f} A; electric power {6 * U_HOLD * I_HOLD:.1f} W, all of it R I^2")
    assert status == "ok"
    assert drift < 1e-9 and current < 1e-6
    assert abs(c["work.electric"][-1] - 6 * U_HOLD * I_HOLD * 3.0) < 1e-6 * c["work.electric"][-1]


def test_dynamic_braking_lowers_the_platform_at_the_quasi_static_speed():
    """U = 0 from t = 0.5 s (windings shorted): the platform sinks at the speed at which each
    leg's braking force N^2 (k_t k_e / R + D) l' holds its share of the weight, computed here
    from the stand's geometry; it lands on its stops softly and rests at the static solution.
    The same power loss with ideal force actuators falls."""
    c, messages, status = dr.power_loss((I_HOLD, U_HOLD), t_loss=0.5, t_end=16.0, h=0.01)
    assert status == "ok"
    t, z, vz = c["time"], c["r[3]"], c["v[3]"]
    landing = next(float(m.split()[2].rstrip(":")) for _, _, m in messages if "reached its lower end stop" in m)
    steady = (t > 1.0) & (t < landing - 0.2)
    expected = np.array([oracle.quasi_static_descent_rate(zi, P) for zi in z[steady]])
    error = np.max(np.abs(vz[steady] / expected - 1.0))
    lmin, _, stiffness, _ = stop_defaults()
    z_rest, _ = static_rest_height(stiffness, lmin)
    falling, _, _ = dr.power_loss_forces(t_loss=0.5, t_end=1.5, h=1e-3)
    braked_peak, fall_peak = float(np.max(c["der(v[3])"])), float(np.max(falling["der(v[3])"]))
    residual = float(np.max(np.abs(balance(c))))
    print(f"dynamic braking: heave rate {vz[steady][0] * 1e3:.3f} .. {vz[steady][-1] * 1e3:.3f} mm/s, within "
          f"{error:.1e} of the quasi-static rate; on the stops at t = {landing:.3f} s; rest z = {z[-1]:.9f} m (static "
          f"solution {z_rest:.9f}); peak deceleration {braked_peak:.2f} m/s2 against {fall_peak:.1f} m/s2 for the "
          f"falling platform with ideal force actuators; energy balance residual {residual:.1e} J of "
          f"{c['work.dissipated'][-1]:.0f} J dissipated")
    assert error < 1e-3
    assert 10.0 < landing < 15.0
    assert abs(z[-1] - z_rest) < 1e-6
    assert braked_peak < 0.02 * fall_peak
    assert residual < 1e-3


def test_voltage_commands_follow_the_heave_programme():
    """The default controller in voltage mode (drive = 1 in both), 10 s at 1 ms: every leg
    within a millimetre of its programme; voltages within Umax, currents within three times
    the holding current; over the last period the electric energy supplied equals the energy
    lost (a periodic motion stores nothing)."""
    c, errors, status = dr.heave_closed_loop(I_HOLD, 10.0, record=[f"U[{k}]" for k in dr.LEGS])
    assert status == "ok"
    voltages = np.concatenate([c[f"U[{k}]"] for k in dr.LEGS])
    currents = np.concatenate([c[f"I[{k}]"] for k in dr.LEGS])
    period = 2 * math.pi / 2.5573423705088842
    t = c["time"]
    i0 = int(np.searchsorted(t, t[-1] - period))
    supplied = c["work.electric"][-1] - c["work.electric"][i0]
    lost = c["work.dissipated"][-1] - c["work.dissipated"][i0]
    stored = c["E"][-1] - c["E"][i0]
    print(f"heave programme with voltage commands: largest leg error {np.max(errors) * 1e3:.4f} mm; U "
          f"{voltages.min():.1f} .. {voltages.max():.1f} V, I {currents.min():.2f} .. {currents.max():.2f} A; last "
          f"period: {supplied:.1f} J supplied, {lost:.1f} J lost, {stored:.1f} J stored")
    assert np.max(errors) < 1e-3
    assert np.max(np.abs(voltages)) <= 300.0 and np.max(np.abs(currents)) < 3 * I_HOLD
    assert abs(supplied - lost - stored) < 1e-6 * supplied
    assert abs(stored) < 0.05 * supplied


def test_libcosim_runs_the_drive_system_from_its_ssp():
    """libcosim loads target/fmu/StewartSystemDrives.ssp (parameter bindings drive = 1 and the
    holding current) and runs the loop 5 s at 1 ms: the platform follows the programme."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    vrp = {v.name: v.valueReference for v in read_model_description(str(PLATFORM_FMU)).modelVariables}
    vrc = {v.name: v.valueReference for v in read_model_description(str(CONTROLLER_FMU)).modelVariables}
    execution = CosimExecution.from_ssp_file(ssp_path=str(SYSTEM_DRIVES_SSP), step_size=1_000_000)
    index = {(s.name.decode() if isinstance(s.name, bytes) else s.name): s.index for s in execution.slave_infos()}
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    worst, peak = 0.0, 0.0
    for _ in range(5000):
        assert execution.step()
        l = observer.last_real_values(slave_index=index["platform"], variable_references=[vrp[f"l[{k}]"] for k in dr.LEGS])
        lp = observer.last_real_values(slave_index=index["controller"],
                                       variable_references=[vrc[f"lp[{k}]"] for k in dr.LEGS])
        i = observer.last_real_values(slave_index=index["platform"], variable_references=[vrp[f"I[{k}]"] for k in dr.LEGS])
        worst = max(worst, float(np.max(np.abs(np.array(l) - np.array(lp)))))
        peak = max(peak, float(np.max(np.abs(i))))
    print(f"libcosim on StewartSystemDrives.ssp, 5 s at 1 ms: largest leg error {worst * 1e3:.3f} mm, currents up to "
          f"{peak:.1f} A")
    # libcosim exchanges the values after both components stepped (a one-step delay).
    assert worst < 2e-3
    assert peak > I_HOLD


def test_a_shorted_drive_brakes_its_leg_instead_of_dropping_it():
    """Leg 1's voltage to 0 at t = 1 s under feedback: its shorted winding brakes the leg, which
    sinks slowly (back EMF current) and stays off its stop for 6 s; the platform tilts a few
    degrees and the other five follow the programme. With ideal force actuators the failed leg
    (force 0) reaches its stop within 0.4 s (docs: workspace scenario 4)."""
    c, errors, status = dr.failure(I_HOLD, t_fail=1.0, t_end=6.0)
    assert status == "ok"
    after = c["time"] > 1.0005  # the rows after the first step from t = 1 s
    lmin, _, _, _ = stop_defaults()
    sink = np.min(np.diff(c["l[1]"][after]) / np.diff(c["time"][after]))
    tilt = math.degrees(max(np.max(np.abs(c["angles[1]"])), np.max(np.abs(c["angles[2]"]))))
    print(f"leg 1's drive shorted at 1 s: U[1] = {np.max(np.abs(c['U[1]'][after])):.1f} V, its current "
          f"{c['I[1]'][-1]:.2f} A (back EMF), fastest sinking {sink * 1e3:.1f} mm/s, shortest length "
          f"{np.min(c['l[1]']):.4f} m (stop at {lmin} m), largest tilt {tilt:.2f} deg")
    assert np.all(c["U[1]"][after] == 0.0)
    assert np.min(c["l[1]"]) > lmin and np.max(np.abs(c["Fstop[1]"])) == 0.0
    assert np.all(c["I[1]"][after][10:] > 0.0)
    assert tilt < 10.0


def test_fmi3_equals_fmi2_with_drives_bit_for_bit():
    """Voltages from a leg feedback, 2 s at 1 ms: every output of the FMI 3 platform with
    drives equals the FMI 2 platform's bit for bit."""
    start = dr.drive_start(I_HOLD)
    p2 = Platform(parameters=start, name="fmi2-drives")
    p3 = Fmu3(PLATFORM3, name="fmi3-drives", integers={"drive": 1}, reals={"I0": [I_HOLD] * 6})
    names = ["r[3]", "v[1]", "E", "work.electric", "work.dissipated"] + dr.CURRENTS
    l0 = p2.vector("l", 6)
    volts_per_newton = P["motor.R"] / (oracle.transmission(P) * P["motor.kt"])
    for i in range(2000):
        legs, rates = p2.vector("l", 6), p2.vector("ldot", 6)
        assert np.array_equal(legs, p3.get("l")) and np.array_equal(rates, p3.get("ldot"))
        u = U_HOLD * (1 + 0.3 * np.sin(3 * p2.time + np.arange(6))) + volts_per_newton * (2e5 * (l0 - legs) - 2e4 * rates)
        p2.slave.setReal([p2.vr[f"U[{k}]"] for k in dr.LEGS], list(u))
        p3.set("U", u)
        p2.step(1e-3)
        p3.step(1e-3)
        out2 = np.array(p2.get(*names))
        out3 = np.concatenate([[p3.get("r")[2], p3.get("v")[0], p3.get("E"), p3.get("work.electric"),
                                p3.get("work.dissipated")], p3.get("I")])
        assert np.array_equal(out2, out3), f"step {i}: {out2 - out3}"
    print(f"FMI 3 = FMI 2 with drives over 2000 steps; final currents {p3.get('I')} A")
    p2.free()
    p3.free()


def test_model_exchange_with_drives_matches_co_simulation():
    """FMPy's CVODE over the 61 Model Exchange states (the currents among them), braking from
    the start (U = 0, I0 the holding current): the heave after 3 s equals Co-Simulation's."""
    start = {**dr.drive_start(I_HOLD), "stops": False}
    outputs = ["r[3]", "I[1]"]
    me = simulate_fmu(str(PLATFORM_FMU), fmi_type="ModelExchange", start_values=start, stop_time=3.0,
                      output_interval=0.01, relative_tolerance=1e-10, output=outputs)
    cs = simulate_fmu(str(PLATFORM_FMU), fmi_type="CoSimulation", start_values={**start, "solver.relTol": 1e-11},
                      stop_time=3.0, output_interval=0.01, output=outputs)
    dz = float(np.max(np.abs(me["r[3]"] - cs["r[3]"])))
    di = float(np.max(np.abs(me["I[1]"] - cs["I[1]"])))
    print(f"braking from t = 0, Model Exchange (CVODE, rtol 1e-10) against Co-Simulation: heave within {dz:.1e} m, "
          f"current within {di:.1e} A; z fell {cs['r[3]'][0] - cs['r[3]'][-1]:.4f} m")
    assert dz < 1e-6 and di < 1e-3


def test_directional_derivatives_with_drives_match_central_differences():
    """d(derivatives)/d(states) and d(derivatives)/d(U) from fmi2GetDirectionalDerivative
    (the currents' rates, the accelerations through the drives' forces), and of the drives'
    forces actuatorForce, against central differences of fmi2GetDerivatives and fmi2GetReal:
    relative error <= 1e-6."""
    from stewart_fmu.linearise import PlatformModel
    m = PlatformModel(dr.drive_start(I_HOLD), [0.0] * 6)
    u_vrs = [m.vr[f"U[{k}]"] for k in dr.LEGS]
    out_vrs = [m.vr[f"actuatorForce[{k}]"] for k in (1, 4)]
    rng = np.random.default_rng(5)
    x0 = m.states()
    worst = 0.0
    for _ in range(3):
        x = x0 + np.concatenate([rng.normal(0, 0.02, 6), rng.normal(0, 0.02, 9), rng.normal(0, 0.3, 9), [0.0, 0.0],
                                 rng.normal(0, 3.0, 6), [0.0], np.zeros(28)])
        u = U_HOLD + rng.normal(0, 20.0, 6)
        state_steps = [1e-6 if j < 24 else 1e-4 for j in range(len(x))]
        worst = max(worst, largest_error(m, x, u, u_vrs, out_vrs, state_steps, [1e-4] * len(u_vrs)))
    m.free()
    print(f"directional derivatives with drives vs central differences: max relative error {worst:.1e}")
    assert worst <= 1e-6


def test_an_fmu_state_with_drives_continues_bit_for_bit():
    """fmi2GetFMUstate mid-run (currents and electric work in the state), serialized and
    restored into a fresh instance: the run goes on to the bit, as the uninterrupted one."""
    pl = Platform(parameters=dr.drive_start(I_HOLD), name="state-a")
    u = [pl.vr[f"U[{k}]"] for k in dr.LEGS]
    voltages = lambda t: [U_HOLD * (1 + 0.4 * math.sin(4 * t + k)) for k in range(6)]  # noqa: E731
    for _ in range(300):
        pl.slave.setReal(u, voltages(pl.time))
        pl.step(1e-3)
    state, t_saved = pl.slave.serializeFMUstate(pl.slave.getFMUstate()), pl.time
    names = ["r[3]", "angles[1]", "work.electric", "work.dissipated"] + dr.CURRENTS
    reference = []
    for _ in range(300):
        pl.slave.setReal(u, voltages(pl.time))
        pl.step(1e-3)
        reference.append(pl.get(*names))
    other = Platform(parameters=dr.drive_start(I_HOLD), name="state-b")
    other.slave.setFMUstate(other.slave.deSerializeFMUstate(state))
    other.time = t_saved
    restored = []
    for _ in range(300):
        other.slave.setReal(u, voltages(other.time))
        other.step(1e-3)
        restored.append(other.get(*names))
    print(f"FMU state with drives: {len(state)} bytes; 300 steps after restoring, currents "
          f"{restored[-1][4:7]} A, identical: {reference == restored}")
    assert np.array_equal(np.array(reference), np.array(restored))
    pl.free()
    other.free()


def test_the_actuator_force_is_the_input_or_the_drives_law_in_every_mode():
    """`actuatorForce[k]`: with drives the force of the drive law N (k_t I_k - D N ldot_k),
    computed here from the model description's parameters and the recorded currents and leg
    rates, through a power loss (holding, then braking with the windings shorted: the force
    changes sign of its rate and the legs move); with forces as inputs the input F_k itself."""
    legs = list(dr.LEGS)
    record = [f"actuatorForce[{k}]" for k in legs] + [f"I[{k}]" for k in legs] + [f"ldot[{k}]" for k in legs]
    c, _, status = dr.open_loop(lambda t: [U_HOLD if t < 0.3 else 0.0] * 6, 1.5, h=0.01, parameters=dr.drive_start(I_HOLD),
                                record=record)
    assert status == "ok"
    n = 2.0 * math.pi * P["gear.ratio"] / P["screw.lead"]
    worst, moving = 0.0, 0.0
    for k in legs:
        law = n * (P["motor.kt"] * c[f"I[{k}]"] - P["motor.D"] * n * c[f"ldot[{k}]"])
        worst = max(worst, float(np.max(np.abs(c[f"actuatorForce[{k}]"] - law) / np.maximum(np.abs(law), 1.0))))
        moving = max(moving, float(np.max(np.abs(c[f"ldot[{k}]"]))))
    print(f"actuatorForce with drives: largest relative difference from N (k_t I - D N ldot) {worst:.1e} "
          f"(legs moving at up to {moving * 1e3:.1f} mm/s)")
    assert worst < 1e-12 and moving > 1e-3

    forces = [5000.0, 5200.0, 5400.0, 5600.0, 5800.0, 6000.0]
    f, _, status = dr.open_loop(lambda t: forces, 0.05, h=0.01, record=record[:6], drive=False)
    assert status == "ok"
    for k in legs:
        # The first row is read before any input was set: the default leg forces.
        assert np.all(f[f"actuatorForce[{k}]"][1:] == forces[k - 1]), k
