"""The 3-D viewer in a real browser: Debian's headless Chromium driven by Playwright loads the
built page (viewer/dist) with a 10 s result at 1 ms written by `stewart_fmu.viewer.view`, seeks
to given times and reads back, through the page's test hook, the twelve leg end points and the
platform pose: they equal the ones computed here from the same CSV to 1e-9. No console errors,
a non-blank screenshot, and a file that is not a platform result gets a message naming the
missing columns."""

import csv
import functools
import http.server
import json
import shutil
import subprocess
import threading

import numpy as np
import pytest
from matplotlib.image import imread

from stewart_fmu import ROOT
from stewart_fmu.cosim import closed_loop
from stewart_fmu.viewer import VIEW_OUTPUTS, stand, view

TIMES = [0.0, 0.6049, 1.25, 3.3333, 7.0, 9.999]


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
    address = view(result, stand(start), folder, "tilted", "tilted start")
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(folder))
    handler.log_message = lambda *args: None
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield folder, f"http://127.0.0.1:{server.server_address[1]}/{address}", result
    server.shutdown()


def expected(folder, t):
    """Leg end points at the last row at or before t, from the CSV the page read."""
    with open(folder / "data" / "tilted.csv") as f:
        names = next(csv.reader(f))
    data = np.loadtxt(folder / "data" / "tilted.csv", delimiter=",", skiprows=1)
    col = {n: data[:, j] for j, n in enumerate(names)}
    i = max(int(np.searchsorted(col["time"], t, side="right")) - 1, 0)
    r = np.array([col[f"r[{a}]"][i] for a in (1, 2, 3)])
    rot = np.array([[col[f"R[{a},{b}]"][i] for b in (1, 2, 3)] for a in (1, 2, 3)])
    s = json.loads((folder / "data" / "tilted.stand.json").read_text())
    return col["time"][i], [[s["B"][k], list(r + rot @ np.array(s["A"][k]))] for k in range(6)], r, rot


def test_the_browser_shows_the_same_legs_as_python(served, tmp_path):
    folder, url, result = served
    shot = tmp_path / "viewer.png"
    run = subprocess.run(["node", str(ROOT / "viewer" / "test" / "check.mjs"), url, str(shot),
                          ",".join(map(str, TIMES))], capture_output=True, text=True, cwd=ROOT / "viewer", timeout=180)
    assert run.returncode == 0, run.stderr[-3000:]
    report = json.loads(run.stdout.strip().splitlines()[-1])
    assert report["loadError"] is None, report["loadError"]
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
    assert report["errors"] == []
    assert distinct > 50 and pixels.std() > 0.05, "the screenshot is blank"
    message = report["badFile"]["error"]
    assert message.startswith("not a platform result: missing columns") and "r[2]" in message and "R[1,1]" in message
    assert report["badFile"]["shown"] == message
    shutil.copyfile(shot, ROOT / "target" / "viewer_screenshot.png")
