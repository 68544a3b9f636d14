"""What a sweep case is: a JSON dict of scene and load parameters with a stable id.

A case is canonical: every parameter the run depends on is present (defaults filled in),
floats are floats, whole numbers are ints, and the tightness levels of an open knot are
sorted from the loosest to the tightest (the order the continuation path visits them). Its id
is a hash of that canonical dict, so the same physics always gets the same id, whatever the
order or spelling in which it was asked for; the store uses the id to skip finished cases.

Parameters (SI units):

* ``knot``: "closed" (the study's closed trefoil) or "open" (overhand knot, pulled).
* ``knot_type``: "3_1" (trefoil, the study's) or "4_1" (figure-eight; its scenes'
  default lengths: L0/D0 = 22.1 closed, L0 = 0.30 m open).
* ``nodes``: vertices (>= 24 closed, >= 40 open; default 200 closed, 300 open).
* ``diameter`` D0 [m] (8.5e-3), ``youngs_modulus`` E [Pa] (1.25e6), ``poisson`` nu
  (0.5, in (-1, 0.5]), ``density`` [kg/m^3] (1160; only the proximal fallback uses it).
* ``contact``: "compliant" (the FEM-calibrated radial-compliance law), "smoothed" (the
  same law, the section thinned by the stretch averaged over +-1 D0; a sweep with
  ``--batch`` ties these cases one by one)
  or "rigid" (the rigid-tube law, 1e3 times stiffer, radius not thinned by stretch).
* ``twist``: twist dofs on or off (default on for closed, off for open knots: an isotropic
  rod with twist-free ends relaxes its twist to zero).
* closed: ``l0_over_d0`` L0/D0 (16.37, >= 10).
* open: ``length`` L0 [m] (0.185, >= 10 D0) and exactly one level list:
  ``pull_force`` [N] or ``target_lambda`` (Lambda_OC, physics.md sec. 2), each with at
  least one value; ``lambda_tolerance`` (0.1) is how close a target is reached.
* ``residual_tol`` (1e-6): Newton tolerance on the scaled residual; ``tighten_steps`` (40).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

#: Prefix of the hashed text: bump it when the meaning of a parameter changes, so that a
#: store written by an older version is not taken for finished work.
_ID_SCHEMA = "tightknot-sweep-case-v1"

KNOTS = ("closed", "open")
CONTACT_LAWS = ("compliant", "smoothed", "rigid")
LEVEL_KEYS = ("pull_force", "target_lambda")

_COMMON_DEFAULTS: dict[str, Any] = {
    "diameter": 8.5e-3,
    "youngs_modulus": 1.25e6,
    "poisson": 0.5,
    "density": 1160.0,
    "contact": "compliant",
    "residual_tol": 1e-6,
    "tighten_steps": 40,
}
_DEFAULTS: dict[str, dict[str, Any]] = {
    "closed": {"knot_type": "3_1", "nodes": 200, "twist": True, "l0_over_d0": None},
    "open": {"knot_type": "3_1", "nodes": 300, "twist": False, "length": None,
             "lambda_tolerance": 0.1},
}
#: Knot types with a scene (tightknot.knots.scenes), and the default length of each: the
#: study's trefoils (L0/D0 = 16.37; L0 = 185 mm), the figure-eight scenes' own defaults.
KNOT_TYPES = ("3_1", "4_1")
_LENGTH_DEFAULTS = {("closed", "3_1"): 16.37, ("closed", "4_1"): 22.1,
                    ("open", "3_1"): 0.185, ("open", "4_1"): 0.30}
_LENGTH_KEY = {"closed": "l0_over_d0", "open": "length"}


def defaults(knot: str, knot_type: str = "3_1") -> dict[str, Any]:
    """Every parameter's default for a ``knot`` ("closed"/"open") of ``knot_type``."""
    out = {**_COMMON_DEFAULTS, **_DEFAULTS[knot]}
    out["knot_type"] = knot_type
    out[_LENGTH_KEY[knot]] = _LENGTH_DEFAULTS[(knot, knot_type)]
    return out
_MIN_NODES = {"closed": 24, "open": 40}


