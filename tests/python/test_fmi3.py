"""The FMI 3.0 FMUs (target/fmu/fmi3/) through FMPy: validation, the FMI 3 platform against the
FMI 2 platform bit for bit, Model Exchange, the end stops through Co-Simulation event mode and
early return, adjoint against directional derivatives, variable dependencies, serialized FMU
states, and the controller closing the loop."""

import math
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi3 import FMU3Model, FMU3Slave
from fmpy.validation import validate_fmu

from stewart_fmu import PLATFORM_FMU, Platform

FMI3_DIR = Path(PLATFORM_FMU).parent / "fmi3"
PLATFORM3 = FMI3_DIR / "StewartPlatform.fmu"
CONTROLLER3 = FMI3_DIR / "StewartController.fmu"
CONTROLLER2 = Path(PLATFORM_FMU).parent / "StewartController.fmu"
FORCE = 0.2005 * 3000.0 * 9.81
_extracted = {}


class Fmu3:
    """An FMI 3 instance (Co-Simulation or Model Exchange) with access by variable name;
    arrays are read and written whole."""

    def __init__(self, fmu, interface="CoSimulation", name="fmi3", booleans=None, reals=None, integers=None,
                 events=None, **instantiate):
        fmu = str(fmu)
        self.md = read_model_description(fmu)
        if fmu not in _extracted:
            _extracted[fmu] = extract(fmu)
        self.var = {v.name: v for v in self.md.modelVariables}
        cls = FMU3Slave if interface == "CoSimulation" else FMU3Model
        identifier = (self.md.coSimulation if interface == "CoSimulation" else self.md.modelExchange).modelIdentifier
        self.fmu = cls(guid=self.md.guid, unzipDirectory=_extracted[fmu], modelIdentifier=identifier,
                       instanceName=name)
        if events is not None:
            def log(_env, status, category, message):
                events.append((status, (category or b"").decode(), (message or b"").decode()))
            instantiate["logMessage"] = log
        self.fmu.instantiate(**instantiate)
        if events is not None:
            self.fmu.setDebugLogging(True, ["logEvents"])
        self.fmu.enterInitializationMode()
        for name, value in (reals or {}).items():
            self.set(name, value)
        for name, value in (booleans or {}).items():
            self.fmu.setBoolean([self.var[name].valueReference], [bool(value)])
        for name, value in (integers or {}).items():
            self.fmu.setInt32([self.var[name].valueReference], [int(value)])
        self.fmu.exitInitializationMode()
        self.time = 0.0

    def size(self, name):
        return int(np.prod([int(d.start) for d in self.var[name].dimensions])) if self.var[name].dimensions else 1

    def get(self, name):
        v = self.fmu.getFloat64([self.var[name].valueReference], self.size(name))
        return np.array(v) if self.var[name].dimensions else v[0]

    def set(self, name, values):
        values = np.atleast_1d(np.asarray(values, dtype=float))
        self.fmu.setFloat64([self.var[name].valueReference], list(values))

    def states(self):
        from ctypes import c_double
        n = self.md.numberOfContinuousStates
        x = (c_double * n)()
        self.fmu.getContinuousStates(x, n)
        return np.array(x)

    def set_states(self, x):
        from ctypes import c_double
        self.fmu.setContinuousStates((c_double * len(x))(*x), len(x))

    def derivatives(self):
        from ctypes import c_double
        n = self.md.numberOfContinuousStates
        dx = (c_double * n)()
        self.fmu.getContinuousStateDerivatives(dx, n)
        return np.array(dx)

    def dependencies(self, vr):
        """(elements of the dependent, independents, their elements, kinds) through the C
        functions (FMPy 0.3.32's getNumberOfVariableDependencies passes a type, not a value)."""
        from ctypes import byref, c_int, c_size_t, c_uint
        n = c_size_t()
        assert self.fmu.fmi3GetNumberOfVariableDependencies(self.fmu.component, c_uint(vr), byref(n)) == 0
        n = n.value
        arrays = ((c_size_t * n)(), (c_uint * n)(), (c_size_t * n)(), (c_int * n)())
        assert self.fmu.fmi3GetVariableDependencies(self.fmu.component, c_uint(vr), *arrays, n) == 0
        return tuple(list(a) for a in arrays)

    def step(self, h):
        result = self.fmu.doStep(self.time, h)
        self.time = result[3]
        return result

    def steps_with_events(self, h, t_end, before_step=None, at_early_return=None):
        """Co-Simulation in step mode on the grid of `h` up to `t_end` (an instance made with
        eventModeUsed and earlyReturnAllowed): `before_step(self)` before each step; a step that
        returns early is followed by the rest of its grid interval, `at_early_return(self)` called
        where it returned; each event handled in Event Mode. Returns the times of the early returns
        and the flags of each fmi3UpdateDiscreteStates (discreteStatesNeedUpdate,
        terminateSimulation, ...)."""
        early, flags = [], []
        self.fmu.enterStepMode()
        while self.time < t_end - 1e-12:
            if before_step is not None:
                before_step(self)
            target = min(t_end, (math.floor(self.time / h + 1e-9) + 1) * h)
            event, terminate, early_return, last = self.fmu.doStep(self.time, target - self.time)
            assert not terminate
            self.time = last
            if early_return:
                early.append(last)
                if at_early_return is not None:
                    at_early_return(self)
            if event:
                self.fmu.enterEventMode()
                flags.append(self.fmu.updateDiscreteStates())
                self.fmu.enterStepMode()
        return early, flags

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


