"""Read a tightknot .rrd back with ``rerun.chunk.RrdReader``: for tests and checks, not viewing.

The rows of one entity may be spread over several chunks (the SDK batches rows by time and
size), so every query here gathers rows from all chunks of the entity before it answers.
Component columns are named ``"<Archetype>:<field>"``, e.g. ``"Points3D:positions"``,
``"LineStrips3D:colors"``, ``"Scalars:scalars"``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np
from rerun.chunk import RrdReader

from tightknot.viz.rerun_log import LOAD_STEP_TIMELINE

# Rerun's own bookkeeping entity (recording properties), not data we logged.
_PROPERTIES_ENTITY = "/__properties"


@dataclass(frozen=True)
class Row:
    """One logged row of one component: its step (None if static) and its decoded value."""

    step: int | None
    value: Any


def _entity(path: str) -> str:
    """Rerun stores entity paths with a leading slash; accept both spellings."""
    return "/" + path.strip("/")


def _chunks(rrd: str | os.PathLike[str]) -> list[Any]:
    return list(RrdReader(rrd).stream())


def entity_paths(rrd: str | os.PathLike[str]) -> list[str]:
    """Sorted entity paths (with leading slash) of the first recording, without rerun's own."""
    paths = {c.entity_path for c in _chunks(rrd)}
    paths.discard(_PROPERTIES_ENTITY)
    return sorted(paths)


def static_entity_paths(rrd: str | os.PathLike[str]) -> list[str]:
    """Sorted entity paths that hold static data (logged with ``static=True``)."""
    return sorted({c.entity_path for c in _chunks(rrd) if c.is_static} - {_PROPERTIES_ENTITY})


def row_counts(rrd: str | os.PathLike[str], timeline: str = LOAD_STEP_TIMELINE) -> dict[str, int]:
    """Number of rows per entity along ``timeline`` (static rows not counted), over all chunks."""
    counts: dict[str, int] = {}
    for chunk in _chunks(rrd):
        if timeline in chunk.timeline_names:
            counts[chunk.entity_path] = counts.get(chunk.entity_path, 0) + chunk.num_rows
    return counts


def component_rows(
    rrd: str | os.PathLike[str],
    entity: str,
    component: str,
    timeline: str = LOAD_STEP_TIMELINE,
) -> list[Row]:
    """All rows of ``component`` logged on ``entity``, in logging order.

    Rows from several chunks are concatenated; a stable sort by step keeps the logging order
    among rows of one step (chunks of one entity are written in order, rows within a chunk are
    sorted by row id, i.e. by logging time). Static rows come first with ``step=None``.
    Rows where the component was not logged are skipped.
    """
    target = _entity(entity)
    rows: list[Row] = []
    for chunk in _chunks(rrd):
        if chunk.entity_path != target:
            continue
        batch = chunk.to_record_batch()
        if component not in batch.schema.names:
            continue
        values = batch.column(component).to_pylist()
        if timeline in batch.schema.names:
            steps: list[int | None] = batch.column(timeline).to_pylist()
        else:
            steps = [None] * len(values)
        rows.extend(Row(s, v) for s, v in zip(steps, values, strict=True) if v is not None)
    rows.sort(key=lambda row: -1 if row.step is None else row.step)
    return rows


def steps(rrd: str | os.PathLike[str], entity: str, component: str) -> list[int]:
    """Sorted distinct ``load_step`` values at which ``component`` was logged on ``entity``."""
    return sorted({r.step for r in component_rows(rrd, entity, component) if r.step is not None})


def last_points3d(rrd: str | os.PathLike[str], entity: str, step: int | None = None) -> np.ndarray:
    """Positions of the last ``Points3D`` row of ``entity`` (at ``step`` if given), (K, 3).

    float32, as rerun stores them. Raises KeyError when there is no such row.
    """
    rows = component_rows(rrd, entity, "Points3D:positions")
    if step is not None:
        rows = [r for r in rows if r.step == step]
    if not rows:
        where = "" if step is None else f" at step {step}"
        raise KeyError(f"no Points3D positions logged on {_entity(entity)}{where}")
    return np.asarray(rows[-1].value, dtype=np.float32).reshape(-1, 3)


def scalar_series(rrd: str | os.PathLike[str], entity: str) -> tuple[np.ndarray, np.ndarray]:
    """``(steps, values)`` of a ``Scalars`` series (one value per row), int64 and float64."""
    rows = [r for r in component_rows(rrd, entity, "Scalars:scalars") if r.step is not None]
    return (
        np.array([r.step for r in rows], dtype=np.int64),
        np.array([r.value[0] for r in rows], dtype=np.float64),
    )


def unpack_rgba(packed: list[int] | np.ndarray) -> np.ndarray:
    """Rerun colours are packed 0xRRGGBBAA uint32; return (K, 4) uint8 RGBA."""
    c = np.asarray(packed, dtype=np.uint32)
    shifts = np.array([24, 16, 8, 0], dtype=np.uint32)
    return ((c[:, None] >> shifts) & 0xFF).astype(np.uint8)


def blueprint_views(rrd: str | os.PathLike[str]) -> list[tuple[str, str]]:
    """Sorted ``(view class, origin)`` of the views in the file's blueprint(s).

    View classes are rerun's identifiers, e.g. ``"3D"`` and ``"TimeSeries"``.
    """
    reader = RrdReader(rrd)
    views: list[tuple[str, str]] = []
    for store in reader.blueprints():
        for chunk in reader.stream(store=store):
            batch = chunk.to_record_batch()
            names = batch.schema.names
            if (
                "ViewBlueprint:class_identifier" not in names
                or "ViewBlueprint:space_origin" not in names
            ):
                continue
            kinds = batch.column("ViewBlueprint:class_identifier").to_pylist()
            origins = batch.column("ViewBlueprint:space_origin").to_pylist()
            for kind, origin in zip(kinds, origins, strict=True):
                if kind and origin:
                    views.append((kind[0], origin[0]))
    return sorted(views)
