"""Two builds of the platform FMU, output by output and bit by bit: every Real output both
declare, over 3000 steps of 1 ms through FMPy, with forces (legs with mass and friction; RK4;
the paper's legs), with electric drives (adaptive and RK4) under a leg feedback with a
ripple, and with hydraulic legs of oil without air and with the default air, the ideal supply (adaptive and
RK4; a valve ripple, the pump failing at 2 s) and fed by the power unit (its pump stopping at 2 s). How a change that should not touch these modes is checked (benches/results/hydraulics.txt),
and how far apart a change that moves them at round-off leaves them (benches/results/machine_lanes.txt).

    .venv/bin/python benches/same_bits.py OLD/StewartPlatform.fmu NEW/StewartPlatform.fmu
"""
import numpy as np, math
from fmpy import read_model_description, extract
from fmpy.fmi2 import FMU2Slave
def run(fmu, params, inputs_name, law, steps=3000, h=1e-3, scalars=None):
    md = read_model_description(fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    d = extract(fmu)
    s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier, instanceName="x")
    s.instantiate(); s.setupExperiment(startTime=0.0); s.enterInitializationMode()
    for k, v in params.items():
        if k not in vr:  # a parameter the older build does not have (at its neutral value here)
            continue
        if isinstance(v, int) and k in INTEGERS: s.setInteger([vr[k]], [v])
        elif isinstance(v, bool): s.setBoolean([vr[k]], [v])
        else: s.setReal([vr[k]], [v])
    s.exitInitializationMode()
    names = [v.name for v in md.modelVariables if v.type == "Real" and v.causality == "output" and v.name in OLD_NAMES]
    rows=[]; t=0.0
    for i in range(steps):
        l = np.array(s.getReal([vr[f"l[{k}]"] for k in range(1,7)])); ld = np.array(s.getReal([vr[f"ldot[{k}]"] for k in range(1,7)]))
        s.setReal([vr[f"{inputs_name}[{k}]"] for k in range(1,7)], list(law(t, l, ld)))
        for name, value in (scalars(t) if scalars else {}).items():
            s.setReal([vr[name]], [value])
        s.doStep(currentCommunicationPoint=t, communicationStepSize=h); t += h
        rows.append(s.getReal([vr[n] for n in names]))
    s.terminate(); s.freeInstance()
    return np.array(rows), names
import sys
INTEGERS = ("drive", "solver.method", "hydraulic.supply")
old, new = sys.argv[1], sys.argv[2]
OLD_NAMES = {v.name for v in read_model_description(old).modelVariables}
l0 = 1.7550860729486566
hold = 0.2005*3000*9.81
force = lambda t,l,ld: hold + 2e5*(l0-l) - 2e4*ld + 800*np.sin(3*t + np.arange(6))
N = 2*math.pi/0.02; ihold = hold/N
volts = lambda t,l,ld: ihold*0.4*(1+0.3*np.sin(3*t+np.arange(6))) + 0.4/N*(2e5*(l0-l) - 2e4*ld)
cases = [("forces, machine", {"leg.cylinderMass": 40.0, "leg.rodMass": 15.0, "friction.coulomb": 150.0}, "F", force),
         ("forces, RK4", {"solver.method": 2}, "F", force),
         ("forces, paper legs", {}, "F", force),
         ("drives", {"drive": 1, **{f"I0[{k}]": ihold for k in range(1,7)}}, "U", volts),
         ("drives, RK4", {"drive": 1, "solver.method": 2, **{f"I0[{k}]": ihold for k in range(1,7)}}, "U", volts)]
# Hydraulic legs with oil without air (docs/model.md §10b: airFraction = 0 is §10's law to the
# bit): a valve ripple with a position term, the pump failing at 2 s.
valves = lambda t,l,ld: np.clip(0.3*(l0-l)/0.01 - 0.02*ld + 0.05*np.sin(3*t + np.arange(6)), -1, 1)
pump = lambda t: {"pS": 16e6 if t < 2.0 else 0.0}
no_air = {"drive": 2, "hydraulic.airFraction": 0.0}
cases += [("hydraulics, no air", no_air, "valve", valves, pump),
          ("hydraulics, no air, RK4", {**no_air, "solver.method": 2}, "valve", valves, pump),
          # The default oil (with air) and the ideal supply (hydraulic.supply = 0): what the power
          # unit of §10b leaves as it was.
          ("hydraulics, air", {"drive": 2}, "valve", valves, pump),
          ("hydraulics, air, RK4", {"drive": 2, "solver.method": 2}, "valve", valves, pump)]
# The power unit (hydraulic.supply = 1), the pump stopping at 2 s (where the older build has it).
stop = lambda t: {"pump.speed": 1.0 if t < 2.0 else 0.0}
if "pump.speed" in OLD_NAMES:
    cases += [("power unit", {"drive": 2, "hydraulic.supply": 1}, "valve", valves, stop),
              ("power unit, RK4", {"drive": 2, "hydraulic.supply": 1, "solver.method": 2}, "valve", valves, stop)]
for name, params, inp, law, *scalars in cases:
    a, names = run(old, {k: (int(v) if k in INTEGERS else v) for k,v in params.items()}, inp, law, scalars=scalars[0] if scalars else None)
    b, _ = run(new, {k: (int(v) if k in INTEGERS else v) for k,v in params.items()}, inp, law, scalars=scalars[0] if scalars else None)
    diff = np.argwhere(a.view(np.uint64) != b.view(np.uint64))
    print(f"{name}: {a.shape[1]} outputs x {a.shape[0]} steps; differing bits: {len(diff)}", [names[j] for j in sorted(set(diff[:,1]))][:5])
    if len(diff):
        # How far apart: each output's largest difference over its largest value (constraintError,
        # round-off itself, apart), the three largest.
        scale = np.abs(a).max(axis=0)
        keep = [j for j, n in enumerate(names) if n != "constraintError" and scale[j] > 0]
        rel = np.abs(a - b).max(axis=0)[keep] / scale[keep]
        c = names.index("constraintError")
        print("   largest differences relative to the output's largest value:",
              ", ".join(f"{names[keep[o]]} {rel[o]:.1e}" for o in np.argsort(rel)[::-1][:3]),
              f"; constraintError at most {np.abs(a[:, c]).max():.1e} (old), {np.abs(b[:, c]).max():.1e} (new)")
