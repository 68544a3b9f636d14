"""The sweep store's bookkeeping: atomic files, an index repaired from the case files.

These tests exercise the files only (synthetic records, no physics); the real sweeps that
are interrupted and resumed are in test_sweep.py.
"""

import json
from pathlib import Path

import pytest

from tightknot.sweep.cases import grid
from tightknot.sweep.store import FAILED, OK, PENDING, Store, StoreError


def _record(case, status: str = OK) -> dict:
    return {"id": case.id, "params": case.params, "status": status, "failure": "",
            "result": {"L_over_D": 17.0}, "wall_time_s": 1.0}


def test_records_survive_a_crash_between_the_case_file_and_the_index(tmp_path: Path) -> None:
    cases = grid({"knot": "closed", "nodes": 40}, l0_over_d0=[18, 20, 22])
    store = Store.open(tmp_path / "s")
    store.plan(cases)
    assert [store.status(c.id) for c in cases] == [PENDING] * 3
    store.put(_record(cases[0]))
    # A crash after the case file was renamed into place, before the index was: the case
    # file is there, the index still says pending.
    index = json.loads((tmp_path / "s" / "index.json").read_text())
    (tmp_path / "s" / "cases" / f"{cases[1].id}.json").write_text(
        json.dumps(_record(cases[1], FAILED)))
    reopened = Store.open(tmp_path / "s")
    assert reopened.status(cases[0].id) == OK
    assert reopened.status(cases[1].id) == FAILED  # found from its file
    assert reopened.status(cases[2].id) == PENDING
    assert reopened.finished() == {cases[0].id, cases[1].id}
    assert reopened.index()["counts"] == {"pending": 1, "ok": 1, "failed": 1, "error": 0}
    # A finished entry whose file was deleted goes back to pending.
    (tmp_path / "s" / "cases" / f"{cases[0].id}.json").unlink()
    assert Store.open(tmp_path / "s").status(cases[0].id) == PENDING
    assert index["store"] == "tightknot-sweep"
    # No temporary files are left by the atomic writes.
    assert not [p for p in (tmp_path / "s").rglob(".*.tmp")]


def test_forget_makes_a_case_pending_again(tmp_path: Path) -> None:
    (case,) = grid({"knot": "closed", "nodes": 40}, l0_over_d0=[18])
    store = Store.open(tmp_path / "s")
    store.plan([case])
    store.put(_record(case, FAILED))
    store.forget(case.id)
    assert store.status(case.id) == PENDING
    assert not store.case_path(case.id).exists()
    with pytest.raises(KeyError):
        store.get(case.id)


def test_folders_that_are_not_stores_are_refused(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("x")
    with pytest.raises(StoreError, match="not a folder"):
        Store.open(tmp_path / "file")
    with pytest.raises(StoreError, match="parent folder"):
        Store.open(tmp_path / "missing" / "s")
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    with pytest.raises(StoreError, match="no index.json"):
        Store.open(other)
    (other / "index.json").write_text("{\"store\": \"x\"}")
    with pytest.raises(StoreError, match="not a tightknot sweep index"):
        Store.open(other)
    with pytest.raises(ValueError, match="record status"):
        Store.open(tmp_path / "s").put({"id": "0" * 16, "status": "pending"})