@pytest.mark.quick
def test_fmi3_fmus_validate_clean():
    for fmu in (PLATFORM3, CONTROLLER3):
        assert validate_fmu(str(fmu)) == [], fmu
        md = read_model_description(str(fmu))
        assert md.fmiVersion == "3.0"
    md = read_model_description(str(PLATFORM3))
    shapes = {v.name: tuple(int(d.start) for d in v.dimensions) for v in md.modelVariables}
    assert shapes["F"] == (6,) and shapes["R"] == (3, 3) and shapes["B"] == (6, 3) and shapes["l"] == (6,)
    # 24 special-form states, work.F, work.dissipated, six drive currents, work.electric, the
    # hydraulic legs' 26 and the power unit's 2; 12 stroke margins, the determinant, 12
    # joint-limit margins, the accumulator's precharge
    assert md.numberOfContinuousStates == 61 and md.numberOfEventIndicators == 26
    assert md.coSimulation.hasEventMode and md.coSimulation.canReturnEarlyAfterIntermediateUpdate


def forces_at(t, legs, rates):
    """Open-loop sine forces plus a leg feedback towards the neutral length (the comparison
    run of the issue): the same arithmetic for both FMI versions."""
    l0 = 1.7550860729486566
    return [FORCE * (1.0 + 0.02 * math.sin(3.0 * t + k)) + 2.0e5 * (l0 - legs[k]) - 2.0e4 * rates[k]
            for k in range(6)]


@pytest.mark.quick
def test_fmi3_platform_equals_fmi2_platform_bit_for_bit():
    """Same inputs (sine forces plus leg feedback), 1 ms, 3 s: every output of the FMI 3
    platform equals the FMI 2 platform's bit for bit."""
    p2 = Platform(name="fmi2")
    p3 = Fmu3(PLATFORM3, name="fmi3")
    names2 = ([f"r[{i}]" for i in range(1, 4)] + [f"R[{a},{b}]" for a in range(1, 4) for b in range(1, 4)]
              + [f"l[{k}]" for k in range(1, 7)] + [f"ldot[{k}]" for k in range(1, 7)] + ["E", "kappa", "work.F"])
    worst = 0.0
    for i in range(3000):
        legs2, rates2 = p2.vector("l", 6), p2.vector("ldot", 6)
        legs3, rates3 = p3.get("l"), p3.get("ldot")
        assert np.array_equal(legs2, legs3) and np.array_equal(rates2, rates3)
        f = forces_at(p2.time, legs2, rates2)
        p2.set_forces(f)
        p3.set("F", f)
        p2.step(1e-3)
        p3.step(1e-3)
        out2 = np.array(p2.get(*names2))
        out3 = np.concatenate([p3.get("r"), p3.get("R"), p3.get("l"), p3.get("ldot"),
                               [p3.get("E"), p3.get("kappa"), p3.get("work.F")]])
        worst = max(worst, float(np.max(np.abs(out2 - out3))))
        assert np.array_equal(out2, out3), f"step {i}: FMI 2 and FMI 3 outputs differ"
    print(f"FMI 3 vs FMI 2 platform, 3000 steps of 1 ms with sine forces and leg feedback: identical "
          f"(max difference {worst}); final z = {p3.get('r')[2]:.12f} m, roll {math.atan2(-p3.get('R')[5], p3.get('R')[8]):.3e}")
    p2.free()
    p3.free()


