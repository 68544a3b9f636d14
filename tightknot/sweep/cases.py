"""What a sweep case is: a JSON dict of scene and load parameters with a stable id.

A case is canonical: every parameter the run depends on is present (defaults filled in),
floats are floats, whole numbers are ints, and the tightness levels of an open knot are
sorted from the loosest to the tightest (the order the continuation path visits them). Its id
is a hash of that canonical dict, so the same physics always gets the same id, whatever the
order or spelling in which it was asked for; the store uses the id to skip finished cases.

Parameters (SI units): those of :class:`tightknot.study.params.Scene` (knot, knot_type,
nodes, diameter, youngs_modulus, poisson, density, contact, twist; closed: l0_over_d0;
open: length) and some of :class:`tightknot.loading.options.LoadPath` (residual_tol,
tighten_steps; open: lambda_tolerance), with the defaults and ranges declared there (per
knot: :data:`tightknot.study.params.KNOT_DEFAULTS`); :data:`CASE_KEYS` lists them. An open
knot has exactly one level list, each level checked as the load it is (:data:`LEVELS`):
``pull_force`` [N] or ``target_lambda`` (Lambda_OC, physics.md sec. 2), each with at least
one value. A ``contact="smoothed"`` or ``"sectioned"`` case is tied one by one under
``--batch``.
"""

from __future__ import annotations

import hashlib
import itertools
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from tightknot.study.params import RUN_PARAMS, check_scene, knot_defaults, resolve_nodes

#: Prefix of the hashed text: bump it when the meaning of a parameter changes, so that a
#: store written by an older version is not taken for finished work.
_ID_SCHEMA = "tightknot-sweep-case-v2"

#: The parameters of a case besides its knot and levels, in the order its dict lists them.
#: The canonical dict holds exactly these: one more would change every case's id.
CASE_KEYS: dict[str, tuple[str, ...]] = {
    "closed": ("diameter", "youngs_modulus", "poisson", "density", "contact", "section_modes",
               "residual_tol", "tighten_steps", "knot_type", "nodes", "twist", "l0_over_d0"),
    "open": ("diameter", "youngs_modulus", "poisson", "density", "contact", "section_modes",
             "residual_tol", "tighten_steps", "knot_type", "nodes", "twist", "length",
             "lambda_tolerance", "grip_length", "grip_twist"),
}
#: Run parameters that are not case parameters, and why: a sweep's path pulls level by
#: level with its own steps, ties with tie()'s relaxation, has no end-distance levels
#: (its force levels are ``pull_force``), ties a long rod by mesh continuation from the
#: coarse count that its vertex count implies (``default_coarse_nodes``), and writes no
#: pictures; the device is the sweep's, not the case's; it sweeps the built-in knots from
#: their parametric starts, not a user's start curve or an ideal start (``tie --start``,
#: ``--start-shape``); a sectioned case runs tie()'s default path (``section_path``
#: "auto"), as the open knots' sweep path pulls with the sections; the sections' bend shift
#: is an opt-in the FEM does not back (docs/sectioned_level.md), so sweeps run without it.
NOT_CASE_KEYS = ("pull_steps", "relax_iterations", "end_distance", "force", "target_lambda",
                 "coarse_nodes", "color_by", "device", "start", "units", "columns",
                 "start_shape", "section_path", "section_bend_shift",
                 "section_thinning")
#: Level lists of an open knot -> the load each level is (its range and unit).
LEVELS = {"pull_force": "force", "target_lambda": "target_lambda"}
LEVEL_KEYS = tuple(LEVELS)


def defaults(knot: str, knot_type: str = "3_1") -> dict[str, Any]:
    """Every parameter's default for a ``knot`` ("closed"/"open") of ``knot_type``."""
    per_knot = {"knot_type": knot_type, **knot_defaults(knot, knot_type)}
    out = {k: per_knot[k] if k in per_knot else RUN_PARAMS[k].default for k in CASE_KEYS[knot]}
    out["nodes"] = resolve_nodes({"knot": knot, **out})
    return out


def _value(key: str, value: Any) -> Any:
    """A case parameter checked (:meth:`tightknot.loading.options.Param.check`); a whole
    number spelled as a float is the same case as the int."""
    p = RUN_PARAMS[key]
    if value is None:
        raise ValueError(f"{key}: must not be null ({p.meaning})")
    if p.kind is int and isinstance(value, float) and value.is_integer():
        value = int(value)
    return p.check(value)


