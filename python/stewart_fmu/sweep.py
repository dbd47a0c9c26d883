"""`stewart-sweep STUDY.toml --out DIR [--fmu PATH] [--scheduler ADDRESS] [--workers N] [--limit N] [--serial]`:
runs a design study (see `stewart_fmu.study`) on Dask.

- The study file is checked first (`stewart_fmu.study_schema`; docs/studies.md): a file with
  problems, or of more than `--max-runs` runs, is refused before anything runs.
  `--check` prints the plan and exits.
- One sweep per `DIR` at a time: `DIR/.stewart-sweep.lock` (`StudyLock`).
- Without `--scheduler` it starts a `LocalCluster` on this machine (`--workers` processes, one
  thread each; default: one per core). With it, it connects to a running scheduler (`dask
  scheduler` and `dask worker` elsewhere, dask-jobqueue, Kubernetes); the FMUs travel to the
  workers as bytes, so no shared file system is needed. `--serial` runs in this process
  without Dask (the reference for "same rows wherever they ran").
- Rows go to `DIR/results.parquet/` (a Parquet dataset, one file per batch, each written
  atomically) as runs finish: an interrupted study keeps what was done, and running it again
  with the same `DIR` runs only the missing runs.
- A progress line with rate and ETA on stderr; at the end a summary (`DIR/summary.txt`) and
  the study's plots (`DIR/*.png`).
- A failed run is a row with its status and message. A worker that dies has its runs
  re-executed elsewhere by Dask; each run's row is written once.
- Exit status: 0 done, 1 every run failed (the first error is printed) or a plot could not be
  written, 2 the study could not start (the message says why).
"""

import argparse
import faulthandler
import fcntl
import itertools
import json
import math
import os
import shutil
import socket
import sys
import time
import uuid
from pathlib import Path

import pandas as pd

from . import study as st
from . import study_schema


def results_dir(out):
    return Path(out) / "results.parquet"


def load_results(out):
    """All rows written so far (an empty frame if none)."""
    folder = results_dir(out)
    parts = sorted(folder.glob("part-*.parquet")) if folder.exists() else []
    if not parts:
        return pd.DataFrame()
    return pd.concat([pd.read_parquet(p) for p in parts], ignore_index=True)


class Writer:
    """Appends rows to the dataset in batches (at most every `interval` seconds)."""

    def __init__(self, out, interval=1.0):
        self.folder = results_dir(out)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.pending, self.interval, self.last = [], interval, time.monotonic()

    def add(self, row):
        self.pending.append(row)
        if time.monotonic() - self.last >= self.interval:
            self.flush()

    def flush(self):
        if self.pending:
            name = f"part-{time.time_ns():020d}-{uuid.uuid4().hex[:8]}.parquet"
            tmp = self.folder / f".{name}.tmp"
            pd.DataFrame(self.pending).to_parquet(tmp, index=False)
            os.replace(tmp, self.folder / name)
            self.pending = []
        self.last = time.monotonic()


class Progress:
    def __init__(self, total, done):
        self.total, self.done, self.start, self.first = total, done, time.monotonic(), done
        self.shown = 0.0

    def tick(self, count=1):
        self.done += count
        now = time.monotonic()
        if now - self.shown < 0.1 and self.done < self.total:
            return  # at most ten lines a second: thousands of runs a second would flood the terminal
        self.shown = now
        elapsed = now - self.start
        rate = (self.done - self.first) / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else math.inf
        width = 30
        filled = int(width * self.done / max(self.total, 1))
        sys.stderr.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} runs, "
                         f"{rate:.2f} runs/s, ETA {eta:.0f} s ")
        sys.stderr.flush()

    def close(self):
        sys.stderr.write("\n")


def make_row(run, metrics, seconds, worker):
    row = {"run_id": st.run_id(run)}
    row.update({f"param:{k}": v for k, v in sorted(run.items())})
    row.update(metrics)
    row.update(wall_time=seconds, worker=worker)
    return row


def run_and_time(spec, run, fmus, master="fmpy"):
    """One run: the row with the run's wall time and worker."""
    return run_batch(spec, [run], fmus, master)[0]


