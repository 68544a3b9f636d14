"""Sweeps over the knot scenes' parameters, resumable, on local processes or a Dask cluster.

* :mod:`~tightknot.sweep.cases`: a case is a canonical JSON dict with a stable id;
  :func:`grid` makes the Cartesian product of parameter lists.
* :mod:`~tightknot.sweep.path`: an open knot's tightness levels reached one after the other
  along one continuation path (tie once, then pull level by level).
* :mod:`~tightknot.sweep.execute`: one case -> its JSON record (what the workers run);
  closed-knot cases can also be tied together in one model (``run_sweep(...,
  batch=N)``, ``tightknot sweep closed ... --batch N``): the same records, each batch
  one task of the executor.
* :mod:`~tightknot.sweep.store`: one atomically written JSON file per case, plus an index.
* :mod:`~tightknot.sweep.executors`: serial, local processes (spawned), Dask distributed.
* :mod:`~tightknot.sweep.sweep`: :func:`run_sweep`, which skips what a store has finished.
* :mod:`~tightknot.sweep.table`: a store as one flat table, a row per case and level
  (:func:`table_rows`, :func:`to_dataframe`, :func:`write_table`).
* :mod:`~tightknot.sweep.commands`: ``tightknot sweep``.

Example::

    from tightknot.sweep import grid, run_sweep
    cases = grid({"knot": "open", "nodes": 150, "target_lambda": [14, 13, 12]},
                 length=[0.185, 0.16])
    report = run_sweep(cases, "runs/sweep")      # process pool; run again to resume
"""

from tightknot.sweep.cases import Case, canonical, case_id, grid
from tightknot.sweep.execute import physics, run_case
from tightknot.sweep.executors import DaskExecutor, SerialExecutor, make_executor
from tightknot.sweep.store import Store, StoreError
from tightknot.sweep.sweep import SweepReport, run_sweep
from tightknot.sweep.table import table_rows, to_dataframe, write_table

__all__ = [
    "Case", "DaskExecutor", "SerialExecutor", "Store", "StoreError", "SweepReport",
    "canonical", "case_id", "grid", "make_executor", "physics", "run_case", "run_sweep",
    "table_rows", "to_dataframe", "write_table",
]
