"""A study's --out folder (docs/studies.md): one sweep at a time (`StudyLock`), the rows as a
Parquet dataset written as runs finish (`Writer`, `load_results`), and the summary."""

import fcntl
import json
import os
import socket
import time
import uuid
from pathlib import Path

import pandas as pd

from . import study as st


class SweepError(Exception):
    """A study that cannot start (its --out, its lock, its scheduler), with what to change."""


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


def make_row(run, metrics, seconds, worker):
    row = {"run_id": st.run_id(run)}
    row.update({f"param:{k}": v for k, v in sorted(run.items())})
    row.update(metrics)
    row.update(wall_time=seconds, worker=worker)
    return row


def first_error(failed, order):
    """The message of the first failed run in the study's order, with its parameters."""
    row = failed.assign(_order=failed["run_id"].map(order)).sort_values("_order").iloc[0]
    params = ", ".join(f"{k[6:]} = {row[k]}" for k in row.index if k.startswith("param:") and not pd.isna(row[k]))
    return f"{row['message']} (run {row['run_id']}{': ' + params if params else ''})"


def summarise(spec, results, executed, elapsed, order=None, master=None):
    lines = [f"study {spec['study']['name']}: {len(results)} rows in results.parquet; this call ran {executed} in "
             f"{elapsed:.1f} s ({executed / elapsed if elapsed > 0 else 0:.2f} runs/s)"
             + (f" with the {master} master" if master and executed else "")]
    if len(results):
        counts = results["status"].value_counts().to_dict()
        lines.append("status: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
        lines.append(f"stable: {int(results['stable'].sum())} of {len(results)}")
        for metric in ("max_leg_error", "max_pose_error", "max_stop_force", "peak_deceleration", "energy_residual",
                       "min_supply_pressure", "landing_deceleration", "cue_error", "max_usage", "least_scale",
                       "max_tilt"):
            column = results[metric].dropna()
            if len(column):
                lines.append(f"{metric}: min {column.min():.3g}, median {column.median():.3g}, max {column.max():.3g}")
        failed = results[results["status"] == "error"]
        if len(failed):
            lines.append(f"first error: {first_error(failed, order or {})}")
    return "\n".join(lines)


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
