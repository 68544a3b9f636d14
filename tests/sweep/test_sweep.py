"""Real sweeps of tiny closed trefoils: a sweep interrupted after k cases and started again
finishes with every case stored once and the same physics as an uninterrupted sweep; the
serial, process-pool and Dask executors give identical records.

The cases are the cheapest real knots (36 vertices, loose L0/D0 = 20 to 24, 10 initial load
steps: ~0.6 s each here once Warp and numba are warm).
"""

from pathlib import Path

import pytest

from tightknot.sweep import physics, run_sweep
from tightknot.sweep.cases import grid
from tightknot.sweep.executors import SerialExecutor
from tightknot.sweep.store import Store

CASES = grid({"knot": "closed", "nodes": 36, "tighten_steps": 10},
             l0_over_d0=[20.0, 22.0, 24.0])


class Crash(RuntimeError):
    """The simulated crash."""


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict]:
    """Records of an uninterrupted serial sweep, by id."""
    report = run_sweep(CASES, tmp_path_factory.mktemp("ref") / "s", SerialExecutor())
    assert report.ok, [report.store.get(c)["failure"] for c in report.failed]
    return {r["id"]: r for r in report.records()}


def test_the_cases_are_real_knots(reference: dict[str, dict]) -> None:
    for rec in reference.values():
        res = rec["result"]
        assert rec["status"] == "ok" and res["knot_type"] == "3_1"
        # A loose knot (L0/D0 >= 20 > 16.37) does not pass through itself: gap > 0.5 D0
        # (the contact law's range; the hard limit is 0.05).
        assert res["min_gap_over_D0"] > 0.5
    # Three different lengths give three different knots.
    assert len({round(r["result"]["L_over_D"], 6) for r in reference.values()}) == 3


@pytest.mark.parametrize("k", [1, 2])
def test_a_sweep_interrupted_after_k_cases_resumes_and_loses_nothing(
        tmp_path: Path, reference: dict[str, dict], k: int) -> None:
    folder = tmp_path / "s"
    seen: list[str] = []

    def crash_after_k(record: dict) -> None:
        seen.append(record["id"])
        if len(seen) == k:
            raise Crash(f"simulated crash after {k} case(s)")

    with pytest.raises(Crash):
        run_sweep(CASES, folder, SerialExecutor(), on_record=crash_after_k)
    store = Store.open(folder)
    assert len(store.finished()) == k
    again = run_sweep(CASES, folder, SerialExecutor())
    assert sorted(again.skipped) == sorted(seen)
    assert len(again.ran) == len(CASES) - k
    assert set(again.ran).isdisjoint(seen)
    # Every case present exactly once: one file each, one index entry each, all ok.
    files = sorted(p.stem for p in (folder / "cases").glob("*.json"))
    assert files == sorted(c.id for c in CASES)
    assert sorted(Store.open(folder).index()["cases"]) == files
    assert again.ok
    # Same physics as the uninterrupted sweep, bit for bit (only timings differ).
    for rec in again.records():
        assert physics(rec) == physics(reference[rec["id"]])
    # A third run has nothing to do.
    third = run_sweep(CASES, folder, SerialExecutor())
    assert third.ran == [] and len(third.skipped) == len(CASES)


def test_process_pool_and_dask_give_the_serial_records(tmp_path: Path,
                                                       reference: dict[str, dict]) -> None:
    distributed = pytest.importorskip("distributed")
    from tightknot.sweep.executors import DaskExecutor, process_executor

    two = CASES[:2]
    # One spawned worker: each new process pays ~5 s of imports and table set-up (measured
    # here under load), which is all this test would add by running two.
    pool = process_executor(1)
    try:
        by_pool = run_sweep(two, tmp_path / "pool", pool)
    finally:
        pool.shutdown()
    # Dask's in-process local cluster: one worker thread, the test's own process.
    client = distributed.Client(processes=False, n_workers=1, threads_per_worker=1,
                                dashboard_address=None)
    try:
        by_dask = run_sweep(two, tmp_path / "dask", DaskExecutor(client))
    finally:
        client.close()
    for report in (by_pool, by_dask):
        assert report.ok and sorted(report.ran) == sorted(c.id for c in two)
        for rec in report.records():
            assert physics(rec) == physics(reference[rec["id"]])
    # The pool's records came from other processes than this one (spawned workers).
    import os

    assert {r["pid"] for r in by_pool.records()} != {os.getpid()}


def _close(a, b, path: str = "") -> None:
    """Records equal but for round-off: the batched rods follow their own tie's path with
    sums in another order and banded instead of sparse LU solves (tests/loading/test_batch.py:
    positions within 1e-10 D0), so measured floats agree to 1e-8 relative (absolute 1e-9
    for values near zero), and everything else exactly."""
    if isinstance(a, dict):
        assert sorted(a) == sorted(b), path
        for k in a:
            _close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for k, (x, y) in enumerate(zip(a, b, strict=True)):
            _close(x, y, f"{path}[{k}]")
    elif isinstance(a, float) and isinstance(b, float):
        assert b == pytest.approx(a, rel=1e-8, abs=1e-9), path
    else:
        assert a == b, path


def test_a_batched_sweep_gives_the_one_by_one_records_and_resumes(
        tmp_path: Path, reference: dict[str, dict]) -> None:
    folder = tmp_path / "b"
    first = run_sweep(CASES[:2], folder, SerialExecutor(), batch=8)
    assert first.ok and sorted(first.ran) == sorted(c.id for c in CASES[:2])
    # Resumed with the third case added: only that one runs (a batch of one).
    again = run_sweep(CASES, folder, SerialExecutor(), batch=8)
    assert again.ran == [CASES[2].id] and sorted(again.skipped) == sorted(first.ran)
    batches = {r["id"]: r["batch"] for r in again.records()}
    assert [batches[c.id]["rods"] for c in CASES] == [2, 2, 1]
    for rec in again.records():
        ref = reference[rec["id"]]
        # The same number of Newton iterations and load steps: each rod is its own tie.
        assert rec["result"]["newton_iterations"] == ref["result"]["newton_iterations"]
        assert rec["result"]["load_steps"] == ref["result"]["load_steps"]
        _close(physics(ref), physics(rec))


def test_a_batch_of_mixed_settings_is_refused_per_case() -> None:
    from tightknot.sweep.execute import run_batch

    mixed = grid({"knot": "closed", "nodes": 36, "tighten_steps": 10}, contact=["compliant",
                                                                              "rigid"])
    records = run_batch([c.params for c in mixed])
    assert [r["status"] for r in records] == ["error", "error"]
    assert "share" in records[0]["failure"] and "contact" in records[0]["failure"]
