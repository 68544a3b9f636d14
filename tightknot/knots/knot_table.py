"""Knot names from the Alexander polynomial: the prime knots through 8 crossings.

Source of the polynomials: the Rolfsen knot table as given by KnotInfo (Livingston and
Moore, https://knotinfo.math.indiana.edu, column "Alexander polynomial") and the Knot Atlas
(http://katlas.org/wiki/The_Rolfsen_Knot_Table). Each entry is written as
:func:`tightknot.knots.topology.alexander_polynomial` normalises a polynomial: the
coefficients from t^0 up (the unit +-t^k removed) with a positive leading coefficient.

What a name from this table means. The Alexander polynomial is an invariant, not a
classification:

* it is blind to chirality (a knot and its mirror image share it), so ``3_1`` names both
  trefoils;
* composite knots share it with primes: Delta(K1 # K2) = Delta(K1) Delta(K2), and
  3_1#3_1 (granny and square knots) has the polynomial of 8_20, 3_1#4_1 that of 8_21;
* knots beyond 8 crossings may share it with a knot of the table (6_1 and 9_46; the unknot
  and every knot of polynomial 1, such as the Kinoshita-Terasaka knot).

So a name lists every knot of at most 8 crossings, prime or a connected sum of primes,
that has the polynomial, joined by ``|`` (primes first, by crossing number and index; a
sum written ``A#B``): ``"8_20|3_1#3_1"``. A polynomial of no such knot reads
``"unknown(det=D)"`` with D = |Delta(-1)|, the knot determinant.
"""

from __future__ import annotations

import itertools
import types
from collections.abc import Mapping, Sequence

#: Alexander polynomials of the unknot and the 35 prime knots through 8 crossings
#: (KnotInfo / Rolfsen table), coefficients of t^0, t^1, ... (module docstring).
PRIME_ALEXANDER: Mapping[str, tuple[int, ...]] = types.MappingProxyType({
    "0_1": (1,),
    "3_1": (1, -1, 1),
    "4_1": (1, -3, 1),
    "5_1": (1, -1, 1, -1, 1),
    "5_2": (2, -3, 2),
    "6_1": (2, -5, 2),
    "6_2": (1, -3, 3, -3, 1),
    "6_3": (1, -3, 5, -3, 1),
    "7_1": (1, -1, 1, -1, 1, -1, 1),
    "7_2": (3, -5, 3),
    "7_3": (2, -3, 3, -3, 2),
    "7_4": (4, -7, 4),
    "7_5": (2, -4, 5, -4, 2),
    "7_6": (1, -5, 7, -5, 1),
    "7_7": (1, -5, 9, -5, 1),
    "8_1": (3, -7, 3),
    "8_2": (1, -3, 3, -3, 3, -3, 1),
    "8_3": (4, -9, 4),
    "8_4": (2, -5, 5, -5, 2),
    "8_5": (1, -3, 4, -5, 4, -3, 1),
    "8_6": (2, -6, 7, -6, 2),
    "8_7": (1, -3, 5, -5, 5, -3, 1),
    "8_8": (2, -6, 9, -6, 2),
    "8_9": (1, -3, 5, -7, 5, -3, 1),
    "8_10": (1, -3, 6, -7, 6, -3, 1),
    "8_11": (2, -7, 9, -7, 2),
    "8_12": (1, -7, 13, -7, 1),
    "8_13": (2, -7, 11, -7, 2),
    "8_14": (2, -8, 11, -8, 2),
    "8_15": (3, -8, 11, -8, 3),
    "8_16": (1, -4, 8, -9, 8, -4, 1),
    "8_17": (1, -4, 8, -11, 8, -4, 1),
    "8_18": (1, -5, 10, -13, 10, -5, 1),
    "8_19": (1, -1, 0, 1, 0, -1, 1),
    "8_20": (1, -2, 3, -2, 1),
    "8_21": (1, -4, 5, -4, 1),
})

#: Largest crossing number of the knots the table names (a sum's is the sum of its
#: summands': additivity of the crossing number is proven for the sums of alternating
#: knots that occur here, all summands through 5 crossings being alternating).
MAX_CROSSINGS = 8


def crossings(name: str) -> int:
    """Crossing number of a table name ("5_2" -> 5, "3_1#4_1" -> 7, "0_1" -> 0)."""
    return sum(int(part.split("_")[0]) for part in name.split("#"))


def poly_mul(a: Sequence[int], b: Sequence[int]) -> tuple[int, ...]:
    """Product of two polynomials given as coefficients from t^0 up."""
    out = [0] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        for j, y in enumerate(b):
            out[i + j] += x * y
    return tuple(out)


def _composites() -> dict[str, tuple[int, ...]]:
    """Connected sums of nontrivial primes with at most MAX_CROSSINGS crossings in all,
    each with the product of its summands' polynomials (Delta is multiplicative)."""
    primes = [k for k in PRIME_ALEXANDER if k != "0_1"]
    out: dict[str, tuple[int, ...]] = {}
    for count in range(2, MAX_CROSSINGS // 3 + 1):
        for parts in itertools.combinations_with_replacement(primes, count):
            name = "#".join(parts)
            if crossings(name) > MAX_CROSSINGS:
                continue
            poly: tuple[int, ...] = (1,)
            for p in parts:
                poly = poly_mul(poly, PRIME_ALEXANDER[p])
            out[name] = poly
    return out


#: Every knot the table names, prime or composite, with its polynomial.
ALEXANDER_TABLE: Mapping[str, tuple[int, ...]] = types.MappingProxyType(
    {**PRIME_ALEXANDER, **_composites()})


def _by_polynomial() -> dict[tuple[int, ...], tuple[str, ...]]:
    groups: dict[tuple[int, ...], list[str]] = {}
    for name, poly in ALEXANDER_TABLE.items():
        groups.setdefault(poly, []).append(name)
    # Primes before sums, then by crossing number; the table's order within those.
    return {poly: tuple(sorted(names, key=lambda n: ("#" in n, crossings(n))))
            for poly, names in groups.items()}


_CANDIDATES = _by_polynomial()


def determinant(poly: Sequence[int]) -> int:
    """Knot determinant |Delta(-1)| of a polynomial given from t^0 up."""
    return abs(sum(c * (-1) ** k for k, c in enumerate(poly)))


def candidates(poly: Sequence[int]) -> tuple[str, ...]:
    """Every knot of the table with the Alexander polynomial ``poly`` (normalised as
    :func:`tightknot.knots.topology.alexander_polynomial` returns it); () when none."""
    return _CANDIDATES.get(tuple(int(c) for c in poly), ())


def knot_name(poly: Sequence[int]) -> str:
    """The name of the knot(s) of polynomial ``poly``: one name ("5_2"), the candidates
    joined by ``|`` where the polynomial does not separate them ("8_20|3_1#3_1"), or
    "unknown(det=D)" (module docstring)."""
    names = candidates(poly)
    if names:
        return "|".join(names)
    return f"unknown(det={determinant(poly)})"