def run_batch(spec, runs, fmus, master="fmpy"):
    """What a worker executes: a batch of runs, their rows (each with its wall time and the
    worker). The compiled master runs the batch in one call."""
    try:
        faulthandler.enable()  # an FMU that crashes the process names itself in the worker's log
    except (AttributeError, OSError, ValueError):
        pass  # a standard error without a file descriptor (captured): nowhere to write it
    worker = st.worker_name()
    if master == "compiled":
        return [make_row(run, row, seconds, worker) for run, (row, seconds) in zip(runs, st.execute_many(spec, runs, fmus))]
    rows = []
    for run in runs:
        start = time.perf_counter()
        metrics = st.execute(spec, run, fmus)
        rows.append(make_row(run, metrics, time.perf_counter() - start, worker))
    return rows


# The compiled master's runs go to the workers in batches of about this many communication
# steps in all: at 2-10 us a step a batch takes a fraction of a second, long enough that
# Dask's own cost per task (about 10 ms) is small, short enough that the progress line moves
# and a worker that dies loses little. The FMPy master's runs (about 50 us a step) go one by one.
BATCH_STEPS = 100_000


def run_steps(spec, run):
    study = spec["study"]
    return max(1, int(round(float(run.get("stop_time", study["stop_time"])) / float(run.get("step", study["step"])))))


def batches(spec, runs, master, workers):
    """The runs in batches for `master`: one run each for the FMPy master; for the compiled
    one, up to BATCH_STEPS steps each and at least four batches per worker while there are
    runs enough, so that every worker stays busy to the end."""
    if master != "compiled":
        return [[run] for run in runs]
    cap = max(1, math.ceil(len(runs) / (4 * max(workers, 1))))
    out, current, steps = [], [], 0
    for run in runs:
        current.append(run)
        steps += run_steps(spec, run)
        if steps >= BATCH_STEPS or len(current) >= cap:
            out.append(current)
            current, steps = [], 0
    if current:
        out.append(current)
    return out


def choose_master(requested, spec, fmus):
    """(master, note): the compiled master unless `requested` is "fmpy" or it cannot run here
    (then the FMPy master, and the note says why). SweepError if "compiled" was asked for and
    cannot run."""
    if requested == "fmpy":
        return "fmpy", None
    from . import master
    ok, reason = master.available()
    if ok and spec["study"]["system"] == "closed-loop" and "couplings" not in fmus:
        ok, reason = False, "the closed loop's StewartSystem.ssp is not beside the package's FMUs"
    if ok:
        return "compiled", None
    if requested == "compiled":
        raise SweepError(f"--master compiled: {reason}")
    return "fmpy", f"{reason}: running with the FMPy master (--master fmpy; slower, the same rows)"


class SweepError(Exception):
    """A study that cannot start (its --out, its lock, its scheduler), with what to change."""


LOCK_NAME = ".stewart-sweep.lock"


def _process_alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


class StudyLock:
    """One stewart-sweep per --out at a time. An exclusive `flock` on OUT/.stewart-sweep.lock,
    which the kernel releases when the holder ends however it ends, so a lock left by a killed
    sweep never blocks the next one; the file records the holder (pid, host, start, study) for
    the message, and on file systems without `flock` the recorded pid decides whether the
    holder still runs."""

    def __init__(self, out, study_name):
        self.path, self.study, self.fd = Path(out) / LOCK_NAME, study_name, None
        self.taken_over = None  # the record of a dead holder whose lock file was left behind

    def _open(self):
        try:
            return os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as e:
            raise SweepError(f"cannot write in --out {self.path.parent} ({e.strerror}): give a folder you can "
                             f"write to") from None

    def _record(self, fd):
        try:
            return json.loads(os.pread(fd, 4096, 0).decode() or "null")
        except (OSError, ValueError):
            return None

    def _busy(self, record):
        who = (f"pid {record.get('pid')} on {record.get('host')}, started {record.get('started')}, study "
               f"{record.get('study')!r}") if isinstance(record, dict) else "a process that has not written its name yet"
        return SweepError(f"--out {self.path.parent} is in use by another stewart-sweep ({who}): wait for it to "
                          f"finish or give another --out (the lock {self.path} is released when that process ends)")

    def __enter__(self):
        while True:
            fd = self._open()
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                record = self._record(fd)
                os.close(fd)
                raise self._busy(record) from None
            except OSError:  # no flock here (some network file systems): the recorded pid decides
                record = self._record(fd)
                if (isinstance(record, dict) and record.get("host") == socket.gethostname()
                        and isinstance(record.get("pid"), int) and record["pid"] != os.getpid()
                        and _process_alive(record["pid"])):
                    os.close(fd)
                    raise self._busy(record) from None
            # The holder may have removed the file between our open and our flock: hold the file
            # that is there now, or try again.
            try:
                same = os.fstat(fd).st_ino == os.stat(self.path).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        record = self._record(fd)
        if isinstance(record, dict):
            self.taken_over = record
        self.fd = fd
        text = json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "study": self.study,
                           "started": time.strftime("%Y-%m-%d %H:%M:%S")})
        os.ftruncate(fd, 0)
        os.pwrite(fd, text.encode(), 0)
        return self

    def __exit__(self, *exc):
        # Unlink before unlocking: a sweep that opened the old file sees it is gone and retries.
        try:
            os.unlink(self.path)
        except OSError:
            pass
        os.close(self.fd)
        self.fd = None


