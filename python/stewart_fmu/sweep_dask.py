"""Running a study's runs: in batches (`batches`, `run_batch`: what a worker executes), and on a
Dask cluster (`run_on_dask`), where a worker that dies has its runs re-executed and a run that
kills every worker it reaches becomes an error row (docs/studies.md)."""

import faulthandler
import itertools
import math
import sys
import time
import uuid

from . import study as st
from .sweep_results import SweepError, make_row


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


def connect(args):
    """(client, cluster): a client of the scheduler at --scheduler, or of a LocalCluster of
    --workers processes (then `cluster` is it, else None)."""
    from distributed import Client, LocalCluster
    if not args.scheduler:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        return Client(cluster), cluster
    try:
        client = Client(args.scheduler, timeout=args.connect_timeout)
    except ValueError as e:
        raise SweepError(f"--scheduler {args.scheduler} is not a scheduler address ({e}): write tcp://host:port")
    except (OSError, TimeoutError) as e:
        raise SweepError(f"no Dask scheduler answered at {args.scheduler} within {args.connect_timeout:g} s "
                         f"(the connection timeout, --connect-timeout): check the address and that `dask "
                         f"scheduler` runs there, or leave out --scheduler to run on this machine ({e})") from None
    if not client.scheduler_info().get("workers"):
        print(f"stewart-sweep: the scheduler at {args.scheduler} has no workers yet; waiting for them (start "
              f"`dask worker {args.scheduler}`)", file=sys.stderr, flush=True)
    return client, None


class SharedFmus:
    """The FMUs on every worker, once, under keys made from their contents (another study on
    the same scheduler shares them only if they are the same files). Scattered data lives only
    on the workers: after a worker died (a run that crashes each worker it reaches may take
    them all) they are scattered again before anything more is submitted (the client may not
    have heard yet that they are lost): `stale()` says so."""

    def __init__(self, client, fmus):
        self.client, self.fmus, self.shared, self.is_stale = client, fmus, {}, True

    def stale(self):
        self.is_stale = True

    def futures(self):
        # (The old futures are let go only once the new ones hold the keys: a key whose count
        # of futures reaches 0 is released, which could overtake the new scatter.)
        if self.is_stale or any(f.status != "finished" for f in self.shared.values()):
            try:
                futures = self.client.scatter(list(self.fmus.values()), broadcast=True, timeout=WORKER_WAIT)
            except TimeoutError:
                raise SweepError(f"no Dask worker came for {WORKER_WAIT:g} s to take the FMUs (the workers died and "
                                 "none came back: their logs say why); the rows written so far are kept, run the "
                                 "study again to go on") from None
            self.shared.update(zip(self.fmus, futures))
            self.is_stale = False
        return self.shared


class Submitter:
    """Submits batches of runs to the cluster and turns their results into rows."""

    def __init__(self, client, spec, fmus, master, writer, progress):
        self.client, self.spec, self.master = client, spec, master
        self.fmus, self.writer, self.progress = SharedFmus(client, fmus), writer, progress
        self.submitted = {}

    def submit(self, batch, attempt=0):
        key = f"runs-{st.run_id(batch[0])}-{len(batch)}-{uuid.uuid4().hex[:6]}"
        future = self.client.submit(run_batch, self.spec, batch, self.fmus.futures(), self.master, key=key,
                                    pure=False)
        self.submitted[future] = (batch, attempt)
        return future

    def record(self, rows):
        for row in rows:
            self.writer.add(row)
        self.progress.tick(len(rows))

    def error_rows(self, batch, error, alone=False):
        return [make_row(run, st.failed_metrics(failure_message(error, alone)), math.nan, "none") for run in batch]


def run_on_dask(spec, todo, fmus, args, writer, progress, master="fmpy"):
    client, cluster = connect(args)
    try:
        runner = Submitter(client, spec, fmus, master, writer, progress)
        runner.fmus.futures()
        workers = len(client.scheduler_info().get("workers", {})) or args.workers
        suspects = _run_all(runner, iter(batches(spec, todo, master, workers)), max(WINDOW, 4 * workers))
        for run in suspects:
            _run_alone(runner, run)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _run_all(runner, pending, window):
    """Every batch, at most `window` waiting at the scheduler at a time; returns the runs whose
    worker died under them. Dask blames every task a dying worker held, so the run that crashed
    it and its neighbours look alike: each runs again at the end, alone on the cluster
    (`_run_alone`), where a run that still kills its worker is the one."""
    from distributed import as_completed
    suspects = []
    futures = as_completed([runner.submit(batch) for batch in itertools.islice(pending, window)])
    for future in futures:
        batch, attempt = runner.submitted.pop(future)
        try:
            rows = future.result()
        except Exception as e:  # noqa: BLE001 - e.g. KilledWorker: the runs are rows, not the study's crash
            future.release()
            if killed(e) or cancelled(e):
                runner.fmus.stale()
            if cancelled(e) and attempt < LOST_INPUT_RETRIES:
                # Its inputs were lost with workers that died: not the task's doing.
                futures.add(runner.submit(batch, attempt + 1))
                continue
            if killed(e) or cancelled(e):
                # Still cancelled after the retries: workers kept dying under it, as under a
                # KilledWorker; alone on the cluster it shows whether one of its runs is why.
                suspects.extend(batch)
            else:
                runner.record(runner.error_rows(batch, e))
        else:
            runner.record(rows)
            future.release()
        following = next(pending, None)
        if following is not None:
            futures.add(runner.submit(following))
    return suspects


def _run_alone(runner, run):
    """One suspect run alone on the cluster: its row, or its error row if it takes its workers
    down again."""
    attempt = 0
    while True:
        future = runner.submit([run], attempt)
        runner.submitted.pop(future)
        try:
            rows = future.result()
        except Exception as e:  # noqa: BLE001 - the run's error row
            future.release()
            if killed(e) or cancelled(e):
                # Alone on the cluster, so the run took its workers down: Dask says so
                # (KilledWorker) or, when the FMUs went down with the last worker that held
                # them first, cancels the run. Once more, in case something else killed them.
                runner.fmus.stale()
                if attempt < 1:
                    attempt += 1
                    continue
            rows = runner.error_rows([run], e, alone=True)
        else:
            future.release()
        runner.record(rows)
        return


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
