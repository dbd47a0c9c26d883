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

The command line and its course; the parts live beside it: `sweep_results` (the --out folder:
the lock, the rows, the summary), `sweep_dask` (batches, workers, Dask) and `sweep_plots`.
"""

import argparse
import math
import os
import shutil
import sys
import time

import pandas as pd

from . import study as st
from . import study_params
# The parts' names the users of `stewart_fmu.sweep` know (tests, examples, docs).
from .sweep_dask import Progress, batches, run_and_time, run_batch, run_on_dask  # noqa: F401
from .sweep_plots import _figure, colour_limits, plot  # noqa: F401
from .sweep_results import (StudyLock, SweepError, Writer, first_error, load_results, prepare_out,  # noqa: F401
                            results_dir, summarise)


def choose_master(requested, spec, fmus):
    """(master, note): the compiled master unless `requested` is "fmpy" or it cannot run here
    (then the FMPy master, and the note says why). SweepError if "compiled" was asked for and
    cannot run."""
    if requested == "fmpy":
        return "fmpy", None
    if spec["study"]["system"] == "cueing":
        if requested == "compiled":
            raise SweepError("--master compiled: a system = 'cueing' study runs with the FMPy master")
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
    p.add_argument("--cueing-fmu", metavar="PATH",
                   help="the StewartCueing.fmu of a system = 'cueing' study (default: the one beside --fmu, or the "
                        "package's; or STEWART_CUEING_FMU)")
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
    paths = study_params.fmu_paths(args.fmu, args.controller_fmu, args.cueing_fmu)
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
    for path, problem in plot(spec, results, out, study_params.fmu_variables(paths)):
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


if __name__ == "__main__":
    sys.exit(main())