def prepare_out(out):
    """The --out folder, created if missing; a clear SweepError if it cannot be."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise SweepError(f"--out {out} is a file, not a folder: give a folder (it is created if missing)")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise SweepError(f"cannot create --out {out} ({e.strerror}): give a folder you can write to") from None
    return out


def _positive_int(text):
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text}: at least 1")
    return value


def _positive_float(text):
    value = float(text)
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text}: a positive number of seconds")
    return value


def parser():
    p = argparse.ArgumentParser(prog="stewart-sweep", description=__doc__.split("\n\n")[0],
                                epilog="docs/studies.md describes the study file and these options.")
    p.add_argument("study", help="the study file (TOML)")
    p.add_argument("--out", help="output folder (results.parquet/, summary, plots); required unless --check")
    p.add_argument("--check", action="store_true",
                   help="check the study file, print its plan (parameters, run count, plots) and exit without "
                        "running anything")
    p.add_argument("--max-runs", type=_positive_int, default=st.DEFAULT_MAX_RUNS,
                   help=f"refuse a study of more runs (default {st.DEFAULT_MAX_RUNS}: on a 2-core, 24 GiB machine the "
                        "shipped studies run at about 60 runs/s with the compiled master (5-40 with the FMPy master), so "
                        "that is about half an hour, and the run list (about 0.4 kB a run) and the rows stay far below "
                        "the memory; raise it for a bigger cluster)")
    p.add_argument("--fmu", metavar="PATH",
                   help="the StewartPlatform.fmu to run (default: the package's: the repository's target/fmu/ or "
                        "the copy an installed wheel carries; or the environment variable STEWART_PLATFORM_FMU)")
    p.add_argument("--controller-fmu", metavar="PATH",
                   help="the StewartController.fmu (default: the one beside --fmu, or the package's; or "
                        "STEWART_CONTROLLER_FMU)")
    p.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:port)")
    p.add_argument("--connect-timeout", type=_positive_float, default=CONNECT_TIMEOUT,
                   help=f"seconds to wait for --scheduler to answer (default {CONNECT_TIMEOUT:g})")
    p.add_argument("--workers", type=_positive_int, default=os.cpu_count(),
                   help="local worker processes (default: cores)")
    p.add_argument("--limit", type=int, help="run at most this many of the missing runs")
    p.add_argument("--serial", action="store_true", help="run in this process, without Dask")
    p.add_argument("--master", choices=st.MASTERS,
                   help="the co-simulation master: 'compiled' (the default: stewart_fmu.master, Rust, at the FMUs' "
                        "own speed) or 'fmpy' (the Python reference over FMPy; the same rows to the bit)")
    return p


CONNECT_TIMEOUT = 5.0


def main(argv=None):
    """The command; returns its exit status: 0 done, 1 every run failed (or a plot could not be
    written), 2 the study could not start (a message says why)."""
    args = parser().parse_args(argv)
    if args.out is None and not args.check:
        parser().error("--out is required (except with --check)")
    try:
        return sweep(args)
    except (st.StudyError, SweepError, FileNotFoundError) as e:
        print(f"stewart-sweep: {e}", file=sys.stderr, flush=True)
        return 2
    except KeyboardInterrupt:
        print("\nstewart-sweep: interrupted; the rows written are kept: the same command resumes", file=sys.stderr)
        return 130


def sweep(args):
    paths = study_schema.fmu_paths(args.fmu, args.controller_fmu)
    plan = st.plan(args.study, args.max_runs, fmus=paths)
    spec = plan.spec
    if args.check:
        print(plan.text())
        if args.out and results_dir(args.out).is_dir():
            ids = {st.run_id(r) for r in st.runs(spec)}
            done = len(ids & set(load_results(args.out).get("run_id", pd.Series(dtype=str))))
            print(f"  --out {args.out}: {done} of {plan.runs} runs done already")
        print("stewart-sweep: --check: the study is valid; nothing was run")
        return 0
    out = prepare_out(args.out)
    with StudyLock(out, spec["study"]["name"]) as lock:
        if lock.taken_over:
            print(f"stewart-sweep: the lock of a sweep that ended without releasing it (pid "
                  f"{lock.taken_over.get('pid')}, started {lock.taken_over.get('started')}) was taken over",
                  file=sys.stderr)
        return _sweep_locked(spec, plan, args, out, paths)


def _sweep_locked(spec, plan, args, out, paths):
    try:
        if not (out / "study.toml").exists() or not os.path.samefile(args.study, out / "study.toml"):
            shutil.copyfile(args.study, out / "study.toml")
    except OSError as e:
        raise SweepError(f"cannot write in --out {out} ({e.strerror}): give a folder you can write to") from None
    all_runs = st.runs(spec)
    order = {st.run_id(r): i for i, r in enumerate(all_runs)}
    done = set(load_results(out).get("run_id", pd.Series(dtype=str))) & set(order)
    todo = [r for r in all_runs if st.run_id(r) not in done]
    if args.limit is not None:
        todo = todo[: max(args.limit, 0)]
    fmus = st.fmus_for(spec, paths) if todo else {}
    master, note = choose_master(args.master, spec, fmus) if todo else (args.master or "compiled", None)
    if note:
        print(f"stewart-sweep: {note}", file=sys.stderr, flush=True)
    print(f"stewart-sweep: study {spec['study']['name']}: {len(all_runs)} runs, {len(done)} done already, "
          f"running {len(todo)} with the {master} master", flush=True)
    writer = Writer(out)
    progress = Progress(len(all_runs), len(done))
    started = time.monotonic()
    try:
        if todo:
            if args.serial:
                for batch in batches(spec, todo, master, 1):
                    for row in run_batch(spec, batch, fmus, master):
                        writer.add(row)
                    progress.tick(len(batch))
            else:
                run_on_dask(spec, todo, fmus, args, writer, progress, master)
    finally:
        writer.flush()  # what finished is kept, whatever stopped the study
        progress.close()
    elapsed = time.monotonic() - started
    results = load_results(out)
    if len(results):
        results = results[results["run_id"].isin(order)].reset_index(drop=True)
    summary = summarise(spec, results, len(todo), elapsed, order, master)
    (out / "summary.txt").write_text(summary + "\n")
    print(summary)
    status = 0
    for path, problem in plot(spec, results, out, study_schema.fmu_variables(paths)):
        if problem:
            print(f"stewart-sweep: {path.name} not written: {problem}", file=sys.stderr)
            status = 1
        else:
            print(f"wrote {path}")
    failed = results[results["status"] == "error"] if len(results) else results
    if len(results) and len(failed) == len(results):
        print(f"stewart-sweep: every run failed ({len(failed)} of {len(results)}); the first error: "
              f"{first_error(failed, order)}", file=sys.stderr)
        status = 1
    return status


def first_error(failed, order):
    """The message of the first failed run in the study's order, with its parameters."""
    row = failed.assign(_order=failed["run_id"].map(order)).sort_values("_order").iloc[0]
    params = ", ".join(f"{k[6:]} = {row[k]}" for k in row.index if k.startswith("param:") and not pd.isna(row[k]))
    return f"{row['message']} (run {row['run_id']}{': ' + params if params else ''})"


