"""The ideal (tightest) trefoil shipped with the package (CC0, Ashton et al. 2011).

See ``tightknot/knots/data/README.md`` for the source, licence and checksum.
"""

from __future__ import annotations

import hashlib
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
    raw = _data_bytes(IDEAL_TREFOIL_FILE)
    if verify and hashlib.sha256(raw).hexdigest() != IDEAL_TREFOIL_SHA256:
        raise OSError(f"{IDEAL_TREFOIL_FILE}: checksum mismatch, the package data is damaged")
    pts = np.loadtxt(raw.decode().splitlines(), dtype=np.float64)
    r = polygonal_thickness(pts, closed=True)
    return pts * (diameter / (2.0 * r))


def load_ideal_curvature_profile() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Shipped profile of the ideal trefoil: (s/D, kappa*D) per vertex (Bergou curvature)."""
    text = _data_bytes(IDEAL_CURVATURE_FILE).decode()
    data = np.loadtxt(text.splitlines(), delimiter=",", comments="#")
    return data[:, 1], data[:, 2]