@pytest.mark.quick
def test_fmi3_model_exchange_matches_fmi2_model_exchange():
    """FMPy over the FMI 3 Model Exchange interface (states in FMI 3 order: whole arrays)
    against the FMI 2 one. Explicit Euler with time-varying inputs: identical. CVODE with
    constant forces: equal to what its error control allows (the permuted state vector changes
    the order of its sums). (With time-varying inputs FMPy's CVODE root function applies the
    inputs at CVODE's internal times, which differ between the two runs; see docs/fmi-behaviour.md.)"""
    t = np.linspace(0.0, 2.0, 2001)
    inputs = np.zeros(len(t), dtype=[("time", float)] + [(f"F[{k}]", float) for k in range(1, 7)])
    inputs["time"] = t
    for k in range(6):
        inputs[f"F[{k + 1}]"] = FORCE * (1.0 + 0.01 * np.sin(2.0 * t + k))
    inputs3 = np.zeros(len(t), dtype=[("time", float), ("F", float, (6,))])
    inputs3["time"] = t
    inputs3["F"] = np.column_stack([inputs[f"F[{k}]"] for k in range(1, 7)])
    e2 = simulate_fmu(str(PLATFORM_FMU), fmi_type="ModelExchange", solver="Euler", step_size=1e-3, input=inputs,
                      stop_time=2.0, output_interval=1e-2, output=["r[3]", "l[1]"])
    e3 = simulate_fmu(str(PLATFORM3), fmi_type="ModelExchange", solver="Euler", step_size=1e-3, input=inputs3,
                      stop_time=2.0, output_interval=1e-2, output=["r", "l"])
    euler_equal = np.array_equal(e3["r"][:, 2], e2["r[3]"]) and np.array_equal(e3["l"][:, 0], e2["l[1]"])
    constant2 = {f"F[{k}]": FORCE * (1 + 0.01 * k) for k in range(1, 7)}
    constant3 = {"F": [FORCE * (1 + 0.01 * k) for k in range(1, 7)]}
    c2 = simulate_fmu(str(PLATFORM_FMU), fmi_type="ModelExchange", relative_tolerance=1e-10, start_values=constant2,
                      stop_time=2.0, output_interval=1e-2, output=["r[3]", "l[1]"])
    c3 = simulate_fmu(str(PLATFORM3), fmi_type="ModelExchange", relative_tolerance=1e-10, start_values=constant3,
                      stop_time=2.0, output_interval=1e-2, output=["r", "l"])
    dz = np.max(np.abs(c3["r"][:, 2] - c2["r[3]"]))
    print(f"Model Exchange, FMI 3 vs FMI 2: FMPy Euler with time-varying forces identical: {euler_equal}; "
          f"CVODE rtol 1e-10 with constant forces, 2 s: max |dz| = {dz:.1e} m (heave range {np.ptp(c2['r[3]']):.3f} m)")
    assert euler_equal
    assert dz < 1e-7


@pytest.mark.quick
def test_fmi3_co_simulation_returns_early_at_contacts_and_reports_events():
    """Power loss through FMI 3 Co-Simulation with event mode and early return: each step that
    meets a contact returns at the located contact time with eventHandlingNeeded; the
    importer handles it in Event Mode; the motion equals the FMI 2 run's."""
    requests = []

    def intermediate_update(_env, time, _set_requested, _get_allowed, _finished, can_return_early,
                            early_return_requested, early_return_time):
        requests.append(time)
        early_return_requested[0] = True
        early_return_time[0] = time

    p3 = Fmu3(PLATFORM3, name="events", eventModeUsed=True, earlyReturnAllowed=True,
              intermediateUpdate=intermediate_update)
    h, t_end = 1e-2, 1.5
    early, flags = p3.steps_with_events(h, t_end, lambda p: p.set("F", [FORCE if p.time < 0.5 - 1e-12 else 0.0] * 6))
    assert flags and not any(f[0] or f[1] for f in flags)
    z3 = p3.get("r")[2]
    p3.free()
    p2 = Platform(name="reference")
    while p2.time < t_end - 1e-12:
        p2.set_forces([FORCE if p2.time < 0.5 - 1e-12 else 0.0] * 6)
        p2.step(min(h, t_end - p2.time))
    z2 = p2.get("r[3]")[0]
    p2.free()
    print(f"FMI 3 Co-Simulation with event mode: {len(early)} early returns at contacts, first at t = {early[0]:.9f} s "
          f"(intermediate updates at {[round(t, 6) for t in requests[:4]]} ...); z at {t_end} s: {z3:.12f} m "
          f"(FMI 2 without events {z2:.12f} m)")
    assert abs(early[0] - 0.780616998) < 1e-8
    assert requests[:len(early)] == early
    assert abs(z3 - z2) < 1e-7


