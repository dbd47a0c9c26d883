"""Fuzz over study files (issue 28): seeded random mutations of small valid studies (random keys,
near-miss names, values of every TOML type, NaN, infinities, 1e300, negative and zero times,
broken sections, invalid TOML) given to `stewart-sweep`. Each case runs in a child process
with a time limit, so a hang is a failure, not a stuck test. For every case:

- `--check` returns 0 with a plan, or 2 with a message that starts `stewart-sweep:` and names
  something; never an exception or a traceback;
- a case that passes the check and is small is run for real (`--serial`, the packaged FMUs):
  exit 0 or 1, one row per run, every failed row with a message; and run again it resumes
  with nothing to do and does not crash.

STEWART_FUZZ_CASES sets the number of cases (default 300); the seed is fixed, so a failure
prints the case and reproduces."""

import contextlib
import copy
import datetime
import io
import json
import math
import multiprocessing
import os
import random
import resource
import traceback

import pytest

from stewart_fmu.sweep import load_results

CASES = int(os.environ.get("STEWART_FUZZ_CASES", "300"))
CHECK_LIMIT = 20.0  # s for --check of one case
RUN_LIMIT = 90.0  # s for running one small case twice

BASES = [
    {"study": {"name": "fuzz", "system": "closed-loop", "units": "nondimensional", "stop_time": 0.05, "step": 0.01,
               "stable_error": 0.01},
     "fixed": {"controller.heave.centre[3]": 1.3059496109441155, "controller.heave.amplitude": 0.2},
     "grid": {"controller.G": [2.0, 10.0]},
     "random": {"samples": 2, "seed": 3, "platform.M": {"uniform": [0.9, 1.1]}},
     "plot": [{"kind": "scatter", "x": "controller.G", "value": "max_leg_error", "file": "g.png"}]},
    {"study": {"name": "fuzz-platform", "system": "platform", "units": "si", "stop_time": 0.02, "step": 0.005},
     "fixed": {"scenario.power_loss_at": 0.01},
     "grid": {"platform.M": [2500.0, 3500.0]},
     "plot": [{"kind": "histogram", "value": "final_z", "file": "z.png"}]},
]
NAMES = ["study", "fixed", "grid", "random", "plot", "name", "system", "units", "stop_time", "step", "stable_error",
         "stop_contact_unstable", "samples", "seed", "uniform", "normal", "kind", "x", "y", "facet", "value", "file",
         "log", "bins", "title", "platform.M", "platform.J[1]", "platform.com_offset[3]", "platform.stops",
         "platform.solver.method", "platform.F[1]", "platform.r[3]", "controller.G", "controller.D",
         "controller.programme", "controller.l[1]", "scenario.power_loss_at", "scenario.failed_leg",
         "scenario.failure_time", "platform", "controller", "G", "map", "scatter", "histogram", "closed-loop", "si"]
VALUES = [0, 1, 2, 6, 7, -3, 10**7, 2**63 - 1, 0.0, -0.0, 0.01, -0.01, 0.5, 1e-300, 1e300, -1e300, math.nan, math.inf,
          -math.inf, True, False, "", "heavy", "10 ms", "../../x.png", "/tmp/x.png", "x.txt", "a.png", "map",
          "platform.M", "controller.G", "step", "closed-loop", "platform", "nondimensional", [], [1], [2000.0],
          [0.0, 0.01], [-0.01, 0.01], ["a"], [[1.0]], [1.0, 1.0], [math.nan], {}, {"uniform": [2000.0]},
          {"uniform": [1.0, 0.5]}, {"normal": [1.0, -1.0]}, {"normal": [1.0, 0.1]}, {"bogus": 1},
          {"uniform": [0.9, 1.1], "normal": [1, 1]}, datetime.datetime(2026, 1, 1, 12, 0), datetime.date(2026, 1, 1)]


