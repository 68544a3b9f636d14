"""Self-contact of rods with a radial-compliance layer: the term the Newton solver adds.

The layer is made of four parts, each in its own module:

* :mod:`tightknot.contact.broad_phase`: which edge pairs can touch (a BVH over the edges'
  bounds, a growing candidate buffer, the rest-arc tables of the exclusion window);
* :mod:`tightknot.contact.energy`: the energy, gradient and Hessian of the candidates (the
  pair kernel, :mod:`tightknot.contact.pair_kernel`, and the law,
  :mod:`tightknot.contact.law`);
* :mod:`tightknot.contact.step_bound`: no passing through, every Newton step bounded so
  that no two non-local segments come closer than the hard limit (``hard_fraction`` x D)
  anywhere along the step;
* :mod:`tightknot.contact.checks`: refusing a state that already intersects itself, and
  the smallest non-local distance.

Pairs closer along the rod than the exclusion window are skipped; the window is ``pi D/2``
of rest arc length: on the tightest bend a tube allows (radius D/2) two points an arc s
apart are a chord ``D sin(s/D)`` apart, below D (touching) for every s < pi D/2, so a
shorter window would make a tight but legal bend touch itself (with a C2 ramp over the next
quarter window).
"""

from __future__ import annotations

import math

import numpy as np
import warp as wp

from tightknot.contact.broad_phase import MAX_CANDIDATES, BroadPhase, ContactCapacityError
from tightknot.contact.checks import ContactChecks, SelfIntersectionError
from tightknot.contact.energy import ContactEnergy, pair_blocks
from tightknot.contact.law import RadialComplianceLaw
from tightknot.contact.pair_kernel import PairKernel
from tightknot.contact.pair_law import pair_law
from tightknot.contact.rod_mean_radius import RodMeanRadius
from tightknot.contact.section_radius import SmoothedRadius
from tightknot.contact.settings import ContactSettings
from tightknot.contact.step_bound import StepBound
from tightknot.rods.model import Model
from tightknot.rods.term import EnergyTerm
from tightknot.warp_setup import init_warp

__all__ = ["MAX_CANDIDATES", "ContactCapacityError", "ContactLayer", "ContactSettings",
           "SelfIntersectionError", "pair_blocks"]