# At most this many batches (single runs with the FMPy master) wait at the scheduler at a time:
# enough to keep a large cluster busy, and the client's and scheduler's memory stay bounded
# whatever the number of runs.
WINDOW = 1000
# A task cancelled because its inputs were lost with workers that died is submitted again up
# to this many times before its runs become error rows.
LOST_INPUT_RETRIES = 3
# How long a study waits for a worker to take the FMUs (after every worker died, for one to
# come back), s.
WORKER_WAIT = 300


def run_on_dask(spec, todo, fmus, args, writer, progress, master="fmpy"):
    from distributed import Client, LocalCluster, as_completed
    if args.scheduler:
        try:
            client, cluster = Client(args.scheduler, timeout=args.connect_timeout), None
        except ValueError as e:
            raise SweepError(f"--scheduler {args.scheduler} is not a scheduler address ({e}): write tcp://host:port")
        except (OSError, TimeoutError) as e:
            raise SweepError(f"no Dask scheduler answered at {args.scheduler} within {args.connect_timeout:g} s "
                             f"(the connection timeout, --connect-timeout): check the address and that `dask "
                             f"scheduler` runs there, or leave out --scheduler to run on this machine ({e})") from None
        if not client.scheduler_info().get("workers"):
            print(f"stewart-sweep: the scheduler at {args.scheduler} has no workers yet; waiting for them (start "
                  f"`dask worker {args.scheduler}`)", file=sys.stderr, flush=True)
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        # The FMUs on every worker, once, under keys made from their contents (another study on
        # the same scheduler shares them only if they are the same files). Scattered data lives
        # only on the workers: after a worker died (a run that crashes each worker it reaches
        # may take them all) they are scattered again before anything more is submitted (the
        # client may not have heard yet that they are lost).
        shared, stale = {}, [True]

        def scattered():
            # (The old futures are let go only once the new ones hold the keys: a key whose
            # count of futures reaches 0 is released, which could overtake the new scatter.)
            if stale[0] or any(f.status != "finished" for f in shared.values()):
                try:
                    futures = client.scatter(list(fmus.values()), broadcast=True, timeout=WORKER_WAIT)
                except TimeoutError:
                    raise SweepError(f"no Dask worker came for {WORKER_WAIT:g} s to take the FMUs (the workers died and "
                                     "none came back: their logs say why); the rows written so far are kept, run "
                                     "the study again to go on") from None
                shared.update(zip(fmus, futures))
                stale[0] = False
            return shared

        scattered()
        workers = len(client.scheduler_info().get("workers", {})) or args.workers
        pending = iter(batches(spec, todo, master, workers))
        submitted = {}
        # Runs whose worker died under them. Dask blames every task a dying worker held, so the
        # run that crashed it and its neighbours look alike: each runs again at the end, alone on
        # the cluster, where a run that still kills its worker is the one.
        suspects = []

        def submit(batch, attempt=0):
            key = f"runs-{st.run_id(batch[0])}-{len(batch)}-{uuid.uuid4().hex[:6]}"
            future = client.submit(run_batch, spec, batch, scattered(), master, key=key, pure=False)
            submitted[future] = (batch, attempt)
            return future

        def record(rows):
            for row in rows:
                writer.add(row)
            progress.tick(len(rows))

        window = max(WINDOW, 4 * workers)
        futures = as_completed([submit(batch) for batch in itertools.islice(pending, window)])
        for future in futures:
            batch, attempt = submitted.pop(future)
            try:
                rows = future.result()
            except Exception as e:  # noqa: BLE001 - e.g. KilledWorker: the runs are rows, not the study's crash
                future.release()
                if killed(e) or cancelled(e):
                    stale[0] = True
                if cancelled(e) and attempt < LOST_INPUT_RETRIES:
                    # Its inputs were lost with workers that died: not the task's doing.
                    futures.add(submit(batch, attempt + 1))
                    continue
                if killed(e):
                    suspects.extend(batch)
                else:
                    record([make_row(run, st.failed_metrics(failure_message(e)), math.nan, "none") for run in batch])
            else:
                record(rows)
                future.release()
            following = next(pending, None)
            if following is not None:
                futures.add(submit(following))
        for run in suspects:
            attempt = 0
            while True:
                future = submit([run], attempt)
                submitted.pop(future)
                try:
                    rows = future.result()
                except Exception as e:  # noqa: BLE001 - the run's error row
                    future.release()
                    if killed(e) or cancelled(e):
                        # Alone on the cluster, so the run took its workers down: Dask says so
                        # (KilledWorker) or, when the FMUs went down with the last worker that
                        # held them first, cancels the run. Once more, in case something else
                        # killed them.
                        stale[0] = True
                        if attempt < 1:
                            attempt += 1
                            continue
                    rows = [make_row(run, st.failed_metrics(failure_message(e, alone=True)), math.nan, "none")]
                else:
                    future.release()
                record(rows)
                break
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def killed(error):
    """Dask's KilledWorker: the task was running when workers died, as often as allowed."""
    return type(error).__name__ == "KilledWorker"