def typo(rng, name):
    i = rng.randrange(len(name) + 1)
    edit = rng.choice(["insert", "delete", "swap", "replace"])
    letter = rng.choice("abcdefghijklmnopqrstuvwxyz_.[]1")
    if edit == "insert" or len(name) < 2:
        return name[:i] + letter + name[i:]
    i = min(i, len(name) - 2)
    if edit == "delete":
        return name[:i] + name[i + 1:]
    if edit == "swap":
        return name[:i] + name[i + 1] + name[i] + name[i + 2:]
    return name[:i] + letter + name[i + 1:]


def random_value(rng, depth=0):
    if depth < 2 and rng.random() < 0.15:
        return [random_value(rng, depth + 1) for _ in range(rng.randrange(4))]
    if depth < 2 and rng.random() < 0.1:
        return {rng.choice(NAMES): random_value(rng, depth + 1) for _ in range(rng.randrange(3))}
    if rng.random() < 0.2:
        return rng.uniform(-10, 10) * 10 ** rng.randrange(-5, 8)
    return copy.deepcopy(rng.choice(VALUES))  # a copy: a mutation must not change VALUES


def tables(spec):
    """(parent, key) of every table or list in the spec, the places a mutation can act."""
    found = [(None, None)]
    stack = [spec]
    while stack:
        node = stack.pop()
        items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else []
        for k, v in items:
            if isinstance(v, (dict, list)):
                found.append((node, k))
                stack.append(v)
    return found


def mutate(rng, spec):
    for _ in range(rng.randint(1, 3)):
        parent, key = rng.choice(tables(spec))
        node = spec if parent is None else parent[key]
        action = rng.choice(["set", "set", "add", "rename", "delete", "replace"])
        if isinstance(node, list):
            if node and action in ("set", "rename", "delete"):
                i = rng.randrange(len(node))
                if action == "delete":
                    del node[i]
                else:
                    node[i] = random_value(rng)
            else:
                node.append(random_value(rng))
        elif action == "replace" and parent is not None:
            parent[key] = random_value(rng)
        elif action == "add" or not node:
            name = rng.choice([rng.choice(NAMES), typo(rng, rng.choice(NAMES)),
                               "".join(rng.choice("abcxyz._[]1") for _ in range(rng.randint(1, 8)))])
            node[name] = random_value(rng)
        else:
            k = rng.choice(list(node))
            if action == "set":
                node[k] = random_value(rng)
            elif action == "rename":
                node[typo(rng, k)] = node.pop(k)
            else:
                del node[k]
    return spec


# ----- a TOML writer (the standard library only reads TOML) -----------------------------------

def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (datetime.date, datetime.datetime)):
        return v.isoformat()
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{json.dumps(k)} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(type(v))


def toml(spec):
    lines = [f"{json.dumps(k)} = {toml_value(v)}" for k, v in spec.items()
             if not isinstance(v, dict) and not (isinstance(v, list) and v and all(isinstance(x, dict) for x in v))]
    for k, v in spec.items():
        if isinstance(v, dict):
            lines.append(f"[{json.dumps(k)}]")
            lines += [f"{json.dumps(a)} = {toml_value(b)}" for a, b in v.items()]
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for table in v:
                lines.append(f"[[{json.dumps(k)}]]")
                lines += [f"{json.dumps(a)} = {toml_value(b)}" for a, b in table.items()]
    return "\n".join(lines) + "\n"


def case(seed):
    rng = random.Random(seed)
    spec = json.loads(json.dumps(rng.choice(BASES)))
    if rng.random() < 0.03:
        return "".join(rng.choice('[]"=\n .abc123{},') for _ in range(rng.randrange(80)))  # not TOML
    return toml(mutate(rng, spec))


# ----- the child process that runs the cases --------------------------------------------------

MEMORY_LIMIT = 4 << 30  # bytes of address space for the child: a blow-up is a MemoryError, not the machine's


def _serve(conn):
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    from stewart_fmu import sweep
    while True:
        argv = conn.recv()
        stdout, stderr = io.StringIO(), io.StringIO()
        try:
            with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
                status = sweep.main(argv)
            crash = None
        except SystemExit as e:
            status, crash = e.code, None
        except BaseException:  # noqa: BLE001 - what the fuzz is looking for
            status, crash = None, traceback.format_exc()
        conn.send((status, stdout.getvalue(), stderr.getvalue(), crash))


