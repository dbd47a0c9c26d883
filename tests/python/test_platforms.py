"""Every platform in one FMU: the packaged FMUs' binaries for Linux x86-64, Windows x64
(under wine) and Linux aarch64 (under qemu-user), driven by the same C host
(tests/c/platform_host.c) built for each, through FMI 2 and FMI 3, Co-Simulation and Model
Exchange, give the same bits as Linux x86-64 in every scenario: at rest, moving with end-stop
contact and joint forces, in closed loop with the controller, with the FMU state saved,
restored, serialized and loaded into another instance, two instances in one process, and bad
calls refused with the same messages.

The toolchains and runners come from Debian 12 (tests/setup_cross.sh); the FMUs from
`cargo run --release --bin build-fmu` with its default targets.
"""

import re
import subprocess
import zipfile

import pytest

import platforms as P
from stewart_fmu import CONTROLLER_FMU, NEUTRAL_Z, PLATFORM_FMU

FMI3_DIR = PLATFORM_FMU.parent / "fmi3"
# An unpacking folder with spaces and characters beyond ASCII: the binaries must find
# themselves there (Windows: UTF-16 paths) and take such a resource location (FMI 2 a
# percent-encoded file URI, FMI 3 a native path).
FOLDER = "Stewart FMU Ünïcödé ✓"

# The scenarios: scripts for the host after the models' declarations. Each names the FMI
# interfaces it uses ("cs", "me"); `dt` and counts keep every run within seconds under qemu.
SCENARIOS = {
    # The default stand held by its equilibrium forces, default (adaptive) integrator.
    "rest": ("cs", """
new p platform cs
init p
step p 0.01 100
print p r R l E kappa constraintError
step p 0.01 100
print p r l E
"""),
    # The legs powered off at once: the platform falls onto the lower end stops (adaptive
    # steps through the contacts, logEvents naming them), then the same with RK4.
    "end-stop contact": ("cs", """
new p platform cs
debug p logEvents
set p F 0 0 0 0 0 0
init p
step p 0.001 400
print p r l ldot Fstop E work.F work.dissipated
step p 0.001 600
print p r l ldot Fstop E work.F work.dissipated
new q platform cs
set q solver.method 2
set q F 0 0 0 0 0 0
init q
step q 0.001 1000
print q r l Fstop E work.dissipated
"""),
    # A tilted start under unequal forces: roll, pitch and yaw move, the joints turn
    # (sin, cos, atan2, acos on the model's path) and reach their limits.
    "tilted motion": ("cs", """
new p platform cs
debug p logEvents
set p angles0 0.02 -0.01 0.03
set p F 7000 5900.715 4800 5900.715 6500 5900.715
init p
step p 0.001 800
print p r R angles w l thetaA thetaB jointForce E work.F work.dissipated kappa
"""),
    # The paper's heave programme in closed loop with the controller FMU (another binary's
    # instance in the same process), Gauss-Seidel at 1 ms.
    "closed loop": ("cs", """
new p platform cs
new c controller cs
init p
init c
loop p c 0.001 1500
print p r R l ldot E
print c F Fp lp rp
"""),
    # FMU state: saved at 0.3 s, the run continued to 0.6 s, restored and run again, then
    # serialized, loaded into a second instance and run there: the same three times.
    "FMU state": ("cs", """
new p platform cs
set p angles0 0.02 0 0
init p
step p 0.001 300
save p 0
step p 0.001 300
print p r R l E
restore p 0
step p 0.001 300
print p r R l E
serialize p 0
new q platform cs
init q
deserialize q 0
step q 0.001 300
print q r R l E
release p 0
"""),
    # Two instances of one model in one process, stepped in turn with different forces:
    # each gives its own run's bits ("alone" runs them one after the other).
    "two instances": ("cs", """
new a platform cs
new b platform cs
set a F 7000 5900.715 4800 5900.715 6500 5900.715
set b F 0 0 0 0 0 0
init a
init b
step a 0.001 1
step b 0.001 1
step a 0.001 1
step b 0.001 1
step a 0.001 1
step b 0.001 1
step a 0.001 297
step b 0.001 297
print a r R l E
print b r R l E
"""),
    "alone": ("cs", """
new a platform cs
set a F 7000 5900.715 4800 5900.715 6500 5900.715
init a
step a 0.001 300
print a r R l E
free a
new b platform cs
set b F 0 0 0 0 0 0
init b
step b 0.001 300
print b r R l E
"""),
    # Bad calls: foreign tokens, a negative step, an unknown value reference, a mass that
    # cannot be: each refused with its status and message, the instance still usable.
    "bad calls": ("cs", """
var platform bogus R 1 99999
badtoken platform
badtoken controller
new p platform cs
set p M -1
init p
new q platform cs
init q
badstep q
set q bogus 1
step q 0.001 10
print q r l
"""),
    # Model Exchange: the host's own explicit Euler over the derivatives, with the event
    # handling a host owes; then the exact directional derivatives of the accelerations.
    "model exchange": ("me", """
new m platform me
set m F 6500 5900.715 5300 5900.715 6200 5900.715
init m
euler m 0.0001 1500
dirder m der(v) F

print m r l E
"""),
}