def _levels(name: str, value: Any) -> list[float]:
    p = RUN_PARAMS[LEVELS[name]]
    if isinstance(value, int | float) and not isinstance(value, bool):
        value = [value]
    if isinstance(value, str | bytes) or not isinstance(value, Sequence) or len(value) == 0:
        u = f" {p.unit}" if p.unit else ""
        raise ValueError(f"{name} must be a non-empty list of numbers in {p.valid.text()}{u}, "
                         f"got {value!r}")
    out = []
    for i, v in enumerate(value):
        if v is None:
            raise ValueError(f"{name}[{i}]: must not be null ({p.meaning})")
        out.append(p.check(v, f"{name}[{i}]"))
    if len(set(out)) != len(out):
        raise ValueError(f"{name} lists a level twice: {out}")
    return out


def canonical(params: Mapping[str, Any]) -> dict[str, Any]:
    """The canonical form of a case's parameters (module docstring), checked.

    Raises ValueError naming the parameter and its valid range.
    """
    p = dict(params)
    if "knot" not in p:
        raise ValueError("knot: missing (closed or open)")
    knot = _value("knot", p.pop("knot"))
    allowed = set(CASE_KEYS[knot])
    if knot == "open":
        allowed |= set(LEVELS)
    unknown = sorted(set(p) - allowed)
    if unknown:
        raise ValueError(f"unknown parameter(s) {unknown} for a {knot} knot; valid: "
                         f"{sorted(allowed)}")
    knot_type = _value("knot_type", p.get("knot_type", RUN_PARAMS["knot_type"].default))
    out: dict[str, Any] = {"knot": knot}
    for key, default in defaults(knot, knot_type).items():
        if key == "nodes" and p.get(key) is None:
            continue  # from the rest length, once that is known
        out[key] = _value(key, p.get(key, default))
    if "nodes" not in out:
        # The key keeps its place in the canonical dict's order.
        resolved = _value("nodes", resolve_nodes(out))
        out = {k: (resolved if k == "nodes" else out[k]) for k in ["knot", *CASE_KEYS[knot]]
               if k in out or k == "nodes"}
    check_scene(out)
    if knot == "closed":
        return out
    given = [k for k in LEVELS if p.get(k) is not None]
    if len(given) != 1:
        raise ValueError("an open knot needs exactly one level list: pull_force [N] or "
                         f"target_lambda (Lambda_OC), got {given or 'none'}")
    key = given[0]
    levels = _levels(key, p[key])
    # Loosest first: the weakest pull, the longest knot.
    out[key] = sorted(levels) if key == "pull_force" else sorted(levels, reverse=True)
    return out


def case_id(params: Mapping[str, Any]) -> str:
    """Stable id of a case: 16 hex digits of the SHA-256 of its canonical JSON."""
    text = json.dumps(canonical(params), sort_keys=True, separators=(",", ":"),
                      allow_nan=False)
    return hashlib.sha256(f"{_ID_SCHEMA}\n{text}".encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Case:
    """One case of a sweep: canonical parameters and their id."""

    id: str
    params: dict[str, Any]

    @classmethod
    def of(cls, params: Mapping[str, Any]) -> Case:
        """The case of ``params`` (canonicalised and checked)."""
        p = canonical(params)
        return cls(case_id(p), p)

    @property
    def levels(self) -> list[float]:
        """The tightness levels of an open knot (loosest first), else []."""
        for key in LEVEL_KEYS:
            if key in self.params:
                return list(self.params[key])
        return []

    def label(self) -> str:
        """Human label naming every parameter that defines the case, defaults included
        (a label that leaves them out reads the same for two different rods): the knot,
        then ``key=value`` in the canonical order, a level list in full."""
        parts = [self.params["knot"]]
        for k, v in self.params.items():
            if k == "knot":
                continue
            if isinstance(v, list):
                parts.append(f"{k}=[{', '.join(f'{x:g}' for x in v)}]")
            else:
                parts.append(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}")
        return " ".join(parts)


def grid(base: Mapping[str, Any], **axes: Sequence[Any]) -> list[Case]:
    """Cases of the Cartesian product of ``axes`` over ``base``, in product order.

    ``base`` holds the fixed parameters (including an open knot's level list, which stays
    one continuation path); each axis is a parameter name with the list of its values.
    Duplicates (the same canonical case twice) are kept once. Example::

        grid({"knot": "closed", "nodes": 100}, l0_over_d0=[16.37, 18, 20])
    """
    for name, values in axes.items():
        if isinstance(values, str | bytes) or not isinstance(values, Sequence) or not values:
            raise ValueError(f"sweep axis {name} must be a non-empty list, got {values!r}")
        if name in base:
            raise ValueError(f"{name} is given both as a fixed parameter and as a sweep axis")
    names = list(axes)
    cases: list[Case] = []
    seen: set[str] = set()
    for combo in itertools.product(*(axes[n] for n in names)):
        case = Case.of({**base, **dict(zip(names, combo, strict=True))})
        if case.id not in seen:
            seen.add(case.id)
            cases.append(case)
    return cases
