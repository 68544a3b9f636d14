"""The parameters of one ``tightknot tie`` run, as a file that reproduces it.

Every run folder holds ``config.json``: the exact parameters the run used (defaults resolved,
e.g. ``nodes``). ``tightknot tie --config FILE`` reads it back (JSON, or TOML with the same
keys on Python >= 3.11), so a run can be repeated bit for bit on the same machine.

The keys are the fields of :class:`TieConfig`: those of a :class:`~tightknot.study.params.Scene`,
a :class:`~tightknot.loading.options.LoadPath` and an :class:`~tightknot.study.params.Output`,
each declared there once with its default, range, unit and meaning. The loader validates
before any work: an unknown key, a value of the wrong type or out of its range is a
:class:`ValueError` that names the key and its valid range. SI units throughout.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from tightknot.loading.options import LOADS, LoadPath, default_coarse_nodes, parameters
from tightknot.study.params import (
    COLOR_ALIASES,
    COLOR_FIELDS,
    KNOT_DEFAULTS,
    SCENE_NAMES,
    Output,
    Scene,
    StartFile,
    check_scene,
    knot_defaults,
    resolve_nodes,
    resolve_start,
)

__all__ = ["COLOR_ALIASES", "COLOR_FIELDS", "TieConfig", "config_from_dict", "config_keys",
           "knot_specific", "load_config"]


@dataclass(frozen=True)
class TieConfig(Output, LoadPath, StartFile, Scene):
    """Parameters of one tie run (SI units): its scene, start curve, load path and outputs
    (the fields of :class:`~tightknot.study.params.Scene`,
    :class:`~tightknot.study.params.StartFile`, :class:`~tightknot.loading.options.LoadPath`
    and :class:`~tightknot.study.params.Output`, in that order).

    ``tighten_steps``, ``pull_steps`` and ``relax_iterations`` drive
    :func:`tightknot.loading.tie.tie` (closed knots; open knots pulled by ``force`` or to
    ``end_distance``); a ``target_lambda`` run uses
    :func:`tightknot.loading.pull.tie_to_lambda`'s own schedule with ``lambda_tolerance``
    and ``residual_tol``.
    """

    def to_dict(self) -> dict[str, Any]:
        """The parameters as a JSON-ready dict (every key, nulls included)."""
        return asdict(self)

    @property
    def scene_name(self) -> str:
        """Name of the scene this config ties (e.g. ``closed_trefoil``, ``open_figure_eight``)."""
        if self.start is not None:
            # A detected type may read "8_20|3_1#3_1" or "unknown(det=9)": a folder name.
            kt = "".join(c if c.isalnum() or c == "_" else "-" for c in self.knot_type)
            return f"{self.knot}_start_{kt.strip('-')}"
        return f"{self.knot}_{SCENE_NAMES[self.knot_type]}"

    def tie_options(self) -> dict[str, Any]:
        """Keyword options of :func:`tightknot.study.run.run_knot` for this config."""
        refine = {} if self.coarse_nodes is None else {"coarse_nodes": self.coarse_nodes}
        if self.target_lambda is not None:
            return {"target_lambda": self.target_lambda, "tolerance": self.lambda_tolerance,
                    "residual_tol": self.residual_tol, "section_path": self.section_path,
                    **refine}
        opts: dict[str, Any] = {"tighten_steps": self.tighten_steps,
                                "residual_tol": self.residual_tol,
                                "relax_iterations": self.relax_iterations,
                                "section_path": self.section_path}
        if self.knot == "open":
            opts.update(pull_steps=self.pull_steps, pull_force=self.force,
                        end_distance=self.end_distance)
        return {**opts, **refine}


_PARAMS = parameters(TieConfig)

#: Open-knot keys that are null when not used (the rest length and the loads): a closed
#: knot must leave them null.
_OPEN_ONLY = tuple(k for k, p in _PARAMS.items() if p.only == "open" and p.nullable)


def config_from_dict(data: dict[str, Any]) -> TieConfig:
    """Validate a mapping of parameters and return the resolved :class:`TieConfig`.

    Raises ValueError naming the key: unknown key, wrong type, out of range, or options that
    do not fit together (open-knot loads on a closed knot; not exactly one load on an open
    one; too few vertices for the knot; tails shorter than 10 D0).
    """
    if not isinstance(data, dict):
        raise ValueError(f"a tie config is a mapping of keys to values, got {type(data).__name__}")
    unknown = sorted(set(data) - set(_PARAMS))
    if unknown:
        raise ValueError(f"unknown key(s) {', '.join(map(repr, unknown))}; valid keys: "
                         f"{', '.join(_PARAMS)}")
    if "knot" not in data:
        raise ValueError("knot: missing (closed or open)")
    start = data.get("start") is not None
    # A start curve's knot type is any the topology names (checked against the curve).
    clean = {k: _start_knot_type(v) if start and k == "knot_type" else _PARAMS[k].check(v)
             for k, v in data.items()}
    knot = clean["knot"]
    if knot == "closed":
        given = [k for k in _OPEN_ONLY if clean.get(k) is not None]
        if given:
            raise ValueError(f"{', '.join(given)}: for open knots only (knot is closed)")
    else:
        loads = [k for k in LOADS if clean.get(k) is not None]
        if len(loads) != 1:
            raise ValueError("an open knot needs exactly one of force [N], end_distance [m] or "
                             f"target_lambda; got {', '.join(loads) or 'none'}")
    if not start:
        given = [k for k in ("units", "columns") if clean.get(k) is not None]
        if given:
            raise ValueError(f"{', '.join(given)}: for a start curve only (give start FILE)")
    if start:
        clean.update(resolve_start(clean))
        defaults = {k: v for k, v in knot_defaults(knot).items()
                    if k not in ("l0_over_d0", "length")}
    else:
        defaults = knot_defaults(knot, clean.get("knot_type", Scene.knot_type))
    for key, value in defaults.items():
        if clean.get(key) is None:
            clean[key] = value
    if clean.get("nodes") is None:
        clean["nodes"] = resolve_nodes({"diameter": Scene.diameter, **clean})
    if clean.get("coarse_nodes") is None:
        clean["coarse_nodes"] = default_coarse_nodes(clean["nodes"])  # a long rod ties coarse
    check_scene(clean)
    return TieConfig(**clean)


def _start_knot_type(value: Any) -> str:
    from tightknot.knots.start_curve import is_knot_name

    if not (isinstance(value, str) and is_knot_name(value)):
        raise ValueError(f"knot_type: {value!r} is not a knot type the knot table names "
                         "(e.g. 5_2, 8_20|3_1#3_1, unknown(det=9))")
    return value


def knot_specific(old: tuple[str, str], new: tuple[str, str]) -> set[str]:
    """Keys of a config for the knot ``old`` = (knot, knot_type) that do not carry over to
    ``new``: the per-knot defaults that differ, and on another knot those of one knot only."""
    # (a start curve's detected type has no per-knot defaults of its own)
    a, b = KNOT_DEFAULTS.get(old, {}), KNOT_DEFAULTS.get(new, {})
    keys = {k for k in a.keys() | b.keys() if a.get(k) != b.get(k)}
    if old != new:
        keys.add("nodes")  # a resolution of the old knot's rod, whose length follows it
    if old[0] != new[0]:
        keys |= {k for k, p in _PARAMS.items() if p.only is not None}
    return keys


def load_config(path: str | os.PathLike[str]) -> TieConfig:
    """Read and validate a config file (``.json``, or ``.toml`` on Python >= 3.11)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"--config {p}: not a UTF-8 text file ({exc.reason} at byte "
                         f"{exc.start})") from None
    except OSError as exc:
        raise ValueError(f"--config {p}: cannot read ({exc.strerror})") from None
    if p.suffix.lower() == ".toml":
        try:
            import tomllib
        except ImportError:  # Python 3.10
            raise ValueError(f"--config {p}: TOML needs Python >= 3.11; use JSON") from None
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"--config {p}: not valid TOML ({exc})") from None
    else:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ValueError(f"--config {p}: not valid JSON (line {exc.lineno}: {exc.msg})"
                             ) from None
    try:
        return config_from_dict(data)
    except ValueError as exc:
        raise ValueError(f"--config {p}: {exc}") from None


def config_keys() -> tuple[str, ...]:
    """Every key a config file may hold, in order."""
    return tuple(_PARAMS)
