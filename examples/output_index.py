"""Writes README.md into the main job's output folder: what each file there is, which script
wrote it and where the documentation explains it. Files it has no description for are listed
as such (and named on stderr), so that a new output is seen.

    python examples/output_index.py [output-folder]   (default: output/)
"""

import fnmatch
import sys
from pathlib import Path

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "output")

# (pattern, description), in the order they are listed; the first match describes a file.
SECTIONS = [
    ("The paper's experiments (`examples/paper_experiments.py`; non-dimensional units: length R_b, force M g, "
     "time sqrt(R_b/g); [docs/validation.md](../docs/validation.md))", [
        ("summary.txt", "the experiments' results as printed by the main job"),
        ("default_si.csv", "the default stand at rest for 3 s in SI units, through `fmpy.simulate_fmu`"),
        ("experiment1_equilibrium.csv", "experiment 1: the equilibrium forces held; t, heave, roll, pitch"),
        ("experiment2_parasitic.csv", "experiment 2: parasitic oscillations (paper Fig. 2); t, heave, roll, pitch"),
        ("experiment3_heave.csv", "experiment 3: the heave programme's forces applied; the FMU's heave and the "
                                  "programme"),
        ("experiment3_forces.csv", "experiment 3: the programme leg force u / (M g) of the direct problem (Fig. 4)"),
        ("experiment4_perturbed.csv", "experiment 4: perturbed programme forces (Fig. 5); heave and programme"),
        ("experiment5_*.csv", "experiment 5: the controller FMU driving the platform FMU (one file per gain); "
                              "t, heave, largest leg-length error"),
        ("paper_experiments.png", "experiments 2-5 plotted"),
        ("feedback_tracking_error.png", "experiment 5: leg-length tracking error against time"),
    ]),
    ("The whole workspace: end stops, singular arrangements (`examples/workspace_scenarios.py`; SI; "
     "[docs/validation.md](../docs/validation.md))", [
        ("workspace_summary.txt", "the scenarios' results as printed by the main job"),
        ("workspace1_power_loss.csv", "1: power loss at 0.5 s, the platform drops onto its lower stops"),
        ("workspace2_elastic.csv", "2: elastic stops (no damping), the platform bounces"),
        ("workspace3_start_up.csv", "3: start-up from rest on the stops (controller programme 4)"),
        ("workspace4_actuator_failure.csv", "4: leg 1's force lost at 1 s under feedback"),
        ("workspace5_tumble.csv", "5: open-loop tumble without stops through singular arrangements (kappa)"),
        ("workspace6_power_loss_model_exchange.csv", "6: scenario 1 through Model Exchange (FMPy, CVODE)"),
        ("workspace_scenarios.png", "scenarios 1-4: heave and end-stop forces"),
        ("workspace_energy_and_singularities.png", "the energy balance of scenario 1 and kappa of scenario 5"),
    ]),
    ("The machine: heavy legs, joint limits, friction (`examples/machine_scenarios.py`; SI; [docs/model.md](../docs/model.md) §8, "
     "[docs/validation.md](../docs/validation.md))", [
        ("machine_summary.txt", "the scenarios' results as printed by the main job"),
        ("machine1_heavy_legs.csv", "heavy legs against massless legs on the heave programme"),
        ("machine2_ripple.csv", "the open-loop 5 % ripple resting on the joint limits"),
        ("machine3_friction.csv", "cylinder friction on a 5 mm heave"),
        ("machine_heavy_legs.png", "heavy against massless legs: leg forces and joint forces"),
        ("machine_ripple.png", "the ripple: tilt and joint angles against their limits"),
        ("machine_friction.png", "friction: leg error with and without friction"),
    ]),
    ("The electric drives: holding, dynamic braking, voltage commands, a failed drive "
     "(`examples/drive_scenarios.py`; SI; [docs/model.md](../docs/model.md) §9, "
     "[docs/validation.md](../docs/validation.md))", [
        ("drive_summary.txt", "the drives' parameters and the scenarios' results as printed by the main job"),
        ("drive1_power_loss.csv", "the voltages drop to 0 at 0.5 s: braked descent, quasi-static rate, currents"),
        ("drive2_heave.csv", "the heave programme with the controller in voltage mode: voltages, currents, power"),
        ("drive3_failure.csv", "leg 1's drive loses its voltage at 1 s under feedback"),
        ("drive_power_loss.png", "power loss: braked descent against the fall with force actuators"),
        ("drive_heave.png", "voltage mode: leg error, voltages, electric power"),
        ("drive_failure.png", "a shorted drive against a force actuator that loses its force"),
    ]),
    ("The hydraulic servo legs: holding, the heave in hydraulic mode, loss of control power, pump failure, a "
     "stuck valve, work-precision (`examples/hydraulic_scenarios.py`; SI; [docs/model.md](../docs/model.md) §10)", [
        ("hydraulic_summary.txt", "the defaults' figures and the scenarios' results as printed by the main job"),
        ("hydraulic1_holding.csv", "the neutral pose held under control: pressures, spools, supply flow"),
        ("hydraulic2_heave.csv", "the heave programme in hydraulic mode: pressures, spools, flow, power, leg error"),
        ("hydraulic3_control_power_loss.csv", "every valve command 0 at 1 s: the locked legs creep"),
        ("hydraulic4_pump_failure.csv", "pS to 0 at 1 s: the platform settles onto its stops; pmin (oil with air)"),
        ("hydraulic4_pump_failure_without_air.csv", "the same with hydraulic.airFraction = 0: below zero absolute"),
        ("hydraulic5_stuck_valve.csv", "leg 1's valve stuck at +0.2 from 1 s under feedback"),
        ("hydraulic_heave.png", "hydraulic mode: leg error, chamber pressures, spools, pump flow and power"),
        ("hydraulic_failures.png", "creep after the loss of control power, pump failure, stuck valve"),
        ("hydraulic_air.png", "oil with and without entrained air: the pump failure's lowest absolute pressure and "
                              "landing, the stuck valve's chambers"),
        ("hydraulic_work_precision.png", "pressure error against doStep wall time, RK4 and the adaptive method, stiff regime"),
        ("hydraulic_work_precision.md", "the same as a table"),
    ]),
    ("The hydraulic power unit: the heave on pump and accumulator, pump stops answered by the safe landing "
     "(`examples/power_unit_scenarios.py`; SI; [docs/model.md](../docs/model.md) §10b; its design study is "
     "accumulator/ below)", [
        ("hydraulic_power_unit_summary.txt", "the power unit's scenarios as printed by the main job"),
        ("hydraulic6_power_unit_heave.csv", "the heave programme on the power unit: supply pressure, pump, relief and "
                                           "valve flows, accumulator oil, pump work, leg error"),
        ("hydraulic7_pump_stop_landing.csv", "the pump stopped at the heave's worst moment, the safe landing: the same "
                                             "with the legs, the heave and the energy balance"),
        ("hydraulic_power_unit.png", "the heave on the power unit: supply pressure, flows, accumulator oil, leg error"),
        ("hydraulic_landing.png", "the pump stop and the safe landing: height, supply pressure, accumulator oil, "
                                  "velocity and acceleration"),
    ]),
    ("Motion cueing: the truck's manoeuvres, the motion system, the harsh manoeuvres, the OMCT "
     "(`examples/cueing_scenarios.py`; SI; [docs/cueing.md](../docs/cueing.md))", [
        ("cueing_summary.txt", "the runs' results as printed by the main job"),
        ("manoeuvres/*.csv", "the vehicle's motion at the driver's head: time (s), f[1..3] (m/s2, cabin axes, "
                             "(0, 0, 9.81) at rest), omega[1..3] (rad/s); the cueing FMU's inputs"),
        ("cueing_manoeuvres.png", "each default manoeuvre through StewartCueing: the vehicle's and the simulator's "
                                  "specific force and angular velocity side by side"),
        ("cueing_brake.csv", "the braking through StewartMotionSystem.ssp: vehicle, pose command, fsim, legs"),
        ("cueing_brake.png", "the braking: specific force, pitch and washout, leg lengths"),
        ("cueing_harsh.csv", "the harsh manoeuvres in the closed loop: legs' range, the limiter's least scale, "
                             "the cue's error"),
        ("cueing_omct.csv", "the Objective Motion Cueing Test of the defaults: gain and phase per test"),
        ("cueing_omct.png", "the same as Bode diagrams, with the filters' transfer functions dashed"),
    ]),
    ("Linearisation (`examples/linearise.py`; [docs/control.md](../docs/control.md))", [
        ("linearisation.json", "A, B, C, D about the neutral pose, the modes, the critical gain"),
        ("root_locus.png", "closed-loop eigenvalues against the feedback gain"),
    ]),
    ("Design studies (`stewart-sweep studies/NAME.toml --out output/NAME`; [docs/studies.md](../docs/studies.md))", [
        ("*/study.toml", "the study file the rows were computed from"),
        ("*/results.parquet", "one row a run: parameters, status, metrics (`pandas.read_parquet`)"),
        ("*/summary.txt", "the study's summary as printed"),
        ("*/*.png", "the study's plots (its `[[plot]]` sections)"),
    ]),
    ("The 3-D viewer (`examples/viewer_data.py`; [docs/viewer.md](../docs/viewer.md))", [
        ("viewer/index.html", "the page: serve the folder (`.venv/bin/python -m http.server --directory "
                              "output/viewer 8000`) and open http://127.0.0.1:8000/"),
        ("viewer/assets", "the page's script (three.js included)"),
        ("viewer/data/index.json", "the dataset menu"),
        ("viewer/data/*.csv", "the results it plays (FMPy's CSV layout)"),
        ("viewer/data/*.stand.json", "each result's stand (joints, strokes, legs)"),
    ]),
]


