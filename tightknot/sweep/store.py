"""The result store of a sweep: one JSON file per case plus an index, all written atomically.

Layout of a store folder::

    index.json           every case of the sweep(s) run here: id, params, status, file
    cases/<id>.json      one finished case: id, params, status, failure, result, timing

The case files are the truth; the index is a summary that is rewritten (atomically) after
every finished case. A crash at any moment leaves complete files only (tightknot.atomic):
at worst a case file whose index entry is missing or still "pending", which
:meth:`Store.open` repairs by reading the case files back. So a sweep that is interrupted
and started again skips every finished case and loses nothing but the cases that were
running. One sweep at a time writes a store (two writing the same folder at once would
race on the index; the case files stay whole, and the next :meth:`Store.open` repairs it).
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from tightknot.atomic import write_json_atomic
from tightknot.sweep.cases import Case

INDEX = "index.json"
CASES = "cases"
STORE_VERSION = 1

#: Statuses of a case: not run yet; finished with the physics converged; finished with a
#: physics failure (no convergence, a topology change, a level not reached); finished by an
#: exception in the run (a bug or bad input the checks did not catch).
PENDING, OK, FAILED, ERROR = "pending", "ok", "failed", "error"
FINISHED = (OK, FAILED, ERROR)


class StoreError(ValueError):
    """A store folder that is not a tightknot sweep store, or an inconsistent one."""


class Store:
    """A sweep's result folder (module docstring). Use :meth:`open`."""

    def __init__(self, folder: Path, index: dict[str, Any]) -> None:
        self.folder = folder
        self._index = index

    # -- opening ---------------------------------------------------------------------------
    @classmethod
    def open(cls, folder: str | Path, create: bool = True) -> Store:
        """Open (or create) the store in ``folder``; its parent must exist.

        The index is checked against the case files and repaired: a case file without an
        index entry (a crash between the two writes) is added, an entry marked finished
        whose file is gone goes back to pending.
        """
        root = Path(folder)
        if root.exists() and not root.is_dir():
            raise StoreError(f"sweep store {root} exists and is not a folder")
        if not root.exists():
            if not create:
                raise StoreError(f"sweep store {root} does not exist")
            parent = root.parent if str(root.parent) else Path(".")
            if not parent.is_dir():
                raise StoreError(f"parent folder of the sweep store does not exist: {parent}")
            root.mkdir()
        (root / CASES).mkdir(exist_ok=True)
        index_path = root / INDEX
        if index_path.exists():
            try:
                index = json.loads(index_path.read_text())
            except json.JSONDecodeError as err:
                raise StoreError(f"{index_path}: not valid JSON ({err})") from None
            if not isinstance(index, dict) or index.get("store") != "tightknot-sweep":
                raise StoreError(f"{index_path} is not a tightknot sweep index")
            if index.get("version") != STORE_VERSION:
                raise StoreError(f"{index_path}: store version {index.get('version')!r}, this "
                                 f"tightknot reads version {STORE_VERSION}")
        else:
            if any(p for p in root.iterdir() if p.name != CASES):
                raise StoreError(f"{root} holds files but no {INDEX}: not a sweep store (use "
                                 "an empty or new folder)")
            index = {"store": "tightknot-sweep", "version": STORE_VERSION, "cases": {}}
        store = cls(root, index)
        if store._repair() or not index_path.exists():
            store._write_index()
        return store

    def _repair(self) -> bool:
        changed = False
        entries = self._index["cases"]
        on_disk = {p.stem: p for p in (self.folder / CASES).glob("*.json")}
        for cid, path in on_disk.items():
            entry = entries.get(cid)
            if entry is not None and entry["status"] in FINISHED:
                continue
            record = self._read(path)
            entries[cid] = self._entry(record)
            changed = True
        for cid, entry in entries.items():
            if entry["status"] in FINISHED and cid not in on_disk:
                entry.update(status=PENDING, failure="")
                changed = True
        return changed

    # -- reading ---------------------------------------------------------------------------
    def _read(self, path: Path) -> dict[str, Any]:
        try:
            record = json.loads(path.read_text())
        except json.JSONDecodeError as err:
            # Atomic writes never leave a partial file: this one was edited by hand.
            raise StoreError(f"{path}: not valid JSON ({err})") from None
        if not isinstance(record, dict) or record.get("id") != path.stem:
            raise StoreError(f"{path}: not a case record of id {path.stem}")
        return record

    def case_path(self, cid: str) -> Path:
        """Path of the case file of id ``cid``."""
        return self.folder / CASES / f"{cid}.json"

    def status(self, cid: str) -> str | None:
        """Status of case ``cid`` (None if the store does not know it)."""
        entry = self._index["cases"].get(cid)
        return None if entry is None else entry["status"]

    def finished(self) -> set[str]:
        """Ids of the finished cases (ok, failed or error)."""
        return {c for c, e in self._index["cases"].items() if e["status"] in FINISHED}

    def get(self, cid: str) -> dict[str, Any]:
        """The record of finished case ``cid``."""
        if self.status(cid) not in FINISHED:
            raise KeyError(f"case {cid} is not finished in {self.folder}")
        return self._read(self.case_path(cid))

    def records(self) -> list[dict[str, Any]]:
        """Every finished record, in index order."""
        return [self.get(c) for c in self._index["cases"] if self.status(c) in FINISHED]

    def index(self) -> dict[str, Any]:
        """A copy of the index."""
        return json.loads(json.dumps(self._index))

    # -- writing ---------------------------------------------------------------------------
    @staticmethod
    def _entry(record: dict[str, Any]) -> dict[str, Any]:
        return {"params": record["params"], "status": record["status"],
                "failure": record.get("failure", ""), "file": f"{CASES}/{record['id']}.json"}

    def plan(self, cases: Iterable[Case]) -> None:
        """Add ``cases`` to the index as pending (finished ones are left as they are)."""
        entries = self._index["cases"]
        changed = False
        for case in cases:
            if case.id not in entries:
                entries[case.id] = {"params": case.params, "status": PENDING, "failure": "",
                                    "file": f"{CASES}/{case.id}.json"}
                changed = True
            elif entries[case.id]["params"] != case.params:
                raise StoreError(f"case id {case.id} is in {self.folder} with other "
                                 "parameters (hash collision or an edited index)")
        if changed:
            self._write_index()

    def put(self, record: dict[str, Any]) -> Path:
        """Write a finished case's record (file first, then the index; both atomic)."""
        if record.get("status") not in FINISHED:
            raise ValueError(f"record status must be one of {FINISHED}, got "
                             f"{record.get('status')!r}")
        path = self.case_path(record["id"])
        write_json_atomic(path, record)
        self._index["cases"][record["id"]] = self._entry(record)
        self._write_index()
        return path

    def forget(self, cid: str) -> None:
        """Mark case ``cid`` pending again (its file is removed), e.g. to retry a failure."""
        path = self.case_path(cid)
        if path.exists():
            path.unlink()
        entry = self._index["cases"].get(cid)
        if entry is not None:
            entry.update(status=PENDING, failure="")
            self._write_index()

    def _write_index(self) -> None:
        counts = {s: 0 for s in (PENDING, *FINISHED)}
        for e in self._index["cases"].values():
            counts[e["status"]] += 1
        self._index["counts"] = counts
        write_json_atomic(self.folder / INDEX, self._index)
