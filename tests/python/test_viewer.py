"""The 3-D viewer in a real browser: Debian's headless Chromium driven by Playwright loads the
built page (viewer/dist) with a 10 s result at 1 ms written by `stewart_fmu.viewer.view`, seeks
to given times and reads back, through the page's test hook, the twelve leg end points and the
platform pose: they equal the ones computed here from the same CSV to 1e-9. No console errors,
a non-blank screenshot, and a file that is not a platform result gets a message naming the
missing columns. The machine (docs/model.md §8): each leg drawn as a cylinder from its base
joint and a rod to its platform joint, and the joints the open-loop ripple leaves beyond their
angle limits drawn red, the same ones Python finds in the CSV."""

import csv
import functools
import http.server
import json
import re
import shutil
import subprocess
import threading

import numpy as np
import pytest
from matplotlib.image import imread

from stewart_fmu import ROOT
from stewart_fmu.cosim import closed_loop
from stewart_fmu.machine import ripple_run
from stewart_fmu.viewer import VIEW_OUTPUTS, stand, view
from references import check_reference

TIMES = [0.0, 0.6049, 1.25, 3.3333, 7.0, 9.999]


class QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    """The default controller on the heave programme from a tilted start, 10 s at 1 ms (SI),
    written with the viewer into a folder served on 127.0.0.1."""
    if not shutil.which("node") or not shutil.which("chromium"):
        pytest.fail("node and Debian's chromium are needed (tests/run_all.sh installs them)")
    folder = tmp_path_factory.mktemp("viewer")
    start = {"angles0[1]": 0.03, "angles0[3]": -0.02, "r0[1]": 0.02}
    t, rows, _, status = closed_loop(10.0, 1e-3, platform_reals=start, record=tuple(VIEW_OUTPUTS))
    assert status == "ok"
    result = dict(time=t, **{n: rows[:, j] for j, n in enumerate(VIEW_OUTPUTS)})
    view(result, stand(start), folder, "tilted", "tilted start")
    address = view(ripple_run(10.0, 0.01)[0], stand(), folder, "ripple", "ripple on the joint limits")
    # The symmetric heave (roll, pitch and yaw only round-off) with one impact-like spike in
    # F[1], under a file name that must be encoded in a URL.
    t, rows, _, status = closed_loop(2.0, 1e-3, record=tuple(VIEW_OUTPUTS))
    assert status == "ok"
    spiked = dict(time=t, **{n: rows[:, j].copy() for j, n in enumerate(VIEW_OUTPUTS)})
    spiked["F[1]"][500] = 1e6
    rest_address = view(spiked, stand(), folder, "heave at rest #1", "heave, round-off angles, a spike in F[1]")
    handler = functools.partial(QuietHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    root = f"http://127.0.0.1:{server.server_address[1]}/"
    yield (folder, root + "index.html?data=data/tilted.csv&stand=data/tilted.stand.json", result, root + address,
           root + rest_address)
    server.shutdown()


def browse(url, shot, times):
    """check.mjs's report of the page at `url`, seeking to `times`; the screenshot at the last."""
    run = subprocess.run(["node", str(ROOT / "viewer" / "test" / "check.mjs"), url, str(shot),
                          ",".join(map(str, times))], capture_output=True, text=True, cwd=ROOT / "viewer", timeout=180)
    assert run.returncode == 0, run.stderr[-3000:]
    report = json.loads(run.stdout.strip().splitlines()[-1])
    assert report["loadError"] is None, report["loadError"]
    assert report["errors"] == []
    return report


def browse_served(folder, address, shot, times):
    """`browse` of the page at `address` in `folder`, served on loopback for the call."""
    handler = functools.partial(QuietHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        return browse(f"http://127.0.0.1:{server.server_address[1]}/{address}", shot, times)
    finally:
        server.shutdown()


def row(folder, name, t):
    """The columns of the CSV the page read and the last row at or before t."""
    with open(folder / "data" / f"{name}.csv") as f:
        names = next(csv.reader(f))
    data = np.loadtxt(folder / "data" / f"{name}.csv", delimiter=",", skiprows=1)
    col = {n: data[:, j] for j, n in enumerate(names)}
    return col, max(int(np.searchsorted(col["time"], t, side="right")) - 1, 0)


def expected(folder, t, name="tilted"):
    """Leg end points at the last row at or before t, from the CSV the page read."""
    col, i = row(folder, name, t)
    r = np.array([col[f"r[{a}]"][i] for a in (1, 2, 3)])
    rot = np.array([[col[f"R[{a},{b}]"][i] for b in (1, 2, 3)] for a in (1, 2, 3)])
    s = json.loads((folder / "data" / f"{name}.stand.json").read_text())
    return col["time"][i], [[s["B"][k], list(r + rot @ np.array(s["A"][k]))] for k in range(6)], r, rot


def test_the_browser_shows_the_same_legs_as_python(served, tmp_path):
    folder, url, result, _, _ = served
    shot = tmp_path / "viewer.png"
    report = browse(url, shot, TIMES)
    assert report["rows"] == len(result["time"]) == 10000
    worst = 0.0
    for sample in report["samples"]:
        t_row, ends, r, rot = expected(folder, sample["t"])
        assert sample["time"] == t_row
        worst = max(worst, np.max(np.abs(np.array(sample["ends"]) - np.array(ends))),
                    np.max(np.abs(np.array(sample["pose"]["r"]) - r)), np.max(np.abs(np.array(sample["pose"]["R"]) - rot)))
    image = imread(shot)
    pixels = image[..., :3].reshape(-1, 3)
    distinct = len(np.unique((pixels * 255).astype(np.uint8), axis=0))
    print(f"viewer: {report['rows']} rows loaded in {report['loadSeconds']:.2f} s (headless Chromium, page load to "
          f"ready); leg end points and pose at {len(TIMES)} times within {worst:.1e} m of Python; screenshot "
          f"{image.shape[1]}x{image.shape[0]}, {distinct} distinct colours, std {pixels.std():.3f}; console errors "
          f"{report['errors']}; bad file: {report['badFile']['error']!r}")
    assert worst < 1e-9
    assert distinct > 50 and pixels.std() > 0.05, "the screenshot is blank"
    message = report["badFile"]["error"]
    assert message.startswith("not a platform result: missing columns") and "r[2]" in message and "R[1,1]" in message
    assert report["badFile"]["shown"] == message
    # The dataset menu lists every result written into the folder, also when the address
    # names one (?data=), and selects that one.
    menu = report["shown"]["datasets"]
    assert [d["data"] for d in menu] == ["data/tilted.csv", "data/ripple.csv", "data/heave at rest #1.csv"]
    assert [d["selected"] for d in menu] == [True, False, False]
    # The plots have a time axis over the run (1 ms .. 10 s) and a key.
    plots = report["shown"]["plots"]
    assert (plots["plot-heave"]["t0"], plots["plot-heave"]["t1"]) == (result["time"][0], result["time"][-1])
    assert plots["plot-angles"]["key"] == ["roll", "pitch", "yaw"]
    assert plots["plot-legs"]["key"] == ["1", "2", "3", "4", "5", "6"]
    assert plots["plot-heave"]["ticks"] == [2, 4, 6, 8, 10]
    # Pose that is not a number: rows from the first NaN are left out, with a message naming
    # the row and column; NaN from the first row is an error.
    nan = report["nan"]
    print(f"viewer: NaN pose from row 4: {nan['later']['message']!r}; from row 1: {nan['first']['error']!r}")
    assert nan["later"]["error"] is None and nan["later"]["rows"] == 3
    assert "not a number (NaN)" in nan["later"]["message"] and "column r[2], row 4 of 5 (t = 0.3)" in nan["later"]["message"]
    assert "not a number (NaN) from the first row" in nan["first"]["error"] and "column r[3]" in nan["first"]["error"]
    assert nan["first"]["message"] == nan["first"]["error"]
    shutil.copyfile(shot, ROOT / "target" / "viewer_screenshot.png")


def test_the_plots_keep_round_off_flat_and_the_force_scale_shows_the_working_range(served, tmp_path):
    """The symmetric heave's roll, pitch and yaw are round-off: the angles plot spans at least
    1e-3 rad about them instead of blowing 1e-16 up to its height. One spike of 1e6 N in F[1]
    does not set the force colours: the scale ends at the 98th percentile of |F| (as numpy
    computes it from the CSV), and the legend says that it is clipped and names the peak. The
    result's file name has a space and a '#', which the address and the fetches encode."""
    folder, _, _, _, url = served
    assert "%20" in url and "%23" in url
    report = browse(url, tmp_path / "rest.png", [0.5, 1.999])
    col, _ = row(folder, "heave at rest #1", 0.0)
    assert report["rows"] == len(col["time"]) == 2000
    angles = np.array([col[f"angles[{a}]"] for a in (1, 2, 3)])
    lo, hi = report["shown"]["plots"]["plot-angles"]["lo"], report["shown"]["plots"]["plot-angles"]["hi"]
    forces = np.abs(np.array([col[f"F[{k}]"] for k in range(1, 7)]))
    scale = report["shown"]["forceScale"]
    legend = report["shown"]["legend"]
    print(f"viewer: angles round-off {np.max(np.abs(angles)):.1e} rad plotted over [{lo:.3g}, {hi:.3g}]; force scale "
          f"{scale['limit']:.6g} N (98th percentile of |F|, numpy {np.percentile(forces, 98):.6g}), peak "
          f"{scale['peak']:.3g} N; legend {legend}")
    assert 0 < np.max(np.abs(angles)) < 1e-12
    assert hi - lo >= 1e-3 - 1e-15 and lo <= angles.min() and hi >= angles.max()
    assert scale["limit"] == pytest.approx(np.percentile(forces, 98), rel=1e-12)
    assert scale["limit"] < 1e4 < scale["peak"] == 1e6 and scale["clipped"]
    assert "clipped" in legend["clipped"] and "1.00e+6" in legend["clipped"]
    ends = [float(x) for x in re.findall(r"[\u2264\u2265] (\S+)", legend["scale"])]
    assert ends == pytest.approx([-scale["limit"], scale["limit"]], rel=5e-3), legend["scale"]


def red_pixels(shot):
    """Pixels of the joint-limit red (0xd0021b, lit) in a screenshot."""
    image = imread(shot)[..., :3]
    return int(np.sum((image[..., 0] > 0.55) & (image[..., 1] < 0.2) & (image[..., 2] < 0.25)))


def test_the_browser_draws_the_legs_as_two_bodies_and_the_joints_at_their_limits(served, tmp_path):
    """The ripple result (open loop, joint limits on): at each time the page's joints beyond
    their limit are those whose angle in the CSV exceeds the stand's limit, and the scene draws
    exactly those red; before the tilt none is. Each leg is a cylinder from B_k and a rod to
    a_k along the leg, of twice the centre-of-mass distances lengthened to overlap 5 % at the
    longest leg."""
    folder, _, _, url, _ = served
    s = json.loads((folder / "data" / "ripple.stand.json").read_text())
    times = [0.5, 0.95, 1.4, 5.0, 9.99]
    calm, limits = tmp_path / "calm.png", tmp_path / "limits.png"
    browse(url, calm, [0.5])
    report = browse(url, limits, times)
    cylinder, rod = 2 * s["cylinderCoM"], 2 * s["rodCoM"]
    grow = max(1.0, 1.05 * max(s["lmax"]) / (cylinder + rod))
    cylinder, rod = cylinder * grow, rod * grow
    worst, seen = 0.0, []
    for sample in report["samples"]:
        col, i = row(folder, "ripple", sample["t"])
        want = {"base": [bool(col[f"thetaB[{k}]"][i] > s["baseMaxAngle"]) for k in range(1, 7)],
                "platform": [bool(col[f"thetaA[{k}]"][i] > s["platformMaxAngle"]) for k in range(1, 7)]}
        assert sample["jointsAtLimit"] == want, (sample["t"], sample["jointsAtLimit"], want)
        assert sample["highlighted"] == want, (sample["t"], sample["highlighted"], want)
        seen.append(sum(want["platform"]) + sum(want["base"]))
        _, ends, _, _ = expected(folder, sample["t"], "ripple")
        for (b, a), body in zip(ends, sample["bodies"]):
            b, a = np.array(b), np.array(a)
            n = (a - b) / np.linalg.norm(a - b)
            worst = max(worst, np.max(np.abs(np.array(body["cylinder"]) - [b, b + cylinder * n])),
                        np.max(np.abs(np.array(body["rod"]) - [a - rod * n, a])))
    red_calm, red_limits = red_pixels(calm), red_pixels(limits)
    print(f"viewer, ripple: joints beyond their limits at t = {times}: {seen}; leg bodies within {worst:.1e} m; "
          f"limit-red pixels {red_calm} at t = 0.5 s, {red_limits} at t = 9.99 s")
    assert worst < 1e-9
    assert seen[0] == 0 and seen[-1] >= 1
    assert red_limits > red_calm + 100
    shutil.copyfile(limits, ROOT / "target" / "viewer_joint_limits_screenshot.png")


def test_the_viewers_default_stand_is_the_fmus():
    """viewer/src/result.js's defaultStand() (drawn when no stand file is given) is the FMU's
    start values of B, A, lmin and lmax to the bit: viewer/src/default_stand.json is written
    from its model description (references.py rewrites it), and the page reads that file."""
    fmu = stand()
    written = "{\n" + ",\n".join(f' "{name}": {json.dumps(fmu[name])}' for name in ("B", "A", "lmin", "lmax")) + "\n}\n"
    check_reference(ROOT / "viewer" / "src" / "default_stand.json", written)
    if not shutil.which("node"):
        pytest.fail("node is needed (tests/run_all.sh installs it)")
    script = "import { defaultStand } from './viewer/src/result.js'; console.log(JSON.stringify(defaultStand()));"
    run = subprocess.run(["node", "--no-warnings", "--input-type=module", "-e", script], cwd=ROOT, capture_output=True,
                         text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    drawn = json.loads(run.stdout)
    print(f"viewer's default stand: the FMU's start values of B, A, lmin {drawn['lmin']} and lmax {drawn['lmax']}")
    assert len(drawn["B"]) == len(drawn["A"]) == 6
    assert all(drawn[name] == fmu[name] for name in ("B", "A", "lmin", "lmax"))


def test_a_hydraulic_result_colours_the_cylinders_by_load_pressure(tmp_path):
    """Hydraulic legs fed by the power unit on the heave programme (drive = 2, hydraulic.supply =
    1): the page colours the cylinders by the load pressure pA - (A_B/A_A) pB, its scale the 98th
    percentile of |p_L| in MPa as numpy computes it from the CSV and the stand's bore and rod; the
    pressure, spool and power unit plots span the CSV's values."""
    from stewart_fmu.viewer import HYDRAULIC_VIEW_OUTPUTS
    record = tuple(VIEW_OUTPUTS + HYDRAULIC_VIEW_OUTPUTS)
    t, rows, _, status = closed_loop(3.0, 1e-3, platform_reals={"drive": 2, "hydraulic.supply": 1},
                                     controller_integers={"drive": 2}, record=record)
    assert status == "ok"
    result = dict(time=t, **{n: rows[:, j] for j, n in enumerate(record)})
    folder = tmp_path / "hydraulic"
    address = view(result, stand({"drive": 2}), folder, "hydraulic", "hydraulic legs")
    report = browse_served(folder, address, tmp_path / "hydraulic.png", [1.0, 2.9])
    s = json.loads((folder / "data" / "hydraulic.stand.json").read_text())
    ratio = (s["bore"] ** 2 - s["rod"] ** 2) / s["bore"] ** 2
    load = np.array([(result[f"pA[{k}]"] - ratio * result[f"pB[{k}]"]) / 1e6 for k in range(1, 7)])
    spools = np.array([result[f"spool[{k}]"] for k in range(1, 7)])
    # The plots draw every stride-th row (about 600 points).
    stride = max(1, len(t) // 600)
    load_drawn, spools_drawn = load[:, ::stride], spools[:, ::stride]
    scale, plots, legend = report["shown"]["forceScale"], report["shown"]["plots"], report["shown"]["legend"]
    print(f"viewer, hydraulic legs: colour scale {scale['limit']:.4f} MPa (numpy {np.percentile(np.abs(load), 98):.4f}); "
          f"pressure plot [{plots['plot-pressures']['lo']:.3f}, {plots['plot-pressures']['hi']:.3f}] MPa, spools "
          f"[{plots['plot-valves']['lo']:.3f}, {plots['plot-valves']['hi']:.3f}]; legend {legend['scale']!r}")
    assert s["bore"] == 0.063 and s["rod"] == 0.036
    assert scale["limit"] == pytest.approx(np.percentile(np.abs(load), 98), rel=1e-9)
    assert plots["plot-pressures"]["lo"] == pytest.approx(load_drawn.min(), abs=1e-12)
    assert plots["plot-pressures"]["hi"] == pytest.approx(load_drawn.max(), abs=1e-12)
    assert plots["plot-valves"]["lo"] == pytest.approx(spools_drawn.min(), abs=1e-12)
    assert plots["plot-valves"]["hi"] == pytest.approx(spools_drawn.max(), abs=1e-12)
    assert plots["plot-valves"]["key"] == ["1", "2", "3", "4", "5", "6"]
    supply_drawn = np.array([result["supply.pressure"] / 1e6, result["accumulator.oilVolume"] * 1e3])[:, ::stride]
    print(f"power unit plot [{plots['plot-supply']['lo']:.3f}, {plots['plot-supply']['hi']:.3f}]")
    assert plots["plot-supply"]["lo"] == pytest.approx(supply_drawn.min(), abs=1e-12)
    assert plots["plot-supply"]["hi"] == pytest.approx(supply_drawn.max(), abs=1e-12)
    assert plots["plot-supply"]["key"] == ["supply pressure, MPa", "accumulator oil, L"]


def test_a_cueing_result_plots_the_vehicles_and_the_simulators_cues(tmp_path):
    """The braking through the motion system (cueing -> controller -> platform): the page plays
    the cabin's motion and plots the vehicle's and the simulator's specific force (g off the
    vertical) and angular velocity in pairs, their ranges those of the CSV's values."""
    from stewart_fmu import cueing, vehicle
    run = cueing.motion_system(vehicle.brake(duration=8.0), h=2e-3, record=tuple(VIEW_OUTPUTS))
    result = {n: c[::5] for n, c in run.items()}
    folder = tmp_path / "cueing"
    address = view(result, stand(), folder, "cueing", "motion cueing")
    report = browse_served(folder, address, tmp_path / "cueing.png", [1.0, 6.0])
    plots = report["shown"]["plots"]
    stride = max(1, len(result["time"]) // 600)
    force = np.array([result[f"{n}[{k}]"] - (9.81 if k == 3 else 0.0) for k in (1, 2, 3) for n in ("f", "fsim")])
    rate = np.array([result[f"{n}[{k}]"] for k in (1, 2, 3) for n in ("omega", "omegasim")])
    assert plots["plot-force-cues"]["lo"] == pytest.approx(force[:, ::stride].min(), abs=1e-12)
    assert plots["plot-force-cues"]["hi"] == pytest.approx(force[:, ::stride].max(), abs=1e-12)
    assert plots["plot-rate-cues"]["hi"] == pytest.approx(max(rate[:, ::stride].max(), rate[:, ::stride].min() + 1e-4),
                                                          abs=1e-12)
    assert plots["plot-force-cues"]["key"][:2] == ["vehicle x", "simulator x"]
    assert plots["plot-pressures"]["key"] == [], "no hydraulic series in a cueing result"
    # The cabin pitches nose down as the braking's cue: the page's pose at 6 s has the CSV's pitch.
    t_row, ends, r, rot = expected(folder, 6.0, "cueing")
    sample = report["samples"][-1]
    assert sample["time"] == t_row and np.max(np.abs(np.array(sample["pose"]["R"]) - rot)) < 1e-12
    assert rot[0, 2] > 0.1, "the braking's tilt: sin(pitch) > 0.1"
    print(f"viewer, motion cueing: force plot [{plots['plot-force-cues']['lo']:.3f}, {plots['plot-force-cues']['hi']:.3f}] "
          f"m/s2, rate plot [{plots['plot-rate-cues']['lo']:.4f}, {plots['plot-rate-cues']['hi']:.4f}] rad/s")