@pytest.mark.quick
def test_adjoint_derivatives_are_the_transpose_of_the_directional_ones():
    """<v, J w> = <J^T v, w> to round-off for the derivatives and outputs with respect to the
    states and the inputs, at random states (FMI 3 Model Exchange)."""
    m = Fmu3(PLATFORM3, interface="ModelExchange", name="adjoint")
    m.fmu.enterContinuousTimeMode()
    vr = {n: v.valueReference for n, v in m.var.items()}
    unknowns = [vr[n] for n in ["der(v)", "der(R,2)", "der(work.F)", "l", "ldot", "E", "kappa", "Fstop"]]
    knowns = [vr[n] for n in ["r", "v", "R", "der(R)", "F"]]
    n_u = sum(m.size(n) for n in ["der(v)", "der(R,2)", "der(work.F)", "l", "ldot", "E", "kappa", "Fstop"])
    n_k = sum(m.size(n) for n in ["r", "v", "R", "der(R)", "F"])
    rng = np.random.default_rng(3)
    x0 = m.states()
    worst = 0.0
    for case in range(5):
        x = x0 + np.concatenate([rng.normal(0, 0.02, 6), rng.normal(0, 0.01, 18), np.zeros(len(x0) - 24)])
        m.set_states(x)
        m.set("F", FORCE * (1 + 0.1 * rng.normal(size=6)))
        w, v = rng.normal(size=n_k), rng.normal(size=n_u)
        jw = np.array(m.fmu.getDirectionalDerivative(unknowns, knowns, list(w), n_u))
        jtv = np.array(m.fmu.getAdjointDerivative(unknowns, knowns, list(v), n_k))
        lhs, rhs = float(v @ jw), float(jtv @ w)
        scale = float(np.abs(v) @ np.abs(jw)) + 1e-300
        worst = max(worst, abs(lhs - rhs) / scale)
    print(f"adjoint vs directional derivatives ({n_u} unknowns x {n_k} knowns): max |<v, J w> - <J^T v, w>| / "
          f"|v| |J w| = {worst:.1e}")
    assert worst < 1e-13
    m.free()


@pytest.mark.quick
def test_variable_dependencies_match_the_model_structure():
    """fmi3GetNumberOfVariableDependencies / fmi3GetVariableDependencies against the
    ModelStructure of the model description."""
    m = Fmu3(PLATFORM3, interface="ModelExchange", name="deps")
    m.fmu.enterContinuousTimeMode()
    md = m.md
    derivatives = {d.variable.valueReference for d in md.derivatives}
    # An output that is also a state derivative (v) answers with its derivative's dependencies.
    for unknown in md.derivatives + [o for o in md.outputs if o.variable.valueReference not in derivatives]:
        if unknown.dependencies is None:
            continue
        expected = {d.valueReference for d in unknown.dependencies}
        dependent, independents, elements, kinds = m.dependencies(unknown.variable.valueReference)
        assert set(independents) == expected, unknown.variable.name
        assert all(k == 5 for k in kinds)
        size = m.size(unknown.variable.name)
        assert set(dependent) == ({0} if not unknown.variable.dimensions else set(range(1, size + 1))) or not expected
    dependent, independents, elements, _ = m.dependencies(m.var["l"].valueReference)
    print(f"variable dependencies: l (6 elements) has {len(dependent)} element dependencies on r and R")
    assert len(dependent) == 6 * (3 + 9)
    assert sorted(set(elements)) == list(range(1, 10))
    m.free()


@pytest.mark.quick
def test_fmi3_fmu_state_round_trip_continues_bit_for_bit():
    p = Fmu3(PLATFORM3, name="state")
    p.set("F", [FORCE * 1.01] * 6)
    for _ in range(100):
        p.step(1e-3)
    t_saved = p.time
    state = p.fmu.getFMUState()
    data = p.fmu.serializeFMUState(state)
    p.fmu.freeFMUState(state)
    for _ in range(200):
        p.step(1e-3)
    first = p.get("r").copy()
    restored = p.fmu.deserializeFMUState(data)
    p.fmu.setFMUState(restored)
    p.fmu.freeFMUState(restored)
    p.time = t_saved
    for _ in range(200):
        p.step(1e-3)
    print(f"FMI 3 serialized state ({len(data)} bytes): continuation identical {np.array_equal(first, p.get('r'))}")
    assert np.array_equal(first, p.get("r"))
    p.fmu.reset()
    p.fmu.enterInitializationMode()
    p.fmu.exitInitializationMode()
    p.time = 0.0
    assert p.get("r")[2] == 1.9589244164161732
    p.free()


