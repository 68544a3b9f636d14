"""The parameters of one ``tightknot tie`` run, as a file that reproduces it.

Every run folder holds ``config.json``: the exact parameters the run used (defaults resolved,
e.g. ``nodes``). ``tightknot tie --config FILE`` reads it back (JSON, or TOML with the same
keys on Python >= 3.11), so a run can be repeated bit for bit on the same machine.

The loader validates before any work: an unknown key, a value of the wrong type or out of its
range is a :class:`ValueError` that names the key and its valid range. SI units throughout.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

from tightknot.viz.rerun_log import ROD_FIELDS

#: Fields a rod tube may be coloured by in the .rrd.
COLOR_FIELDS = tuple(ROD_FIELDS)

#: Short aliases accepted for ``color_by`` (the CLI's spelling of the issue's field names).
COLOR_ALIASES = {"contact_width": "contact_width_fraction"}

#: Default vertex counts (the tie command's: enough for the study's measurements).
DEFAULT_NODES = {"closed": 200, "open": 300}


@dataclass(frozen=True)
class _Range:
    """Valid interval of a number; ``low_open``/``high_open`` exclude the end points."""

    low: float
    high: float
    low_open: bool = False
    high_open: bool = False

    def contains(self, v: float) -> bool:
        above = v > self.low if self.low_open else v >= self.low
        below = v < self.high if self.high_open else v <= self.high
        return math.isfinite(v) and above and below

    def text(self) -> str:
        return (f"{'(' if self.low_open else '['}{self.low:g}, {self.high:g}"
                f"{')' if self.high_open else ']'}")


# key -> (type, valid range or allowed strings, unit, what). Ranges bound what the model can
# mean physically or what the machine can hold, not what the study used: a run outside the
# study is allowed, a negative length or a 10^9-vertex rod is not.
_SPEC: dict[str, tuple[type, Any, str, str]] = {
    "knot": (str, ("closed", "open"), "", "closed or open trefoil"),
    "l0_over_d0": (float, _Range(10.0, 1e4), "", "closed: rest length over diameter L0/D0"),
    "length": (float, _Range(0.0, 100.0, low_open=True), "m", "open: rest length L0"),
    "force": (float, _Range(0.0, 1e6, low_open=True), "N", "open: final pulling force"),
    "end_distance": (float, _Range(0.0, 100.0, low_open=True), "m",
                     "open: final end-to-end distance"),
    "target_lambda": (float, _Range(0.0, 1e3, True, True), "",
                      "open: pull until Lambda_OC reaches this"),
    "nodes": (int, _Range(24, 200_000), "", "vertices of the rod"),
    "diameter": (float, _Range(0.0, 1.0, low_open=True), "m", "rest diameter D0"),
    "youngs_modulus": (float, _Range(0.0, 1e12, low_open=True), "Pa", "Young's modulus E"),
    "poisson": (float, _Range(-1.0, 0.5, low_open=True), "", "Poisson ratio nu"),
    "density": (float, _Range(0.0, 1e5, low_open=True), "kg/m^3", "mass density"),
    "tighten_steps": (int, _Range(1, 100_000), "", "initial load steps of the tightening"),
    "pull_steps": (int, _Range(1, 100_000), "", "initial load steps of the pull"),
    "residual_tol": (float, _Range(0.0, 1.0, True, True), "",
                     "Newton tolerance on the scaled residual"),
    "relax_iterations": (int, _Range(1, 1_000_000), "",
                         "Newton budget of the start curve's relaxation"),
    "contact": (str, ("compliant", "smoothed", "rigid"), "",
                "contact level (tightknot.knots.scenes: what each neglects)"),
    "color_by": (str, COLOR_FIELDS, "", "field colouring the rod tube in the .rrd"),
    "device": (str, None, "", "Warp device, e.g. cpu or cuda:0"),
}

#: Keys that may be null (absent = not used).
_OPTIONAL = {"length", "force", "end_distance", "target_lambda", "device"}

_OPEN_ONLY = ("length", "force", "end_distance", "target_lambda")
_LOADS = ("force", "end_distance", "target_lambda")


@dataclass(frozen=True)
class TieConfig:
    """Parameters of one tie run (SI units). See :data:`_SPEC` for each key's range.

    ``tighten_steps``, ``pull_steps`` and ``relax_iterations`` drive
    :func:`tightknot.loading.tie.tie` (closed knots; open knots pulled by ``force`` or to
    ``end_distance``); a ``target_lambda`` run uses
    :func:`tightknot.loading.pull.tie_to_lambda`'s own schedule and only ``residual_tol``.
    """

    knot: str
    l0_over_d0: float = 16.37
    length: float | None = None
    force: float | None = None
    end_distance: float | None = None
    target_lambda: float | None = None
    nodes: int | None = None
    diameter: float = 8.5e-3
    youngs_modulus: float = 1.25e6
    poisson: float = 0.5
    density: float = 1160.0
    tighten_steps: int = 40
    pull_steps: int = 10
    residual_tol: float = 1e-6
    relax_iterations: int = 2000
    contact: str = "compliant"
    color_by: str = "kappa_D0"
    device: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """The parameters as a JSON-ready dict (every key, nulls included)."""
        return asdict(self)

    @property
    def scene_name(self) -> str:
        """Name of the scene this config ties (``closed_trefoil`` or ``open_trefoil``)."""
        return f"{self.knot}_trefoil"

    def tie_options(self) -> dict[str, Any]:
        """Keyword options of :func:`tightknot.study.run.run_knot` for this config."""
        if self.target_lambda is not None:
            return {"target_lambda": self.target_lambda, "residual_tol": self.residual_tol}
        opts: dict[str, Any] = {"tighten_steps": self.tighten_steps,
                                "residual_tol": self.residual_tol,
                                "relax_iterations": self.relax_iterations}
        if self.knot == "open":
            opts.update(pull_steps=self.pull_steps, pull_force=self.force,
                        end_distance=self.end_distance)
        return opts


def _check_value(key: str, value: Any) -> Any:
    """Type and range of one value; returns it normalised (int -> float where a float is due)."""
    kind, valid, unit, what = _SPEC[key]
    u = f" {unit}" if unit else ""
    if value is None:
        if key in _OPTIONAL:
            return None
        raise ValueError(f"{key}: must not be null ({what})")
    if kind is float:
        # bool is an int in Python; true/false is never a number here.
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"{key}: expected a number{u} ({what}), got {value!r}")
        value = float(value)
    elif kind is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{key}: expected an integer ({what}), got {value!r}")
    elif not isinstance(value, str):
        raise ValueError(f"{key}: expected a string ({what}), got {value!r}")
    if key == "color_by":
        value = COLOR_ALIASES.get(value, value)
    if isinstance(valid, _Range) and not valid.contains(float(value)):
        raise ValueError(f"{key}: {value!r} is out of range; valid: {valid.text()}{u} ({what})")
    if isinstance(valid, tuple) and value not in valid:
        names = ", ".join(valid + tuple(k for k in COLOR_ALIASES if key == "color_by"))
        raise ValueError(f"{key}: {value!r} is not one of: {names} ({what})")
    return value


def config_from_dict(data: dict[str, Any]) -> TieConfig:
    """Validate a mapping of parameters and return the resolved :class:`TieConfig`.

    Raises ValueError naming the key: unknown key, wrong type, out of range, or options that
    do not fit together (open-knot loads on a closed knot; not exactly one load on an open one).
    """
    if not isinstance(data, dict):
        raise ValueError(f"a tie config is a mapping of keys to values, got {type(data).__name__}")
    unknown = sorted(set(data) - set(_SPEC))
    if unknown:
        raise ValueError(f"unknown key(s) {', '.join(map(repr, unknown))}; valid keys: "
                         f"{', '.join(_SPEC)}")
    if "knot" not in data:
        raise ValueError("knot: missing (closed or open)")
    clean = {k: _check_value(k, v) for k, v in data.items()}
    knot = clean["knot"]
    if knot == "closed":
        given = [k for k in _OPEN_ONLY if clean.get(k) is not None]
        if given:
            raise ValueError(f"{', '.join(given)}: for open knots only (knot is closed)")
    else:
        loads = [k for k in _LOADS if clean.get(k) is not None]
        if len(loads) != 1:
            raise ValueError("an open knot needs exactly one of force [N], end_distance [m] or "
                             f"target_lambda; got {', '.join(loads) or 'none'}")
        if clean.get("length") is None:
            clean["length"] = 0.185  # the study's loose knot
    if clean.get("nodes") is None:
        clean["nodes"] = DEFAULT_NODES[knot]
    return TieConfig(**clean)


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
    return tuple(f.name for f in fields(TieConfig))