def unpacked(tmp_path_factory):
    folder = tmp_path_factory.mktemp("platforms") / FOLDER
    fmus = {2: (PLATFORM_FMU, CONTROLLER_FMU), 3: (FMI3_DIR / "StewartPlatform.fmu", FMI3_DIR / "StewartController.fmu")}
    out = {}
    for version, (platform, controller) in fmus.items():
        p = P.unpack(platform, folder / f"fmi{version}" / "platform")
        c = P.unpack(controller, folder / f"fmi{version}" / "controller")
        declarations = P.declarations(p / "modelDescription.xml", "platform") + \
            P.declarations(c / "modelDescription.xml", "controller")
        out[version] = (p, c, "\n".join(declarations) + "\n")
    return out


@pytest.fixture(scope="module")
def setting(tmp_path_factory):
    missing = P.tools_missing()
    if missing:
        pytest.fail(f"missing {', '.join(missing)}: run `bash tests/setup_cross.sh` (tests/run_all.sh does)")
    P.build_hosts()
    P.ensure_wine_prefix()
    return unpacked(tmp_path_factory)


def platforms_of(version):
    return [p for p, d in P.PLATFORMS.items() if version == 3 or d["fmi2"]]


def run(setting, version, platform, script):
    p, c, declarations = setting[version]
    binaries = (P.binary(p, version, platform, "StewartPlatform"), P.binary(c, version, platform, "StewartController"))
    code, out, err = P.run_host(platform, version, *binaries, P.resource_location(p / "resources", platform, version),
                                declarations + script)
    assert code == 0 and out.endswith("done\n"), f"{platform} FMI {version}: exit {code}\n{out[-2000:]}\n{err[-2000:]}"
    return out


def printed(out, label):
    """The values of the last line that starts with `label` (`p r`)."""
    lines = [line for line in out.splitlines() if line.startswith(label + " ")]
    assert lines, f"no line {label!r}"
    return P.values_of(lines[-1])


