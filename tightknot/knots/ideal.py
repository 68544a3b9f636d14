"""The ideal (ropelength-minimising) knots shipped with the package (CC0, Ashton et al. 2011).

The polygons of Ashton, Cantarella, Piatek and Rawdon (Experimental Mathematics 20, 2011),
computed with ridgerunner, for the trefoil 3_1, the figure-eight 4_1, the torus knots
5_1 = T(2,5) and 8_19 = T(3,4) and the twist knot 6_1: :data:`IDEAL_KNOTS`. Each is the
upstream file byte for byte, checked against its upstream sha256 when read. See
``tightknot/knots/data/README.md`` for the source, licence and checksums.

Their L/D is measured on the shipped polygon: length over D = 2 r, r its polygonal
thickness min(MinRad, dcsd/2) (Rawdon; :func:`tightknot.knots.contact_map.
polygonal_thickness`), rounded to 4 decimals (tests/knots/test_ideal.py measures it again).
"""

from __future__ import annotations

import hashlib
import types
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources

import numpy as np
from numpy.typing import NDArray

from tightknot.knots.contact_map import polygonal_thickness

IDEAL_TREFOIL_FILE = "ideal_trefoil_ridgerunner_cc0_n2400.tsv"
IDEAL_CURVATURE_FILE = "ideal_trefoil_cc0_curvature_profile.csv"
#: sha256 of the tsv as published (refdata README).
IDEAL_TREFOIL_SHA256 = "e649e6d41a9d0a76bf6be1a93c6eed483ac3c949b6677f3f59520d0e958e8c3c"
#: Ropelength L/D of this polygon (KnotInfo 32.7436 / 2; Przybyl & Pieranski 2014: 16.3715).
IDEAL_TREFOIL_L_OVER_D = 16.3718


@dataclass(frozen=True)
class IdealKnot:
    """One shipped ideal knot: its table name, package data file, the upstream sha256 of
    that file and the L/D measured on it (module docstring)."""

    name: str
    file: str
    sha256: str
    l_over_d: float


#: The shipped ideal knots by table name (upstream: designbynumbers/ropelength-minimizing-
#: knots, knots/prime/3-10/<name>.tsv at commit 0d78454; sha256s from its manifest).
IDEAL_KNOTS: Mapping[str, IdealKnot] = types.MappingProxyType({k.name: k for k in (
    IdealKnot("3_1", IDEAL_TREFOIL_FILE, IDEAL_TREFOIL_SHA256, IDEAL_TREFOIL_L_OVER_D),
    IdealKnot("4_1", "ideal_4_1_ridgerunner_cc0.tsv",
              "099996e1d47c9879be3fe526bf22971e4127f603b6261cd34da036d77c9be7e4", 21.0483),
    IdealKnot("5_1", "ideal_5_1_ridgerunner_cc0.tsv",
              "d88ab5312607cdb6493ac4941211f7c90a70b2a49edd6a5e7bc65d40af6eea94", 23.6074),
    IdealKnot("6_1", "ideal_6_1_ridgerunner_cc0.tsv",
              "a09e80263d9fdf03c395d9a584cea165799d977aa20319baab7b2aeb9c1ae52d", 28.3589),
    IdealKnot("8_19", "ideal_8_19_ridgerunner_cc0.tsv",
              "764bc2fe9a6cb186dc7aaeaf01cd2ab78a0aeb87421e47e5cb0f578f42c1a88b", 30.4978),
)})


def _data_bytes(name: str) -> bytes:
    return resources.files("tightknot.knots").joinpath("data", name).read_bytes()


def ideal_trefoil_sha256() -> str:
    """sha256 hex digest of the shipped ideal trefoil tsv."""
    return hashlib.sha256(_data_bytes(IDEAL_TREFOIL_FILE)).hexdigest()


def load_ideal_trefoil(diameter: float = 1.0, verify: bool = True) -> NDArray[np.float64]:
    """Ideal trefoil (2400, 3), closed, scaled so its tube diameter D = 2 r equals ``diameter``.

    r is Rawdon's polygonal thickness min(MinRad, dcsd / 2) of the polygon (refdata README).
    Units follow ``diameter`` (metres for a physical rod). ``verify`` checks the sha256 first.
    """
    return load_ideal("3_1", diameter, verify)


def has_ideal(name: str) -> bool:
    """Whether the ideal shape of knot type ``name`` is shipped (:data:`IDEAL_KNOTS`)."""
    return name in IDEAL_KNOTS


def load_ideal(name: str, diameter: float = 1.0, verify: bool = True) -> NDArray[np.float64]:
    """The ideal knot ``name`` (:data:`IDEAL_KNOTS`) as a closed polygon (N, 3) scaled so its
    tube diameter D = 2 r (r: polygonal thickness) equals ``diameter`` (its unit: metres for
    a physical rod). ``verify`` checks the upstream sha256 first. ValueError naming the
    shipped knots for another name."""
    if name not in IDEAL_KNOTS:
        raise ValueError(f"no ideal shape of {name!r} is shipped; shipped: "
                         f"{', '.join(IDEAL_KNOTS)}")
    knot = IDEAL_KNOTS[name]
    raw = _data_bytes(knot.file)
    if verify and hashlib.sha256(raw).hexdigest() != knot.sha256:
        raise OSError(f"{knot.file}: checksum mismatch, the package data is damaged")
    pts = np.loadtxt(raw.decode().splitlines(), dtype=np.float64)
    r = polygonal_thickness(pts, closed=True)
    return pts * (diameter / (2.0 * r))


def load_ideal_curvature_profile() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Shipped profile of the ideal trefoil: (s/D, kappa*D) per vertex (Bergou curvature)."""
    text = _data_bytes(IDEAL_CURVATURE_FILE).decode()
    data = np.loadtxt(text.splitlines(), delimiter=",", comments="#")
    return data[:, 1], data[:, 2]
