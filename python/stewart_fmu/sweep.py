"""`stewart-sweep STUDY.toml --out DIR [--scheduler ADDRESS] [--workers N] [--limit N] [--serial]`:
runs a design study (see `stewart_fmu.study`) on Dask.

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
"""

import argparse
import math
import os
import shutil
import sys
import time
import uuid
from pathlib import Path

import pandas as pd

from . import study as st


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

    def tick(self):
        self.done += 1
        elapsed = time.monotonic() - self.start
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


def run_and_time(spec, run, fmus):
    """What a worker executes for one run: the row with the run's wall time and worker."""
    start = time.perf_counter()
    metrics = st.execute(spec, run, fmus)
    return make_row(run, metrics, time.perf_counter() - start, st.worker_name())


def main(argv=None):
    parser = argparse.ArgumentParser(prog="stewart-sweep", description=__doc__.split("\n\n")[0])
    parser.add_argument("study", help="the study file (TOML)")
    parser.add_argument("--out", required=True, help="output folder (results.parquet/, summary, plots)")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:port)")
    parser.add_argument("--workers", type=int, default=os.cpu_count(), help="local worker processes (default: cores)")
    parser.add_argument("--limit", type=int, help="run at most this many of the missing runs")
    parser.add_argument("--serial", action="store_true", help="run in this process, without Dask")
    args = parser.parse_args(argv)
    try:
        spec = st.load(args.study)
    except st.StudyError as e:
        sys.exit(f"stewart-sweep: {e}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(args.study, out / "study.toml")
    all_runs = st.runs(spec)
    done = set(load_results(out).get("run_id", pd.Series(dtype=str)))
    todo = [r for r in all_runs if st.run_id(r) not in done]
    if args.limit is not None:
        todo = todo[: args.limit]
    print(f"stewart-sweep: study {spec['study']['name']}: {len(all_runs)} runs, {len(done)} done already, "
          f"running {len(todo)}", flush=True)
    writer = Writer(out)
    progress = Progress(len(all_runs), len(done))
    started = time.monotonic()
    if todo:
        fmus = st.fmus_for(spec)
        if args.serial:
            for run in todo:
                writer.add(run_and_time(spec, run, fmus))
                progress.tick()
        else:
            run_on_dask(spec, todo, fmus, args, writer, progress)
    writer.flush()
    progress.close()
    elapsed = time.monotonic() - started
    results = load_results(out)
    summary = summarise(spec, results, len(todo), elapsed)
    (out / "summary.txt").write_text(summary + "\n")
    print(summary)
    for path in plot(spec, results, out):
        print(f"wrote {path}")


def run_on_dask(spec, todo, fmus, args, writer, progress):
    from distributed import Client, LocalCluster, as_completed
    if args.scheduler:
        client, cluster = Client(args.scheduler), None
    else:
        cluster = LocalCluster(n_workers=max(args.workers, 1), threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        shared = client.scatter(fmus, broadcast=True)
        futures = [client.submit(run_and_time, spec, run, shared, key=f"run-{st.run_id(run)}-{uuid.uuid4().hex[:6]}",
                                 pure=False) for run in todo]
        for future in as_completed(futures):
            writer.add(future.result())
            progress.tick()
            future.release()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def summarise(spec, results, executed, elapsed):
    lines = [f"study {spec['study']['name']}: {len(results)} rows in results.parquet; this call ran {executed} in "
             f"{elapsed:.1f} s ({executed / elapsed if elapsed > 0 else 0:.2f} runs/s)"]
    if len(results):
        counts = results["status"].value_counts().to_dict()
        lines.append("status: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
        lines.append(f"stable: {int(results['stable'].sum())} of {len(results)}")
        for metric in ("max_leg_error", "max_pose_error", "max_stop_force", "peak_deceleration", "energy_residual"):
            column = results[metric].dropna()
            if len(column):
                lines.append(f"{metric}: min {column.min():.3g}, median {column.median():.3g}, max {column.max():.3g}")
    return "\n".join(lines)


def plot(spec, results, out):
    """The study's `[[plot]]` figures: `map` (a metric over two parameters, one panel per value
    of a third), `histogram` of a metric, `scatter` of a metric against a parameter."""
    if not len(results) or not spec.get("plot"):
        return []
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    paths = []
    for i, p in enumerate(spec["plot"]):
        kind = p.get("kind", "histogram")
        column = lambda name: results[f"param:{name}"] if f"param:{name}" in results else results[name]  # noqa: E731
        value = p.get("value", "max_leg_error")
        title = p.get("title", f"{spec['study']['name']}: {value}")
        if kind == "map":
            facets = sorted(column(p["facet"]).unique()) if p.get("facet") else [None]
            fig, axes = plt.subplots(1, len(facets), figsize=(max(6.5, 4.2 * len(facets)), 4.2), squeeze=False)
            for ax, facet in zip(axes[0], facets):
                part = results if facet is None else results[column(p["facet"]) == facet]
                xs, ys = sorted(column(p["x"])[part.index].unique()), sorted(column(p["y"])[part.index].unique())
                grid = np.full((len(ys), len(xs)), np.nan)
                for _, r in part.iterrows():
                    x, y = r.get(f"param:{p['x']}", r.get(p["x"])), r.get(f"param:{p['y']}", r.get(p["y"]))
                    v = r[value] if r["stable"] or not p.get("unstable_blank", True) else np.nan
                    grid[ys.index(y), xs.index(x)] = v
                shown = np.log10(grid) if p.get("log") else grid
                im = ax.imshow(shown, origin="lower", aspect="auto", cmap="viridis")
                ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs], rotation=45)
                ax.set_yticks(range(len(ys)), [f"{y:g}" for y in ys])
                ax.set_xlabel(p["x"])
                ax.set_ylabel(p["y"])
                if facet is not None:
                    ax.set_title(f"{p['facet']} = {facet:g}")
                for (yi, xi), v in np.ndenumerate(grid):
                    if np.isnan(v):
                        ax.text(xi, yi, "x", ha="center", va="center", color="red")
                fig.colorbar(im, ax=ax, label=("log10 " if p.get("log") else "") + value)
            fig.suptitle(title + " (x: unstable or failed)")
        elif kind == "scatter":
            fig, ax = plt.subplots(figsize=(6, 4))
            ax.scatter(column(p["x"]), results[value], s=12)
            ax.set_xlabel(p["x"])
            ax.set_ylabel(value)
            ax.set_title(title)
            ax.grid(True, alpha=0.3)
        else:
            fig, ax = plt.subplots(figsize=(6, 4))
            ax.hist(results[value].dropna(), bins=p.get("bins", 30))
            ax.set_xlabel(value)
            ax.set_ylabel("runs")
            ax.set_title(title)
        fig.tight_layout()
        path = out / p.get("file", f"plot{i + 1}.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


if __name__ == "__main__":
    main()