def test_every_platform_gives_the_bits_of_linux_x86_64(setting):
    rows, failures = [], []
    outputs = {}
    for version in (2, 3):
        for name, (interface, script) in SCENARIOS.items():
            reference = None
            for platform in platforms_of(version):
                out = run(setting, version, platform, script)
                outputs[version, name, platform] = out
                if platform == P.REFERENCE:
                    reference = out
                    continue
                differing, largest, first = P.compare(reference, out)
                rows.append((platform, f"FMI {version} {interface.upper()}", name, len(out.splitlines()), differing,
                             largest))
                if differing:
                    failures.append(f"{platform} FMI {version} {name}: {differing} lines differ, first {first}")
    print(f"{'platform':16} {'interface':10} {'scenario':18} {'lines':>6} {'differ':>6} {'largest difference':>19}")
    for platform, interface, name, lines, differing, largest in rows:
        print(f"{platform:16} {interface:10} {name:18} {lines:6d} {differing:6d} {largest:19.3g}")
    assert not failures, "\n".join(failures)

    # What the scenarios show, on the reference (and so on every platform).
    for version in (2, 3):
        out = lambda name: outputs[version, name, P.REFERENCE]  # noqa: E731
        # At rest: the equilibrium holds (the centre of mass at the neutral height).
        assert abs(printed(out("rest"), "p r")[2] - NEUTRAL_Z) < 1e-9
        # The fall ends resting on the lower stops, which carry the weight between them (about
        # a sixth each, more along the inclined legs), with RK4 too; energy was dissipated.
        contact = out("end-stop contact")
        weight = 3000.0 * 9.81
        for who in ("p", "q"):
            assert weight / 6 < min(printed(contact, f"{who} Fstop")) < weight / 3
        assert printed(contact, "p work.dissipated")[0] > 0
        assert contact.count("reached its lower end stop") >= 6
        # The tilted motion turned the joints: nonzero joint forces where a limit was met.
        tilted = out("tilted motion")
        assert max(abs(x) for x in printed(tilted, "p angles")) > 1e-3
        # The closed loop follows the programme: leg lengths within a millimetre of lp.
        loop = out("closed loop")
        errors = [abs(a - b) for a, b in zip(printed(loop, "p l"), printed(loop, "c lp"))]
        assert max(errors) < 1e-3, errors
        # FMU state: the run after restore and after deserialize in another instance give
        # the bits of the first.
        state = out("FMU state")
        runs = [[line.split(" ", 1)[1] for line in state.splitlines() if line.startswith(f"{who} ")]
                for who in ("p", "q")]
        assert len(runs[0]) == 8 and len(runs[1]) == 4, runs
        assert runs[0][:4] == runs[0][4:] == runs[1], runs
        assert "restore p 0" in state and "deserialized q 0" in state
        # Two instances in one process run as if alone, as the model descriptions promise.
        for unpacked in setting[version][:2]:
            text = (unpacked / "modelDescription.xml").read_text()
            assert 'canBeInstantiatedOnlyOncePerProcess="false"' in text, unpacked
            assert 'canBeInstantiatedOnlyOncePerProcess="true"' not in text, unpacked
        two, alone = out("two instances"), out("alone")
        for who in ("a", "b"):
            for v in ("r", "R", "l", "E"):
                assert printed(two, f"{who} {v}") == printed(alone, f"{who} {v}"), (who, v)
        # Bad calls: refused, each with its message, and the instance goes on.
        bad = out("bad calls")
        assert bad.count("badtoken refused") == 2
        assert f"badstep q 3" in bad and "status p exitInitializationMode 3" in bad
        assert "99999" in bad and "status q set 3" in bad
        assert printed(bad, "q l")[0] > 1.0
        messages = [line for line in bad.splitlines() if line.startswith("log ")]
        assert len(messages) >= 4 and all("\\n" not in m and "\\r" not in m for m in messages), messages
        # Model Exchange moved and its derivatives are not all zero.
        me = out("model exchange")
        assert any(abs(x) > 0 for x in printed(me, "m dder(v)/dF"))


def test_the_windows_binary_needs_only_windows_own_dlls_and_no_platform_maths(tmp_path):
    """objdump (mingw's binutils, independent of build-fmu's own check) on the packaged DLLs:
    the imported DLLs are system DLLs, and neither they nor the Linux binaries import an
    elementary function from the C library."""
    with zipfile.ZipFile(PLATFORM_FMU) as z:
        z.extract("binaries/win64/StewartPlatform.dll", tmp_path)
        z.extract("binaries/linux64/StewartPlatform.so", tmp_path)
    with zipfile.ZipFile(FMI3_DIR / "StewartPlatform.fmu") as z:
        z.extract("binaries/aarch64-linux/StewartPlatform.so", tmp_path)
    dump = subprocess.run(["x86_64-w64-mingw32-objdump", "-p", str(tmp_path / "binaries/win64/StewartPlatform.dll")],
                          capture_output=True, text=True, check=True).stdout
    dlls = sorted({line.split(":", 1)[1].strip().lower() for line in dump.splitlines() if "DLL Name:" in line})
    print("StewartPlatform.dll imports", ", ".join(dlls))
    system = {"kernel32.dll", "ntdll.dll", "msvcrt.dll", "bcryptprimitives.dll", "userenv.dll", "ws2_32.dll",
              "advapi32.dll", "api-ms-win-core-synch-l1-2-0.dll"}
    assert dlls and set(dlls) <= system, dlls
    assert "kernel32.dll" in dlls
    maths = {"sin", "cos", "tan", "sincos", "asin", "acos", "atan", "atan2", "exp", "expm1", "log", "log2", "pow",
             "tanh", "hypot", "cbrt"}
    imported = {m.group(1) for m in re.finditer(r"^\s+[0-9a-f]+\s+\d+\s+(\S+)$", dump, re.M)}
    assert "GetModuleFileNameW" in imported, "the import table was read"
    assert not imported & maths, imported & maths
    for so, nm in ((tmp_path / "binaries/linux64/StewartPlatform.so", "nm"),
                   (tmp_path / "binaries/aarch64-linux/StewartPlatform.so", "aarch64-linux-gnu-nm")):
        undefined = subprocess.run([nm, "-D", "--undefined-only", str(so)], capture_output=True, text=True,
                                   check=True).stdout
        names = {line.split()[-1].split("@")[0] for line in undefined.splitlines() if line.strip()}
        assert names and not names & maths, (so, names & maths)