def _number(name: str, value: Any, valid: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{name} must be a number {valid}, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite number {valid}, got {value!r}")
    return v


def _positive(name: str, value: Any, unit: str) -> float:
    v = _number(name, value, f"> 0 {unit}".rstrip())
    if v <= 0:
        raise ValueError(f"{name} must be > 0 {unit}".rstrip() + f", got {value!r}")
    return v


def _levels(name: str, value: Any, unit: str) -> list[float]:
    if isinstance(value, int | float) and not isinstance(value, bool):
        value = [value]
    if isinstance(value, str | bytes) or not isinstance(value, Sequence) or len(value) == 0:
        raise ValueError(f"{name} must be a non-empty list of numbers > 0 {unit}".rstrip()
                         + f", got {value!r}")
    out = [_positive(f"{name}[{i}]", v, unit) for i, v in enumerate(value)]
    if len(set(out)) != len(out):
        raise ValueError(f"{name} lists a level twice: {out}")
    return out


def canonical(params: Mapping[str, Any]) -> dict[str, Any]:
    """The canonical form of a case's parameters (module docstring), checked.

    Raises ValueError naming the parameter and its valid range.
    """
    p = dict(params)
    knot = p.pop("knot", None)
    if knot not in KNOTS:
        raise ValueError(f"knot must be one of {KNOTS}, got {knot!r}")
    allowed = set(_COMMON_DEFAULTS) | set(_DEFAULTS[knot])
    if knot == "open":
        allowed |= set(LEVEL_KEYS)
    unknown = sorted(set(p) - allowed)
    if unknown:
        raise ValueError(f"unknown parameter(s) {unknown} for a {knot} knot; valid: "
                         f"{sorted(allowed)}")
    knot_type = p.get("knot_type", "3_1")
    if knot_type not in KNOT_TYPES:
        raise ValueError(f"knot_type must be one of {KNOT_TYPES}, got {knot_type!r}")
    out: dict[str, Any] = {"knot": knot}
    for key, default in defaults(knot, knot_type).items():
        out[key] = p.get(key, default)
    nodes = out["nodes"]
    if isinstance(nodes, bool) or not isinstance(nodes, int | float) or nodes != int(nodes) \
            or nodes < _MIN_NODES[knot]:
        raise ValueError(f"nodes must be a whole number >= {_MIN_NODES[knot]} for a {knot} "
                         f"knot, got {nodes!r}")
    out["nodes"] = int(nodes)
    out["diameter"] = _positive("diameter", out["diameter"], "m")
    out["youngs_modulus"] = _positive("youngs_modulus", out["youngs_modulus"], "Pa")
    nu = _number("poisson", out["poisson"], "in (-1, 0.5]")
    if not -1.0 < nu <= 0.5:
        raise ValueError(f"poisson must be in (-1, 0.5], got {out['poisson']!r}")
    out["poisson"] = nu
    rho = _number("density", out["density"], ">= 0 kg/m^3")
    if rho < 0:
        raise ValueError(f"density must be >= 0 kg/m^3, got {out['density']!r}")
    out["density"] = rho
    if out["contact"] not in CONTACT_LAWS:
        raise ValueError(f"contact must be one of {CONTACT_LAWS}, got {out['contact']!r}")
    if not isinstance(out["twist"], bool):
        raise ValueError(f"twist must be true or false, got {out['twist']!r}")
    tol = _positive("residual_tol", out["residual_tol"], "")
    if tol >= 1e-2:
        raise ValueError(f"residual_tol must be in (0, 1e-2), got {out['residual_tol']!r}")
    out["residual_tol"] = tol
    steps = out["tighten_steps"]
    if isinstance(steps, bool) or not isinstance(steps, int) or not 1 <= steps <= 10000:
        raise ValueError(f"tighten_steps must be a whole number in [1, 10000], got {steps!r}")
    if knot == "closed":
        ratio = _positive("l0_over_d0", out["l0_over_d0"], "")
        if ratio < 10.0:
            raise ValueError(f"l0_over_d0 must be >= 10 (a trefoil needs 16.37 when ideal), "
                             f"got {out['l0_over_d0']!r}")
        out["l0_over_d0"] = ratio
        return out
    out["length"] = _positive("length", out["length"], "m")
    if out["length"] < 10.0 * out["diameter"]:
        raise ValueError(f"length must be >= 10 D0 = {10 * out['diameter']:.4g} m for an open "
                         f"trefoil, got {out['length']!r}")
    lt = _positive("lambda_tolerance", out["lambda_tolerance"], "")
    out["lambda_tolerance"] = lt
    given = [k for k in LEVEL_KEYS if p.get(k) is not None]
    if len(given) != 1:
        raise ValueError("an open knot needs exactly one level list: pull_force [N] or "
                         f"target_lambda (Lambda_OC), got {given or 'none'}")
    key = given[0]
    if key == "pull_force":
        out[key] = sorted(_levels(key, p[key], "N"))  # loosest (weakest pull) first
    else:
        lams = _levels(key, p[key], "")
        if max(lams) >= 1e3:
            raise ValueError(f"target_lambda must be < 1000, got {max(lams)!r}")
        out[key] = sorted(lams, reverse=True)  # loosest (longest knot) first
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
        """Short human label: the knot and the parameters that differ from the defaults."""
        base = defaults(self.params["knot"], self.params["knot_type"])
        parts = [self.params["knot"]]
        if self.params["knot_type"] != "3_1":
            parts.append(self.params["knot_type"])
        for k, v in self.params.items():
            if k in ("knot", "knot_type") or (k in base and base[k] == v):
                continue
            if isinstance(v, list):
                parts.append(f"{k}={len(v)} levels")
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
