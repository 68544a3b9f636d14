"""The settings of a contact layer: quadrature, exclusion window, hard limit, hard core.

One frozen record, checked once, that the layer's parts read and that two layers compare
(a batch of scenes shares one layer, so their settings must be equal).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

#: Gauss-Legendre points and weights on [0, 1].
GAUSS = {
    1: ([0.5], [1.0]),
    2: ([0.5 - 0.5 / math.sqrt(3.0), 0.5 + 0.5 / math.sqrt(3.0)], [0.5, 0.5]),
    3: ([0.5 - 0.5 * math.sqrt(0.6), 0.5, 0.5 + 0.5 * math.sqrt(0.6)],
        [5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0]),
}


#: The stretches that can thin the contact radius (ContactSettings.thinning).
THINNING = ("edge", "rod")


@dataclass(frozen=True)
class ContactSettings:
    """Settings of a :class:`tightknot.contact.layer.ContactLayer` (see its docstring for
    what each one does; here with the law-dependent defaults resolved).

    Attributes:
        gauss_points: quadrature points per edge (1 to 3).
        exclusion_factor: exclusion window over the rest diameter [-] (>= pi/2).
        hard_fraction: hard limit of the centerline distance over the pair's rest
            diameter [-], in (0, 0.5).
        core_fraction: start of the hard core's barrier over the contact radius R [-].
        core_stiffness: the barrier's stiffness over E/D [-].
        hard_relative: the barrier's divergence over R [-] (0: only the absolute floor).
        local_thickness: also guard pairs of one rod inside the exclusion window, down to
            half of it.
        radius_window: half-width [D0] of the window that averages the stretch thinning
            the contact radius (0: each edge's own stretch).
        thinning: the stretch that thins the contact radius: "edge" (each edge's own, or
            its window mean with ``radius_window``) or "rod" (the rod's mean stretch L/L0).
    """

    gauss_points: int = 2
    exclusion_factor: float = math.pi / 2
    hard_fraction: float = 0.05
    core_fraction: float = 0.7
    core_stiffness: float = 1.0
    hard_relative: float = 0.0
    local_thickness: bool = False
    radius_window: float = 0.0
    thinning: str = "edge"

    def __post_init__(self) -> None:
        if self.thinning not in THINNING:
            raise ValueError(f"thinning must be one of {', '.join(THINNING)}, got "
                             f"{self.thinning!r}")
        if self.thinning == "rod" and self.radius_window != 0.0:
            raise ValueError("thinning='rod' takes no radius_window (the rod's mean stretch "
                             f"thins every section), got radius_window={self.radius_window!r}")
        rw = self.radius_window
        if not (math.isfinite(rw) and 0.0 <= rw <= 10.0):
            raise ValueError(f"radius_window must be in [0, 10] (D0), got {rw!r}")
        if self.gauss_points not in GAUSS:
            raise ValueError(f"gauss_points must be 1, 2 or 3, got {self.gauss_points}")
        ef = self.exclusion_factor
        if not (math.isfinite(ef) and ef >= math.pi / 2):
            raise ValueError(f"exclusion_factor must be >= pi/2, got {ef}")
        if not (0.0 < self.hard_fraction < 0.5):
            raise ValueError(f"hard_fraction must be in (0, 0.5), got {self.hard_fraction}")
        if not (0.0 <= self.hard_relative < self.core_fraction <= 1.0):
            raise ValueError("need 0 <= hard_relative < core_fraction <= 1 (fractions of the "
                             f"contact radius R), got {self.hard_relative}, "
                             f"{self.core_fraction}")
        cs = self.core_stiffness
        if not (math.isfinite(cs) and cs > 0):
            raise ValueError(f"core_stiffness must be finite and > 0, got {cs}")

    @property
    def candidate_window(self) -> float:
        """Candidate window over the exclusion window [-]: 1 keeps non-local pairs only,
        0.5 also the pairs the local-thickness barrier guards."""
        return 0.5 if self.local_thickness else 1.0

    @property
    def gauss(self) -> tuple[list[float], list[float]]:
        """Gauss-Legendre points and weights on [0, 1]."""
        return GAUSS[self.gauss_points]

    def as_kwargs(self) -> dict:
        """The settings as keyword arguments of ``ContactLayer``."""
        return asdict(self)
