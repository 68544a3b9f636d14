"""The built-in knots: a start curve per knot type, its family, and its tight length.

Knots by their table name (:mod:`tightknot.knots.knot_table`): the study's trefoil and the
figure-eight (their own curves, :mod:`tightknot.knots.curves`), the torus knots
T(2, 5) = 5_1, T(2, 7) = 7_1 and T(3, 4) = 8_19, and the twist knots 5_2, 6_1, 7_2, 8_1
(:mod:`tightknot.knots.families`). Each is a closed curve; its open version (an overhand
knot of that type) is the curve cut at its outermost point with straight tails along a pull
axis, as the study's open trefoil is built (:func:`tightknot.knots.curves._open_from_closed`).

The tight length of a knot, L/D of its ideal (tightest rigid tube) shape, is that of the
shipped ideal polygon where there is one (:data:`IDEAL_L_OVER_D`), else an estimate:
L/D ~ k c^(3/4) with c the crossing number, the growth of the ropelength bound of Buck and
Simon (1999), and k the largest (L/D) / c^(3/4) of the knots whose ideal is known, so that
the estimate errs on the long (reachable) side for them all.
"""

from __future__ import annotations

import types
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tightknot.knots import curves, families
from tightknot.knots.ideal import IDEAL_KNOTS
from tightknot.knots.knot_table import crossings

#: L/D of the ideal closed knots: those measured on the shipped ideal polygons of Ashton,
#: Cantarella, Piatek, Rawdon 2011 (:data:`tightknot.knots.ideal.IDEAL_KNOTS`: 3_1, 4_1,
#: 5_1, 6_1, 8_19).
IDEAL_L_OVER_D: Mapping[str, float] = types.MappingProxyType(
    {k: v.l_over_d for k, v in IDEAL_KNOTS.items()})


@dataclass(frozen=True)
class BuiltinKnot:
    """A knot with a start curve: its table name, its family (words) and its closed curve
    ``curve(n)`` of n vertices (knot-size units, about one tube diameter)."""

    name: str
    family: str
    curve: Callable[[int], NDArray[np.float64]]

    @property
    def crossings(self) -> int:
        """Crossing number."""
        return crossings(self.name)


def _torus(p: int, q: int) -> Callable[[int], NDArray[np.float64]]:
    return lambda n: families.torus_knot(p, q, n)


def _twist(h: int) -> Callable[[int], NDArray[np.float64]]:
    return lambda n: families.twist_knot(h, n)


#: The built-in knots by name, by crossing number.
BUILTIN_KNOTS: Mapping[str, BuiltinKnot] = types.MappingProxyType({k.name: k for k in (
    BuiltinKnot("3_1", "trefoil, the study's knot", lambda n: curves.trefoil(n)),
    BuiltinKnot("4_1", "figure-eight knot", lambda n: curves.figure_eight(n)),
    BuiltinKnot("5_1", "torus knot T(2,5)", _torus(2, 5)),
    BuiltinKnot("5_2", "twist knot, 3 half-twists", _twist(3)),
    BuiltinKnot("6_1", "twist knot, 4 half-twists", _twist(4)),
    BuiltinKnot("7_1", "torus knot T(2,7)", _torus(2, 7)),
    BuiltinKnot("7_2", "twist knot, 5 half-twists", _twist(5)),
    BuiltinKnot("8_1", "twist knot, 6 half-twists", _twist(6)),
    BuiltinKnot("8_19", "torus knot T(3,4)", _torus(3, 4)),
)})

#: Names of the built-in knots, in table order.
KNOT_NAMES = tuple(BUILTIN_KNOTS)


def builtin(name: str) -> BuiltinKnot:
    """The built-in knot ``name``; ValueError listing the valid names otherwise."""
    if name not in BUILTIN_KNOTS:
        raise ValueError(f"knot {name!r} is not built in; valid: {', '.join(KNOT_NAMES)}")
    return BUILTIN_KNOTS[name]


def _estimate_factor() -> float:
    return max(v / crossings(k) ** 0.75 for k, v in IDEAL_L_OVER_D.items())


def ideal_l_over_d(name: str) -> tuple[float, bool]:
    """(L/D of the ideal knot ``name``, whether it is known rather than estimated from the
    crossing number; module docstring)."""
    if name in IDEAL_L_OVER_D:
        return IDEAL_L_OVER_D[name], True
    return _estimate_factor() * crossings(name) ** 0.75, False


def open_curve(name: str, n: int, size: float = 1.0, tail: float = 6.0
               ) -> NDArray[np.float64]:
    """The open (overhand) knot ``name`` with straight tails of ``tail * size`` along its
    pull axis, n vertices [knot-size units times ``size``]: the trefoil and figure-eight
    as the study's scenes build them, the others from their closed curve centred on the z
    axis and cut at its outermost point the same way."""
    if name == "3_1":
        return curves.open_trefoil(n, size, tail)
    if name == "4_1":
        return curves.open_figure_eight(n, size, tail)
    base = builtin(name).curve(2000)
    base = base - np.r_[base[:, :2].mean(axis=0), 0.0]
    return size * curves._open_from_closed(base, gap=0.03, offset=0.6, tail=tail, n=n)