@pytest.mark.quick
def test_fmi3_controller_closes_the_loop_like_fmi2():
    """The FMI 3 controller driving the FMI 3 platform (Gauss-Seidel, 1 ms, 2 s) gives the
    same legs as the FMI 2 pair, bit for bit."""
    def run(platform, controller, fmi3):
        p = Fmu3(platform, name="p") if fmi3 else Platform(fmu=platform, name="p")
        if fmi3:
            c = Fmu3(controller, name="c")
        else:
            from stewart_fmu.core import Component
            c = Component(controller, "c")
        errors = []
        for i in range(2000):
            if fmi3:
                c.set("l", p.get("l"))
                c.set("ldot", p.get("ldot"))
                p.set("F", c.get("F"))
                p.step(1e-3)
                c.fmu.doStep(i * 1e-3, 1e-3)
                errors.append(np.max(np.abs(p.get("l") - c.get("lp"))))
            else:
                legs = [f"l[{k}]" for k in range(1, 7)]
                rates = [f"ldot[{k}]" for k in range(1, 7)]
                c.set_values(legs + rates, np.concatenate([p.vector("l", 6), p.vector("ldot", 6)]))
                p.set_forces(c.values([f"F[{k}]" for k in range(1, 7)]))
                p.step(1e-3)
                c.slave.doStep(currentCommunicationPoint=i * 1e-3, communicationStepSize=1e-3)
                errors.append(np.max(np.abs(p.vector("l", 6) - c.values([f"lp[{k}]" for k in range(1, 7)]))))
        return np.array(errors)

    e3 = run(PLATFORM3, CONTROLLER3, True)
    e2 = run(PLATFORM_FMU, CONTROLLER2, False)
    print(f"closed loop, FMI 3 pair vs FMI 2 pair, 2 s at 1 ms: max leg error {e3.max() * 1e3:.4f} mm, "
          f"identical {np.array_equal(e2, e3)}")
    assert np.array_equal(e2, e3)
    assert e3.max() < 1e-4


def without_units(fmu, folder):
    """A copy of an FMI 3 FMU whose model description has no `unit`/`displayUnit` attributes on
    its variables and no `A` (ampere) exponents in its base units (same binary, same everything
    else): fmi-sim 0.7.0's FMI 3 schema (rust-fmi fmi-schema 0.8.0) refuses `unit` on Float64
    variables and `A` on `BaseUnit` ("unknown field"), both of which the standard allows."""
    import re
    import zipfile
    out = Path(folder) / Path(fmu).name
    with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                text = re.sub(r'(<(?:Float64|Int32|Boolean) [^>]*?) unit="[^"]*"', r"\1", text)
                text = re.sub(r'(<(?:Float64|Int32|Boolean) [^>]*?) displayUnit="[^"]*"', r"\1", text)
                text = re.sub(r'(<BaseUnit\b[^>]*?)\s+A="[^"]*"', r"\1", text)
                data = text.encode()
            dst.writestr(item, data)
    return out


def test_fmi_sim_loads_the_fmi3_platform_and_gets_a_clear_error_for_its_array_read(tmp_path):
    """fmi-sim 0.7.0 (rust-fmi) imports FMI 3 but (1) its schema refuses `unit` on Float64
    variables and (2) it reads one value per value reference, so it cannot record array
    variables. Given the description without units, it loads the binary, instantiates,
    initialises, and on its first read of `r` (3 values, nValues = 1) the FMU answers with
    fmi3Error and says why, instead of writing past fmi-sim's buffer."""
    import subprocess
    from test_importers import fmi_sim_binary

    fmu = without_units(PLATFORM3, tmp_path)
    import os
    run = subprocess.run([fmi_sim_binary(), "--model", str(fmu), "-o", str(tmp_path / "out.csv"),
                          "co-simulation", "--step", "0.01", "-f", "0.1"], capture_output=True, text=True,
                         env=dict(os.environ, RUST_LOG="info"))
    log = run.stdout + run.stderr
    initialised = "fmi3ExitInitializationMode() -> fmi3OK" in log
    refused = "the value references address 3 values, but nValues = 1" in log
    print(f"fmi-sim 0.7.0 with the FMI 3 platform: exit code {run.returncode}, initialised {initialised}, array read "
          f"refused with a message {refused}")
    assert initialised and refused
    assert run.returncode != 0
