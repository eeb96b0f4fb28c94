"""The batch driver: expand a spec, skip the keys done already, run the rest as Ray tasks and
commit their rows to Parquet as they finish.

Each task runs :func:`eos_svc.batch.task.run_chunk` on a few keys (one with validation, a small
chunk without; :meth:`BatchSpec.plans_per_task`) and returns their rows; only the driver
writes. A task whose worker dies is run again by Ray (``max_retries``, system failures only);
its rows reach the driver once, from the attempt that finished, and the store refuses a key it
has committed already, so no row is lost or written twice. A task that fails every retry is
counted as lost and not written: a rerun plans it.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

import ray

from eos_svc.batch.expansion import PlanKey, chunks, expand
from eos_svc.batch.progress import BatchSummary, ProgressBar
from eos_svc.batch.spec import BatchSpec
from eos_svc.batch.store import DatasetStore
from eos_svc.batch.task import run_chunk

#: tasks kept submitted per CPU, so a worker never waits for the driver
TASKS_PER_CPU = 2
#: the longest the driver waits for a task before it checks whether rows are due on disk (s)
WAIT_S = 1.0

RowsCallback = Callable[[list[dict[str, Any]]], None]


@contextmanager
def ray_session(address: str | None = None, workers: int | None = None) -> Iterator[float]:
    """Ray for a batch: the running session if there is one (left running), else a cluster's
    (``address``, e.g. ``HEAD:6379`` or ``auto``) or a new local one with ``workers`` CPUs
    (default: this machine's). Yields the CPUs it has."""
    started = not ray.is_initialized()
    if started:
        if address is not None:
            ray.init(address=address, logging_level=logging.ERROR, log_to_driver=False)
        else:
            ray.init(
                num_cpus=workers or os.cpu_count() or 1,
                include_dashboard=False,
                logging_level=logging.ERROR,
                log_to_driver=False,
            )
    try:
        yield float(ray.cluster_resources().get("CPU", 1.0))
    finally:
        if started:
            ray.shutdown()


def run_batch(
    spec: BatchSpec,
    out: str | Path,
    *,
    address: str | None = None,
    workers: int | None = None,
    progress: IO[str] | bool | None = True,
    on_rows: RowsCallback | None = None,
) -> BatchSummary:
    """Run ``spec`` into the directory ``out`` (resuming what it holds) and summarise.

    Args:
        spec: the batch.
        out: the output directory (see :mod:`eos_svc.batch.store`).
        address: a Ray cluster to join (default: a local Ray, unless one is running).
        workers: CPUs of the local Ray; with ``address``, the most tasks run at once.
        progress: a stream for the progress bar (True: stderr, False/None: none).
        on_rows: called in the driver with the rows of every finished task, before they are written.
    """
    keys = expand(spec)
    with DatasetStore(out) as store:
        todo = [k for k in keys if k.key not in store.done]
        summary = BatchSummary(skipped=len(keys) - len(todo))
        bar = None
        if progress:
            bar = ProgressBar(len(todo), summary.skipped, None if progress is True else progress)
        started = time.perf_counter()
        if todo:  # nothing left to plan: no Ray to start
            with ray_session(address, workers) as cpus:
                if address is not None and workers is not None:  # at most `workers` tasks at once
                    summary.workers, window = float(min(cpus, workers)), workers
                else:
                    summary.workers, window = cpus, max(1, int(cpus * TASKS_PER_CPU))
                run_tasks(spec, todo, store, summary, bar, on_rows, window=window)
        summary.wall_s = time.perf_counter() - started
        if bar is not None:
            bar.close()
    return summary


def run_tasks(
    spec: BatchSpec,
    todo: list[PlanKey],
    store: DatasetStore,
    summary: BatchSummary,
    bar: ProgressBar | None,
    on_rows: RowsCallback | None,
    window: int,
) -> None:
    """Submit ``todo`` in chunks (at most ``window`` in flight), collect and commit their rows."""
    task = ray.remote(run_chunk).options(num_cpus=1, max_retries=spec.run.max_retries, retry_exceptions=False)
    waiting = chunks(todo, spec.plans_per_task())
    waiting.reverse()  # popped from the end: submitted in expansion order
    in_flight: dict[Any, list[PlanKey]] = {}
    buffer: list[dict[str, Any]] = []
    last_write = time.perf_counter()
    while waiting or in_flight:
        while waiting and len(in_flight) < window:
            chunk = waiting.pop()
            in_flight[task.remote(chunk)] = chunk
        ready, _ = ray.wait(list(in_flight), num_returns=1, timeout=WAIT_S)
        for ref in ready:
            chunk = in_flight.pop(ref)
            try:
                rows = ray.get(ref)
            except ray.exceptions.RayError:  # failed every retry: not written, a rerun plans it
                summary.lost += len(chunk)
                continue
            if on_rows is not None:
                on_rows(rows)
            buffer.extend(rows)
            summary.add(rows)
            if bar is not None:
                bar.update(rows)
        due = time.perf_counter() - last_write >= spec.run.flush_seconds
        if buffer and (len(buffer) >= spec.run.rows_per_file or due or not (waiting or in_flight)):
            store.write(buffer)
            summary.files += 1
            buffer = []
            last_write = time.perf_counter()
