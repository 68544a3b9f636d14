"""Run a sweep: cases through an executor into a store, resuming where a previous run
stopped.

Every case is first added to the store's index as pending; the cases already finished
there are skipped (``retry_failed`` runs the failed ones again). The rest are submitted to
the executor a few at a time (a bounded window, so that a crash loses only the cases that
were running), and each record is written to the store the moment it comes back. Killing
the sweep at any point and starting it again with the same cases therefore finishes the
work and gives the same records, each stored once.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tightknot.sweep.cases import Case
from tightknot.sweep.execute import batch_key, run_batch, run_case
from tightknot.sweep.executors import SerialExecutor, process_executor
from tightknot.sweep.store import ERROR, FAILED, FINISHED, OK, Store

RecordHook = Callable[[dict[str, Any]], None]


@dataclass
class SweepReport:
    """What a call of :func:`run_sweep` did.

    Attributes:
        store: the store the records are in.
        cases: the sweep's cases, in the order given.
        ran: ids of the cases run by this call, in the order they finished.
        skipped: ids of the cases found finished in the store (not run again).
        statuses: status of every case of the sweep ("ok", "failed", "error").
        wall_time_s: wall-clock time of this call [s].
    """

    store: Store
    cases: list[Case]
    ran: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    statuses: dict[str, str] = field(default_factory=dict)
    wall_time_s: float = 0.0

    @property
    def failed(self) -> list[str]:
        """Ids of the cases whose physics failed or that raised."""
        return [c.id for c in self.cases if self.statuses.get(c.id) in (FAILED, ERROR)]

    @property
    def ok(self) -> bool:
        """Every case finished with status "ok"."""
        return all(self.statuses.get(c.id) == OK for c in self.cases)

    def records(self) -> list[dict[str, Any]]:
        """The sweep's records, in case order."""
        return [self.store.get(c.id) for c in self.cases]


def _window(executor: Executor) -> int | None:
    if isinstance(executor, SerialExecutor):
        return 1
    if isinstance(executor, ProcessPoolExecutor):
        # Two per worker keeps every worker busy while a result is being stored.
        return 2 * executor._max_workers  # noqa: SLF001 (no public accessor)
    return None  # a cluster schedules everything it is given


def _units(todo: list[Case], batch: int | None) -> list[list[Case]]:
    """The executor's tasks: one case each, or (``batch``) the closed-knot cases that share
    a batch key in groups of at most ``batch``, placed where their first case was."""
    if batch is None:
        return [[c] for c in todo]
    units: list[list[Case]] = []
    open_group: dict[tuple, list[Case]] = {}
    for case in todo:
        key = batch_key(case.params)
        if key is None:
            units.append([case])
            continue
        group = open_group.get(key)
        if group is None or len(group) >= batch:
            group = []
            open_group[key] = group
            units.append(group)
        group.append(case)
    return units


def run_sweep(
    cases: Iterable[Case],
    store: Store | str | Path,
    executor: Executor | None = None,
    *,
    retry_failed: bool = False,
    on_record: RecordHook | None = None,
    max_pending: int | None = None,
    device: str = "cpu",
    batch: int | None = None,
) -> SweepReport:
    """Run every case of ``cases`` not yet finished in ``store``.

    Args:
        cases: the sweep (see :func:`tightknot.sweep.cases.grid`); duplicates run once.
        store: a :class:`Store` or its folder (created if missing; its parent must exist).
        executor: where the cases run (default: a process pool of up to the CPU count
            workers, shut down at the end; its workers are spawned, so a script calling
            this needs the usual ``if __name__ == "__main__":`` guard); an executor passed
            in stays open.
        retry_failed: run again the cases stored as failed or error.
        on_record: called with each record after it is stored (progress output); an
            exception there stops the sweep (the stored records stay).
        max_pending: most tasks (cases, or batches) submitted at once (default: 1
            serial, 2 per worker for a process pool, all for Dask).
        device: Warp device of the workers.
        batch: tie up to this many closed-knot cases together in one model
            (:func:`tightknot.sweep.execute.run_batch`; cases that share
            :data:`~tightknot.sweep.execute.BATCH_KEYS`, in the order given), each batch
            one task of the executor; open-knot cases run one by one. None: every case
            alone. A batch's records are stored when the whole batch is back.
    """
    if batch is not None and not (isinstance(batch, int) and batch >= 1):
        raise ValueError(f"batch must be None or a whole number >= 1, got {batch!r}")
    start = time.perf_counter()
    unique: dict[str, Case] = {}
    for case in cases:
        unique.setdefault(case.id, case)
    todo_cases = list(unique.values())
    if not isinstance(store, Store):
        store = Store.open(store)
    store.plan(todo_cases)
    report = SweepReport(store, todo_cases)
    for case in todo_cases:
        if retry_failed and store.status(case.id) in (FAILED, ERROR):
            store.forget(case.id)
    todo = []
    for case in todo_cases:
        if store.status(case.id) in FINISHED:
            report.skipped.append(case.id)
            report.statuses[case.id] = store.status(case.id)
        else:
            todo.append(case)
    if not todo:
        report.wall_time_s = time.perf_counter() - start
        return report
    units = _units(todo, batch)
    owned = executor is None
    if executor is None:
        import os

        executor = process_executor(min(len(units), os.cpu_count() or 1))
    window = max_pending or _window(executor) or len(units)
    if window < 1:
        raise ValueError(f"max_pending must be >= 1, got {max_pending}")
    pending: dict[Future, list[str]] = {}
    position = {case.id: k for k, case in enumerate(todo)}
    queue = list(reversed(units))
    finished_ok = False
    try:
        while queue or pending:
            while queue and len(pending) < window:
                unit = queue.pop()
                if batch is None or batch_key(unit[0].params) is None:
                    fut = executor.submit(run_case, unit[0].params, device)
                else:
                    fut = executor.submit(run_batch, [c.params for c in unit], device)
                pending[fut] = [c.id for c in unit]
            done, _ = wait(list(pending), return_when=FIRST_COMPLETED)
            # Store in submission order among those done together (stable indexes).
            for fut in sorted(done, key=lambda f: position[pending[f][0]]):
                ids = pending.pop(fut)
                out = fut.result()  # an executor failure (a dead worker) stops the sweep
                records = out if isinstance(out, list) else [out]
                got = [r.get("id") for r in records]
                if got != ids:
                    raise RuntimeError(f"executor returned the records of {got} for the "
                                       f"cases {ids}")
                for record in records:
                    store.put(record)
                    report.ran.append(record["id"])
                    report.statuses[record["id"]] = record["status"]
                    if on_record is not None:
                        on_record(record)
        finished_ok = True
    finally:
        if not finished_ok:
            for fut in pending:
                fut.cancel()
        if owned:
            executor.shutdown(wait=finished_ok, cancel_futures=not finished_ok)
    report.wall_time_s = time.perf_counter() - start
    return report