# FMPy's own loop on each platform: the same calls, their results as bits.
FMPY_RUNS = r"""
import json, sys
sys.path[:0] = sys.argv[2:]
import numpy as np
from fmpy import platform_tuple, simulate_fmu
fmu = sys.argv[1]
tilted = {"angles0": [0.02, -0.01, 0.03], "F": [7000.0, 5900.715, 4800.0, 5900.715, 6500.0, 5900.715]}
runs = {
    "fall onto the stops": simulate_fmu(fmu, stop_time=1.5, output=["r", "l", "Fstop", "E"], start_values={"F": [0.0] * 6}),
    "tilted motion": simulate_fmu(fmu, stop_time=0.8, output=["r", "R", "angles", "thetaA", "jointForce"], start_values=tilted),
    "model exchange, Euler": simulate_fmu(fmu, fmi_type="ModelExchange", solver="Euler", step_size=1e-4, stop_time=0.2,
                                          output=["r", "l"], start_values=tilted),
}
out = {name: [[float(x).hex() for x in np.concatenate([np.ravel(row[n]) for n in r.dtype.names])] for row in r]
       for name, r in runs.items()}
print(json.dumps({"platform": platform_tuple, "runs": out}))
"""


def test_fmpy_on_arm64_runs_the_aarch64_binary_with_the_bits_of_x86_64(tmp_path, setting):
    """FMPy 0.3.32 on an arm64 CPython (Debian 12's, under qemu-user) picks the FMI 3 FMU's
    `aarch64-linux` binary and gives, in Co-Simulation and in Model Exchange with its own
    Euler loop, the bits FMPy gives on x86-64 with the `x86_64-linux` binary."""
    import json
    import sys
    fmu = FMI3_DIR / "StewartPlatform.fmu"
    script = tmp_path / "fmpy_runs.py"
    script.write_text(FMPY_RUNS)
    command, site = P.arm64_python(sys.executable)
    arm = subprocess.run(command + [str(script), str(fmu), str(site)], capture_output=True, text=True, timeout=900)
    assert arm.returncode == 0, arm.stderr[-3000:]
    x86 = subprocess.run([sys.executable, str(script), str(fmu)], capture_output=True, text=True, timeout=900)
    assert x86.returncode == 0, x86.stderr[-3000:]
    arm_runs, x86_runs = json.loads(arm.stdout.splitlines()[-1]), json.loads(x86.stdout.splitlines()[-1])
    assert arm_runs["platform"] == "aarch64-linux" and x86_runs["platform"] == "x86_64-linux"
    for name, rows in x86_runs["runs"].items():
        other = arm_runs["runs"][name]
        assert [len(r) for r in rows] == [len(r) for r in other], name
        differing = sum(a != b for r, s in zip(rows, other) for a, b in zip(r, s))
        print(f"FMPy FMI 3 {name}: {len(rows)} rows of {len(rows[0])} values, aarch64 (qemu) against x86-64: "
              f"{differing} differ")
        assert len(rows) == len(other) > 10 and differing == 0, name
    # The fall ends on the stops (the last row's Fstop, after r and l: 3 + 6 values in).
    fall = [float.fromhex(x) for x in x86_runs["runs"]["fall onto the stops"][-1]]
    assert min(fall[1 + 9:1 + 15]) > 1e3
