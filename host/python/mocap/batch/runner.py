"""The batch's client: its takes submitted to Dask distributed — a LocalCluster of this
machine's cores, one single-threaded worker process each, or an existing cluster given its
scheduler's address — their results gathered as they end, with a progress line."""

from __future__ import annotations

import contextlib
import logging
import os
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TextIO

from mocap.batch import task
from mocap.batch.inputs import Input
from mocap.errors import InputError

CONNECT_TIMEOUT_S = 10


@contextlib.contextmanager
def client(scheduler: str | None, workers: int | None) -> Iterator:
    """A Dask client of the cluster at `scheduler`, or of a LocalCluster of `workers` processes
    (default: one per core) that ends with this process (its workers end when it does, killed
    or not: distributed's worker processes watch a pipe only their parent holds)."""
    from distributed import Client, LocalCluster  # loaded only by the batch: it takes a second

    logging.getLogger("distributed").setLevel(logging.WARNING)  # its INFO lines would bury the progress line
    if scheduler is not None:
        try:
            c = Client(scheduler, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError, ValueError) as e:
            raise InputError(f"cannot reach the Dask scheduler at {scheduler}: {e}") from None
        with c:
            yield c
        return
    if workers is not None and workers < 1:
        raise InputError(f"--workers {workers}: give at least one")
    n = workers or len(os.sched_getaffinity(0))
    # One thread a worker process; Dask starts them with OMP/MKL/OPENBLAS_NUM_THREADS=1 (its
    # distributed.nanny.pre-spawn-environ), the detector's inference runs on one thread: N workers
    # use N cores (the calibration's two Ceres threads aside).
    with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=logging.ERROR) as cluster, Client(cluster) as c:
        yield c


def run(takes: list[Input], out: Path, options: task.Options, scheduler: str | None = None,
        workers: int | None = None, progress: TextIO = sys.stderr) -> list[dict]:
    """Every take's result (task.run's), in the order given."""
    from distributed import as_completed

    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    results: dict[str, dict] = {}
    with client(scheduler, workers) as c:
        futures = {c.submit(task.run, take, out, options, key=f"take-{take.name}", pure=False): take
                   for take in takes}
        line = Progress(len(takes), progress)
        for future in as_completed(futures):
            take = futures[future]
            results[take.name] = _result(future, take)
            line.update(results[take.name])
    return [results[take.name] for take in takes]


def _result(future, take: Input) -> dict:
    """The task's result, or its failure as one (a worker that died running it, a lost scheduler)."""
    try:
        return future.result()
    except Exception as e:  # the task's own errors are in its result; this is the cluster's
        return {"name": take.name, "take": str(take.path), "kind": take.kind, "status": "failed",
                "error": f"{type(e).__name__}: {e}", "skipped": False}


class Progress:
    """One line of progress: redrawn in place on a terminal, a line per take otherwise (logs)."""

    def __init__(self, total: int, stream: TextIO, width: int = 30):
        self.total, self.stream, self.width = total, stream, width
        self.done = self.failed = 0
        self.tty = stream.isatty()

    def update(self, result: dict) -> None:
        self.done += 1
        self.failed += result["status"] != "ok"
        filled = self.width * self.done // max(1, self.total)
        what = "solved before" if result.get("skipped") else result["status"]
        seconds = f", {result['seconds']:.1f} s" if "seconds" in result and not result.get("skipped") else ""
        text = (f"[{'#' * filled}{'.' * (self.width - filled)}] {self.done}/{self.total} takes, {self.failed} failed; "
                f"{result['name']}: {what}{seconds}")
        self.stream.write(("\r" + text + ("\n" if self.done == self.total else "")) if self.tty else text + "\n")
        self.stream.flush()