def entries(out):
    """The files and folders to describe: top-level files, each study folder's files, the
    viewer's data files; folders of many parts (results.parquet, assets) as one entry."""
    found = []
    for path in sorted(out.iterdir()):
        if path.name == "README.md":
            continue
        if path.is_file():
            found.append(path.name)
        elif path.name == "viewer":
            for sub in sorted(path.iterdir()):
                if sub.name == "data":
                    found += [f"viewer/data/{f.name}" for f in sorted(sub.iterdir())]
                else:
                    found.append(f"viewer/{sub.name}")
        else:
            found += [f"{path.name}/{sub.name}" for sub in sorted(path.iterdir()) if not sub.name.startswith(".")]
    return found


def main():
    names = entries(OUT)
    described = set()
    lines = ["# What the main job wrote", "",
             "Written by `bash examples/main_job.sh` (`examples/output_index.py`). Plots are PNG, tables CSV "
             "(a header row of names) or Parquet; units are SI unless the section says non-dimensional.", ""]
    for title, patterns in SECTIONS:
        rows = []
        for pattern, text in patterns:
            matched = [n for n in names if n not in described and fnmatch.fnmatch(n, pattern)]
            if matched:
                described.update(matched)
                shown = ", ".join(f"`{n}`" for n in matched[:6]) + (f" ... ({len(matched)} files)" if len(matched) > 6 else "")
                rows.append(f"| {shown} | {text} |")
        if rows:
            lines += [f"## {title}", "", "| file | what it is |", "|---|---|", *rows, ""]
    unknown = [n for n in names if n not in described]
    if unknown:
        lines += ["## Not described yet", "", *[f"- `{n}`" for n in unknown], ""]
        print(f"output_index: no description for {', '.join(unknown)} (add them to examples/output_index.py)",
              file=sys.stderr)
    (OUT / "README.md").write_text("\n".join(lines))
    print(f"output_index: wrote {OUT / 'README.md'} ({len(described)} of {len(names)} files described)")


if __name__ == "__main__":
    main()