class Sandbox:
    """A child process that runs stewart-sweep's main(); killed and replaced on a time-out."""

    def __init__(self):
        self.ctx = multiprocessing.get_context("fork")
        self.process = None

    def _start(self):
        self.conn, child = self.ctx.Pipe()
        self.process = self.ctx.Process(target=_serve, args=(child,), daemon=True)
        self.process.start()
        child.close()  # so that the child's death reads as the end of the pipe here

    def run(self, argv, limit):
        if self.process is None or not self.process.is_alive():
            self._start()
        self.conn.send(argv)
        if not self.conn.poll(limit):
            self.close()
            return "hang", "", "", None
        try:
            return self.conn.recv()
        except EOFError:
            self.process.join(5)
            code = self.process.exitcode
            self.close()
            return None, "", "", f"the child process died (exit code {code})"

    def close(self):
        if self.process is not None:
            self.process.kill()
            self.process.join()
            self.process = None


@pytest.fixture
def sandbox():
    box = Sandbox()
    yield box
    box.close()


def test_random_study_files_are_refused_with_a_message_or_run_without_crashing(tmp_path, sandbox):
    counts = {"refused": 0, "valid": 0, "executed": 0, "failed rows": 0}
    failures = []
    for seed in range(CASES):
        text = case(seed)
        path = tmp_path / f"case{seed}.toml"
        path.write_text(text)
        status, out, err, crash = sandbox.run([str(path), "--check"], CHECK_LIMIT)
        problem = None
        if status == "hang":
            problem = f"--check did not return within {CHECK_LIMIT:g} s"
        elif crash:
            problem = f"--check crashed:\n{crash}"
        elif status == 2:
            counts["refused"] += 1
            if not (err.startswith("stewart-sweep: ") and len(err.strip()) > len("stewart-sweep: x: ")):
                problem = f"refused without a message: {err!r}"
        elif status == 0:
            counts["valid"] += 1
            if "\n  runs: " not in out or "nothing was run" not in out:
                problem = f"--check passed without a plan: {out!r}"
            else:
                problem = execute(sandbox, path, tmp_path / f"out{seed}", out, counts)
        else:
            problem = f"--check exit status {status!r}: {err}"
        if problem:
            failures.append(f"case {seed}: {problem}\n--- study file ---\n{text}")
    print(f"{CASES} random study files: {counts}")
    assert not failures, f"{len(failures)} of {CASES} cases failed; the first:\n" + failures[0]
    assert counts["refused"] > CASES // 4 and counts["valid"] > 5 and counts["executed"] > 3, counts


def execute(sandbox, path, out, plan, counts):
    """Runs a small valid case twice; a message if something is wrong."""
    runs = int(plan.split("\n  runs: ")[1].split(" (--max-runs")[0].split(" = ")[-1])
    fewest, most = plan.split("(varied runs: ")[1].split(" steps")[0].split(" .. ")
    if runs > 4 or int(most) > 400:
        return None
    counts["executed"] += 1
    for attempt in range(2):
        status, stdout, stderr, crash = sandbox.run([str(path), "--out", str(out), "--serial"], RUN_LIMIT / 2)
        if status == "hang":
            return f"the run did not end within {RUN_LIMIT / 2:g} s"
        if crash:
            return f"the run crashed:\n{crash}"
        if status not in (0, 1):
            return f"the run's exit status {status!r}: {stderr[-500:]}"
        if "Traceback" in stderr:
            return f"a traceback: {stderr[-1500:]}"
        if attempt == 1 and f"{runs} done already, running 0" not in stdout:
            return f"the second call did not resume: {stdout[:300]}"
    rows = load_results(out)
    if len(rows) != runs or not rows["run_id"].is_unique:
        return f"{len(rows)} rows for {runs} runs"
    failed = rows[rows["status"] != "ok"]
    counts["failed rows"] += len(failed)
    if (failed["message"].str.len() == 0).any():
        return "a failed row without a message"
    if status == 1 and not (rows["status"] == "error").all():
        return "exit 1 although not every run failed"
    return None
