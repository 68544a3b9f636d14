"""A sweep store as one flat table: one row per case and tightness level.

Each row holds the case's id and status, every scene and load-path parameter of the case
(its canonical parameters: defaults filled in, :mod:`tightknot.sweep.cases`), the level
(kind, target, reached, why not) and the level's measurements (SI units or
non-dimensional, the keys of the knot summary). A closed knot is one row with no level.
:func:`table_rows` needs nothing beyond the standard library; :func:`to_dataframe` and
Parquet files need the ``tables`` extra (pandas, pyarrow).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from tightknot.atomic import atomic_open, write_text_atomic
from tightknot.sweep.store import Store

#: Measurements of a level (or a closed knot) copied from its summary, in column order;
#: ``outside_calibrated_range`` and ``warnings`` (joined by "; ") say where a row leaves
#: the range its contact model was calibrated or judged in (the summary's).
MEASURES = ("knot_type", "pull_force_N", "lambda_oc", "end_to_end_m", "stretch", "L_over_D",
            "min_gap_over_D0", "min_area_ratio", "max_contact_width_fraction",
            "max_pressure_over_E", "kappa_D0_max", "kappa_D0_min", "max_approach_w_over_D0",
            "outside_calibrated_range", "warnings", "nodes", "newton_iterations",
            "wall_time_s")
#: Columns of every row before the parameters and the measures.
HEAD = ("case_id", "status", "knot", "level_kind", "level_index", "level_target", "reached",
        "level_failure")
#: File types :func:`write_table` writes, by suffix.
FORMATS = (".csv", ".parquet")

TABLES_HINT = 'pip install "tightknot[tables]" (pandas and pyarrow)'


def _end_to_end(summary: Mapping[str, Any]) -> float | None:
    """Distance between the rod's two ends [m] (an open knot's extension), from its
    stored centerline; None for a closed knot (no pulling force) or without one."""
    x = summary.get("centerline_m")
    if not x or "pull_force_N" not in summary:
        return None
    return math.dist(x[0], x[-1])


def _measures(summary: Mapping[str, Any] | None) -> dict[str, Any]:
    s = summary or {}
    out = {k: s.get(k) for k in MEASURES}
    out["end_to_end_m"] = _end_to_end(s) if s else None
    if out["warnings"] is not None:
        out["warnings"] = "; ".join(out["warnings"])
    return out


def _param_columns(records: list[dict[str, Any]]) -> list[str]:
    """Every parameter any case has, in the order the first case holding it lists them;
    a level list is not a column (its values are the rows' level_target)."""
    from tightknot.sweep.cases import LEVEL_KEYS

    cols: dict[str, None] = {}
    for r in records:
        for k in r["params"]:
            if k != "knot" and k not in LEVEL_KEYS:
                cols[k] = None
    return list(cols)


def table_rows(store: Store | str | Path) -> list[dict[str, Any]]:
    """The store's finished cases as flat rows (module docstring), in index order.

    A parameter that one case lacks (an open knot's ``length`` in a closed case's row) is
    None. An open case that failed before its levels (the tie) is one row with no level.
    """
    st = store if isinstance(store, Store) else Store.open(store, create=False)
    records = st.records()
    params = _param_columns(records)
    rows: list[dict[str, Any]] = []
    for r in records:
        base = {"case_id": r["id"], "status": r["status"], "knot": r["params"]["knot"]}
        base.update({k: r["params"].get(k) for k in params})
        res = r.get("result") or {}
        levels = res.get("levels")
        if not levels:
            rows.append({**base, "level_kind": None, "level_index": None, "level_target": None,
                         "reached": r["status"] == "ok" if "levels" not in res else False,
                         "level_failure": r.get("failure") or None,
                         **_measures(res if "levels" not in res else None)})
            continue
        for i, lv in enumerate(levels):
            m = _measures(lv.get("summary"))
            # The path's own numbers hold for a missed level too (its last good state).
            m["pull_force_N"] = lv["pull_force_N"]
            m["lambda_oc"] = lv["lambda_oc"]
            m["newton_iterations"] = lv["newton_iterations"]
            m["wall_time_s"] = lv["wall_time_s"]
            rows.append({**base, "level_kind": lv["kind"], "level_index": i,
                         "level_target": lv["target"], "reached": lv["reached"],
                         "level_failure": lv["failure"] or None, **m})
    return [{k: row.get(k) for k in (*HEAD, *params, *MEASURES)} for row in rows]


def param_columns(rows: list[dict[str, Any]]) -> list[str]:
    """The case-parameter columns of table ``rows`` (neither head nor measure)."""
    return [k for k in (rows[0] if rows else {}) if k not in HEAD and k not in MEASURES]


def to_dataframe(store: Store | str | Path):  # noqa: ANN201 (pandas is optional)
    """The store's table (:func:`table_rows`) as a pandas DataFrame (the ``tables``
    extra)."""
    try:
        import pandas as pd
    except ImportError:
        raise ImportError(f"to_dataframe needs pandas: {TABLES_HINT}") from None
    rows = table_rows(store)
    columns = list(rows[0]) if rows else list(HEAD)
    return pd.DataFrame(rows, columns=columns)


def write_table(store: Store | str | Path, path: str | Path) -> int:
    """Write the store's table to ``path`` (.csv, or .parquet with the ``tables`` extra),
    atomically; returns the number of rows. A CSV cell of None is empty."""
    out = Path(path)
    if out.suffix not in FORMATS:
        raise ValueError(f"--out {out}: the file name must end in {' or '.join(FORMATS)}")
    if out.suffix == ".parquet":
        try:
            import pyarrow  # noqa: F401  (pandas' Parquet engine)
        except ImportError:
            raise ValueError(f"--out {out}: Parquet needs pyarrow: {TABLES_HINT}") from None
        frame = to_dataframe(store)
        with atomic_open(out, "wb") as handle:
            frame.to_parquet(handle, index=False)
        return len(frame)
    rows = table_rows(store)
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=list(rows[0]) if rows else list(HEAD),
                            lineterminator="\n")
    writer.writeheader()
    for row in rows:
        # repr keeps every float's digits (a round trip is exact, as the centerline csv).
        writer.writerow({k: "" if v is None else (repr(v) if isinstance(v, float) else v)
                         for k, v in row.items()})
    write_text_atomic(out, text.getvalue())
    return len(rows)