class ContactLayer(EnergyTerm):
    """Self-contact (and rod-rod contact) of a model's rods, compliant or rigid-tube.

    Args:
        model: the rods.
        law: the radial-compliance law (default: the shipped FEM calibration).
        gauss_points: quadrature points per edge (1 to 3).
        exclusion_factor: exclusion window over the rest diameter (default pi/2, derived
            in the module docstring).
        hard_fraction: hard limit of the centerline distance over the pair's rest diameter;
            a Newton step never brings two non-local segments closer.
        core_fraction: the hard core: an IPC barrier (Li et al. 2020, eq. 6), zero and C2
            at centerline distances above core_fraction R (R = r_a + r_b, the contact radius
            of the stretched sections), diverging at rho_h = max(hard_relative R,
            hard_fraction D + 0.58 l) (l the longer rest edge: every polyline point is
            within 0.29 l of a Gauss point, so the barrier stops two segments before the
            step bound would). Default: the law's calibrated core (an incompressible section
            stiffens steeply in deep squeezes, which the power laws alone miss:
            :func:`tightknot.fem.calibration.calibrate_core`), else 0.7 for a compliant law
            (the end of the power laws' calibrated range) and 1.0 for a rigid tube.
        core_stiffness: the barrier's stiffness over E/D (energy per length^2 over the
            square of the distance into the band); default the law's core, else 1.
        hard_relative: see core_fraction; default the law's core, else 0 (compliant: only
            the absolute floor) or 0.98 for a rigid tube (its hard radius).
        local_thickness: also guard pairs of one rod inside the exclusion window, down to
            half of it: two points an arc s apart on the tightest legal bend (radius D/2)
            are D sin(s/D) apart, and the barrier acts below core_fraction of that (with R
            for D), so the rod cannot fold onto itself where the law is off. Off by
            default: it changes the load path of marginal knots and adds candidates
            (docs/design_notes.md, contact).
        initial_capacity: first size of the candidate-pair buffer (grows on demand).
        radius_window: half-width [D0] of the window along the rod over which the stretch
            that thins the contact radius is averaged (:mod:`tightknot.contact.section_radius`);
            0 (default): each edge's own stretch. At 1 D0 the FEM cross-check's indent force
            is within -8 to +7 % of the fine-mesh FEM (-15 to +4 % with 0) and the axial
            force at the deepest crossing 1.07 times the FEM's (3.4 times with 0), and the study's
            knots tie in about as many Newton iterations; each iteration costs more (the
            Hessian couples whole windows; docs/fem_crosscheck.md). Not with a rigid-tube
            law (its radius does not thin), not in the batch (:mod:`tightknot.loading.batch`).
        thinning: "edge" (default): each edge's own stretch thins its section (or the
            window mean, ``radius_window``); "rod": every section of a rod thins with the
            rod's mean stretch L/L0 (:mod:`tightknot.contact.rod_mean_radius`: the contact
            then pulls no edge apart; the default level of the scenes).
    """

    name = "contact"
    assembles_in_place = True
    keeps_apart = True
    #: The broad phase's class (the batch's keeps the candidates of chosen rods only).
    broad_phase_class: type[BroadPhase] = BroadPhase

    def __init__(
        self,
        model: Model,
        law: RadialComplianceLaw | None = None,
        gauss_points: int = 2,
        exclusion_factor: float = math.pi / 2,
        hard_fraction: float = 0.05,
        core_fraction: float | None = None,
        core_stiffness: float | None = None,
        hard_relative: float | None = None,
        local_thickness: bool = False,
        initial_capacity: int = 1024,
        radius_window: float = 0.0,
        thinning: str = "edge",
    ) -> None:
        init_warp()
        self.law = law or RadialComplianceLaw.from_json()
        rigid = self.law.rigid
        # The hard core: the law's calibrated one, else a rigid tube's hard radius (0.98 R)
        # or, for a compliant law without one, a barrier from 0.7 R (the end of the power
        # laws' calibrated range) down to the absolute floor.
        if core_fraction is None:
            core_fraction = (self.law.core_fraction if self.law.core_fraction is not None
                             else 1.0 if rigid else 0.7)
        if hard_relative is None:
            hard_relative = (self.law.core_hard_relative
                             if self.law.core_hard_relative is not None
                             else 0.98 if rigid else 0.0)
        if core_stiffness is None:
            core_stiffness = (self.law.core_stiffness if self.law.core_stiffness is not None
                              else 1.0)
        #: The layer's settings (checked; the batch compares them).
        self.settings = ContactSettings(
            gauss_points=gauss_points, exclusion_factor=exclusion_factor,
            hard_fraction=float(hard_fraction), core_fraction=float(core_fraction),
            core_stiffness=float(core_stiffness), hard_relative=float(hard_relative),
            local_thickness=bool(local_thickness), radius_window=float(radius_window),
            thinning=thinning)
        st = self.settings
        if (st.radius_window > 0.0 or st.thinning == "rod") and rigid:
            raise ValueError(f"{'radius_window' if st.radius_window > 0.0 else 'thinning=rod'} "
                             "needs a compliant law: a rigid tube's radius does not thin "
                             "with stretch")
        m = model
        self.model = model
        self.device = model.device
        #: Rest diameter of each edge [m].
        self.edge_diameter = 2.0 * m.edge_radius
        # A rigid tube has a hard radius: its contact radius does not thin with stretch.
        nu = np.array([0.0 if rigid else m.rods[r].material.poisson_ratio for r in m.edge_rod])
        #: Exponent of each edge's section thinning with stretch, r0 lam^-nu (0: rigid).
        self.edge_poisson = nu
        #: Young's modulus of each edge [Pa].
        self.edge_modulus = np.array([m.rods[r].material.youngs_modulus for r in m.edge_rod])
        #: Exclusion window of each edge [m].
        self.exclusion = st.exclusion_factor * self.edge_diameter
        smooth = (SmoothedRadius(m, st.radius_window, nu) if st.radius_window > 0.0
                  else None)
        self.broad_phase = self.broad_phase_class(m, self.exclusion, st.candidate_window,
                                                  initial_capacity)
        kernel = PairKernel(self.broad_phase, pair_law(self.law, st, self.device), st.gauss,
                            m.edge_radius, nu, self.edge_modulus)
        mean = RodMeanRadius(m, nu) if st.thinning == "rod" else None
        self.energy = ContactEnergy(m, self.broad_phase, kernel, smooth, mean)
        self.step_bound = StepBound(self.broad_phase, st.hard_fraction * self.edge_diameter,
                                    self.edge_diameter)
        self.checks = ContactChecks(self.broad_phase, self.step_bound, st.hard_fraction)

    # -- settings --------------------------------------------------------------------------
    @property
    def hard_fraction(self) -> float:
        """Hard limit over the pair's rest diameter [-]."""
        return self.settings.hard_fraction

    @property
    def core_fraction(self) -> float:
        """Start of the hard core over the contact radius [-]."""
        return self.settings.core_fraction

    @property
    def hard_relative(self) -> float:
        """Divergence of the hard core over the contact radius [-]."""
        return self.settings.hard_relative

    @property
    def radius_window(self) -> float:
        """Half-width of the smoothed radius's window [D0] (0: none)."""
        return self.settings.radius_window

    @property
    def thinning(self) -> str:
        """The stretch that thins the contact radius: "edge" or "rod" (the rod's mean)."""
        return self.settings.thinning

    @property
    def section_radius(self) -> SmoothedRadius | None:
        """The smoothed contact radius (None without a radius window)."""
        return self.energy.smooth

    # -- the last evaluation ---------------------------------------------------------------
    @property
    def last_pairs(self) -> np.ndarray:
        """Candidate edge pairs (P, 2) of the last evaluation."""
        return self.energy.last_pairs

    @property
    def last_overlap(self) -> np.ndarray:
        """Their largest overlaps R - rho [m] (P,) (positive: in contact)."""
        return self.energy.last_overlap

    @property
    def last_rest(self) -> np.ndarray:
        """Edge rest lengths [m] of the last evaluation (the model's before any)."""
        return self.energy.last_rest

    # -- the energy term -------------------------------------------------------------------
    def evaluate(
        self, x: np.ndarray, rest: np.ndarray, want_grad: bool = True, want_hess: bool = True
    ) -> tuple[float, np.ndarray | None, tuple[np.ndarray, np.ndarray, np.ndarray] | None]:
        """Contact energy [J], gradient over vertex positions (N, 3) [N], Hessian COO
        triplets over global dofs (:meth:`ContactEnergy.evaluate`)."""
        return self.energy.evaluate(x, rest, want_grad, want_hess)

    def evaluate_into(self, x: np.ndarray, rest: np.ndarray, tables: tuple[wp.array, ...],
                      data: wp.array) -> tuple:
        """Energy [J] and gradient, the Hessian added into the CSC ``data``
        (:meth:`ContactEnergy.evaluate_into`)."""
        return self.energy.evaluate_into(x, rest, tables, data)

    def missing_blocks(self) -> np.ndarray:
        """Vertex-block keys the last :meth:`evaluate_into` found missing."""
        return self.energy.missing_blocks()

    def active_blocks(self) -> np.ndarray:
        """Vertex-block keys of the pairs that interacted at the last evaluation."""
        return self.energy.active_blocks()

    def max_step(self, x: np.ndarray, dx: np.ndarray, rest: np.ndarray) -> float:
        """Largest fraction of the step ``dx`` [m] that keeps every non-local segment pair at
        least the hard limit apart along the straight path (1 = full), at edge rest lengths
        ``rest`` [m] (:meth:`StepBound.max_step`)."""
        return self.step_bound.max_step(x, dx, rest)

    def check_state(self, x: np.ndarray) -> None:
        """:meth:`check_no_intersection` (the system's check of a start)."""
        self.check_no_intersection(x)

    def window_scale(self, lengths: np.ndarray, rest: np.ndarray,
                     edges: slice = slice(None)) -> np.ndarray:
        """The scale of the rest arcs that makes the exclusion window follow the deformed
        rod, for edges ``edges`` of current lengths ``lengths`` [m] and rest lengths
        ``rest`` [m]: lam^(1 + nu) of a stretched edge (lam = length / rest), 1 otherwise.

        The window (pi D / 2 of arc: on the tightest bend a tube allows, two points closer
        along it than that are closer than D, module docstring of the broad phase) holds
        for the deformed rod: its arc grows as lam and its diameter thins as lam^-nu, so in
        rest arcs and rest diameters the window shrinks by lam^(1 + nu). A pair that a
        stretched, thinned knot brings into contact is then no longer taken for a
        neighbour. Compressed edges keep the rest window (it never widens). With
        ``thinning="rod"`` the diameter thins with the rod's mean stretch s instead:
        max(lam, 1) max(s, 1)^nu."""
        lengths = np.asarray(lengths, dtype=np.float64)
        rest = np.asarray(rest, dtype=np.float64)
        lam = lengths / rest
        nu = self.edge_poisson[edges]
        if self.settings.thinning == "rod":
            rod = self.model.edge_rod[edges]
            s = np.bincount(rod, lengths)[rod] / np.bincount(rod, rest)[rod]
            return np.maximum(lam, 1.0) * np.maximum(s, 1.0) ** nu
        return np.maximum(lam, 1.0) ** (1.0 + nu)

    def begin_load_step(self, x: np.ndarray, rest: np.ndarray) -> None:
        """At a new load step, the window follows the rod as it is at the step's start
        (:meth:`window_scale`; fixed through the step, so that the energy is one smooth
        function of the positions within it)."""
        ev = self.model.edge_vertex
        lengths = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1)
        self.broad_phase.window_scale = self.window_scale(lengths, rest)

    # -- measurements ----------------------------------------------------------------------
    def section_stretch(self, x: np.ndarray, rest: np.ndarray) -> np.ndarray:
        """The stretch that thins each edge's section [-]: its own, or the window mean."""
        return self.energy.section_stretch(x, rest)

    def nonlocal_pairs(self, x: np.ndarray, rest: np.ndarray | None = None) -> np.ndarray:
        """Non-local candidate edge pairs (P, 2) within the interaction range at positions
        ``x`` [m] and edge rest lengths ``rest`` [m] (default: :attr:`last_rest`)."""
        return self.broad_phase.nonlocal_pairs(x, self._rest(rest))

    def check_no_intersection(self, x: np.ndarray, rest: np.ndarray | None = None) -> None:
        """Refuse positions ``x`` [m] whose non-local segments are closer than the hard
        limit, saying where (rest arcs for ``rest`` [m], default :attr:`last_rest`)."""
        self.checks.check_no_intersection(x, self._rest(rest))

    def min_distance(self, x: np.ndarray, rest: np.ndarray | None = None
                     ) -> tuple[float, int, int]:
        """Smallest non-local segment distance [m] among pairs within the interaction
        range, and its edge pair (inf, -1, -1 when none); the exclusion window along the
        rest arcs of ``rest`` [m] (default :attr:`last_rest`)."""
        return self.checks.min_distance(x, self._rest(rest))

    def _rest(self, rest: np.ndarray | None) -> np.ndarray:
        return self.last_rest if rest is None else np.asarray(rest, dtype=np.float64)