def cancelled(error):
    """A task Dask cancelled, such as one whose inputs were lost with the workers that held them."""
    return "Cancelled" in type(error).__name__


def failure_message(error, alone=False):
    """A run's error row for a task that failed on the cluster (`alone`: the only one on it):
    what happened, in words, with Dask's own message."""
    text = f"{type(error).__name__}: {error}"
    if alone and (killed(error) or cancelled(error)):
        # The worker process ended while running the run alone: a crash inside an FMU (the
        # FMUs' own code catches its panics, so a foreign binary or the machine), or out of
        # memory.
        return ("the worker process died while running this run alone on the cluster, every time it was tried (a "
                "crash inside an FMU, or the machine out of memory; the worker's log has Python's fault report): "
                + text)
    return text


def summarise(spec, results, executed, elapsed, order=None, master=None):
    lines = [f"study {spec['study']['name']}: {len(results)} rows in results.parquet; this call ran {executed} in "
             f"{elapsed:.1f} s ({executed / elapsed if elapsed > 0 else 0:.2f} runs/s)"
             + (f" with the {master} master" if master and executed else "")]
    if len(results):
        counts = results["status"].value_counts().to_dict()
        lines.append("status: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
        lines.append(f"stable: {int(results['stable'].sum())} of {len(results)}")
        for metric in ("max_leg_error", "max_pose_error", "max_stop_force", "peak_deceleration", "energy_residual"):
            column = results[metric].dropna()
            if len(column):
                lines.append(f"{metric}: min {column.min():.3g}, median {column.median():.3g}, max {column.max():.3g}")
        failed = results[results["status"] == "error"]
        if len(failed):
            lines.append(f"first error: {first_error(failed, order or {})}")
    return "\n".join(lines)


def plot(spec, results, out, variables=None):
    """The study's `[[plot]]` figures: `map` (a metric over two parameters, one panel per value
    of a third), `histogram` of a metric, `scatter` of a metric against a parameter. Axes are
    labelled with each quantity's name and unit (`stewart_fmu.labels`; `variables`: the FMUs'
    variable tables). Yields (path, None) for each figure written, (path, reason) for one that
    could not be: rows are never lost to a plot."""
    if not len(results) or not spec.get("plot"):
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    for i, p in enumerate(spec["plot"]):
        path = out / p.get("file", f"plot{i + 1}.png")
        # The schema refuses names that leave --out; a symbolic link inside it could still.
        if out.resolve() not in path.resolve().parents:
            yield path, f"{path} is outside --out {out}"
            continue
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            fig = _figure(plt, spec, results, p, variables)
            fig.savefig(path, dpi=110)
            plt.close(fig)
        except Exception as e:  # noqa: BLE001 - a figure that fails is reported; the rows are kept
            plt.close("all")
            yield path, f"{type(e).__name__}: {e}"
            continue
        yield path, None


def colour_limits(values):
    """Colour-scale limits that show the bulk of the values: the data's range, cut at 3
    interquartile ranges beyond the quartiles, so that one outlier (a run at rest, 1e-15 m)
    does not take the whole scale. Returns (lo, hi)."""
    import numpy as np
    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    if not len(finite):
        return 0.0, 1.0
    q1, q3 = np.percentile(finite, [25, 75])
    spread = q3 - q1
    lo = max(finite.min(), q1 - 3 * spread) if spread > 0 else finite.min()
    hi = min(finite.max(), q3 + 3 * spread) if spread > 0 else finite.max()
    return (lo, hi) if hi > lo else (lo - 0.5, hi + 0.5)


def _figure(plt, spec, results, p, variables=None):
    import textwrap

    import numpy as np

    from . import labels
    kind = p.get("kind", "histogram")
    nondimensional = spec["study"].get("units") == "nondimensional"

    def column(name):
        return results[f"param:{name}"] if f"param:{name}" in results else results[name]

    def label(name, width=48):
        return textwrap.fill(labels.label(name, variables, nondimensional), width)

    value = p.get("value", "max_leg_error")
    title = p.get("title", f"{spec['study']['name']}: {labels.label(value, variables, nondimensional)}")
    if kind == "map":
        facets = sorted(column(p["facet"]).unique()) if p.get("facet") else [None]
        fig, axes = plt.subplots(1, len(facets), figsize=(max(7.5, 4.2 * len(facets) + 1.5), 5.0), squeeze=False,
                                 sharey=True, layout="constrained")
        grids = []
        for facet in facets:
            part = results if facet is None else results[column(p["facet"]) == facet]
            xs, ys = sorted(column(p["x"])[part.index].unique()), sorted(column(p["y"])[part.index].unique())
            grid = np.full((len(ys), len(xs)), np.nan)
            for _, r in part.iterrows():
                x, y = r.get(f"param:{p['x']}", r.get(p["x"])), r.get(f"param:{p['y']}", r.get(p["y"]))
                v = r[value] if r["stable"] or not p.get("unstable_blank", True) else np.nan
                grid[ys.index(y), xs.index(x)] = v
            with np.errstate(divide="ignore", invalid="ignore"):
                shown = np.log10(grid) if p.get("log") else grid
            grids.append((xs, ys, grid, shown))
        # One colour scale for all panels, robust to outliers; cells beyond it are marked.
        every = np.concatenate([g[3].ravel() for g in grids])
        lo, hi = colour_limits(every)
        below, above = bool(np.any(every < lo)), bool(np.any(every > hi))
        for ax, facet, (xs, ys, grid, shown) in zip(axes[0], facets, grids):
            im = ax.imshow(shown, origin="lower", aspect="auto", cmap="viridis", vmin=lo, vmax=hi)
            ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs], rotation=45)
            ax.set_yticks(range(len(ys)), [f"{y:g}" for y in ys])
            if facet is not None:
                ax.set_title(labels.facet_title(p["facet"], facet, variables, nondimensional))
            for (yi, xi), v in np.ndenumerate(shown):
                if np.isnan(grid[yi, xi]):
                    ax.text(xi, yi, "x", ha="center", va="center", color="red")
                elif v < lo or v > hi:
                    ax.text(xi, yi, "<" if v < lo else ">", ha="center", va="center", color="white",
                            fontweight="bold")
        extend = {(True, True): "both", (True, False): "min", (False, True): "max"}.get((below, above), "neither")
        fig.supxlabel(label(p["x"], 90), fontsize=9)
        axes[0][0].set_ylabel(label(p["y"], 40), fontsize=9)
        fig.colorbar(im, ax=list(axes[0]), extend=extend,
                     label=textwrap.fill(("log10 of " if p.get("log") else "") + labels.label(value, variables,
                                                                                             nondimensional), 40))
        note = "x: unstable or failed" + ("; < >: beyond the colour scale" if below or above else "")
        fig.suptitle(textwrap.fill(f"{title} ({note})", int(10 * fig.get_figwidth())), fontsize=10)
        return fig
    if kind == "scatter":
        fig, ax = plt.subplots(figsize=(6.5, 4.2))
        ax.scatter(column(p["x"]), results[value], s=12)
        ax.set_xlabel(label(p["x"]))
        ax.set_ylabel(label(value))
        ax.set_title(textwrap.fill(title, 64), fontsize=10)
        ax.grid(True, alpha=0.3)
    else:
        fig, ax = plt.subplots(figsize=(6.5, 4.2))
        ax.hist(results[value].dropna(), bins=p.get("bins", 30))
        ax.set_xlabel(label(value))
        ax.set_ylabel("runs")
        ax.set_title(textwrap.fill(title, 64), fontsize=10)
    fig.tight_layout()
    return fig


if __name__ == "__main__":
    sys.exit(main())
