"""Self-contact of rods with a radial-compliance layer: the term the Newton solver adds.

Detection: a Warp BVH over the edges' bounds (inflated by the interaction range), rebuilt at
every evaluation; candidate edge pairs go to a fixed-capacity buffer that grows (and the
query reruns) when it overflows, so no contact is ever dropped. Pairs closer along the rod
than the exclusion window are skipped; the window is ``pi D/2`` of rest arc length: on the
tightest bend a tube allows (radius D/2) two points an arc s apart are a chord
``D sin(s/D)`` apart, below D (touching) for every s < pi D/2, so a shorter window would
make a tight but legal bend touch itself (with a C2 ramp over the next quarter window).

Energy, gradient and Hessian: :mod:`tightknot.contact.kernels` (the law:
:mod:`tightknot.contact.law`). No passing through: :meth:`ContactLayer.max_step`
bounds every Newton step so that no two non-local segments come closer than the hard limit
(``hard_fraction`` x D) anywhere along the step.
"""

from __future__ import annotations

import math

import numpy as np
import warp as wp

from tightknot.contact import kernels as ck
from tightknot.contact.law import (
    TABLE_INTERVALS,
    U_MIN,
    RadialComplianceLaw,
    kernel_table,
)
from tightknot.contact.section_radius import SmoothedRadius
from tightknot.rods.model import Model
from tightknot.rods.staging import Launches, Output, Staging
from tightknot.rods.term import EnergyTerm
from tightknot.warp_setup import init_warp

#: Gauss-Legendre points and weights on [0, 1].
_GAUSS = {
    1: ([0.5], [1.0]),
    2: ([0.5 - 0.5 / math.sqrt(3.0), 0.5 + 0.5 / math.sqrt(3.0)], [0.5, 0.5]),
    3: ([0.5 - 0.5 * math.sqrt(0.6), 0.5, 0.5 + 0.5 * math.sqrt(0.6)],
        [5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0]),
}


#: Bounds margin over the edge radius (see ContactLayer.__init__).
_MARGIN = 1.1


#: Most candidate edge pairs the broad phase may return (about 0.5 GB of pair data).
MAX_CANDIDATES = 20_000_000


class ContactCapacityError(ValueError):
    """More candidate contact pairs than memory allows (too fine a mesh for the contact)."""


class SelfIntersectionError(ValueError):
    """The rods already pass through each other (closer than the hard limit)."""


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
            step bound would). Default 0.7 for a compliant law: the barrier takes over where
            the FEM calibration ends (pair overlap 0.3 R); beyond it the power law alone is
            far too soft (measured: a tight 125 mm trefoil pulled past 7 N snapped to a gap
            of 0.12 D0, sections squeezed to a third), whereas an incompressible section
            stiffens. Default 1.0 for a rigid tube.
        core_stiffness: the barrier's stiffness over E/D (energy per length^2 over the
            square of the distance into the band).
        hard_relative: see core_fraction; default 0 (compliant: only the absolute floor),
            0.98 for a rigid tube (its hard radius: the barrier diverges at 0.98 R).
        local_thickness: also guard pairs of one rod inside the exclusion window, down to
            half of it: two points an arc s apart on the tightest legal bend (radius D/2)
            are D sin(s/D) apart, and the barrier acts below 0.7 of that (with R for D), so
            the rod cannot fold onto itself where the law is off. Off by default: measured
            on a tight 125 mm trefoil pulled to 2x its tightening force, it turned a fold
            that jammed Newton at the step bound (legs 0.05 D apart) into one held at
            0.42 D, but it changes the load path of the marginal 185 mm knot (which then
            slides off its tail when loosened to Lambda_OC 15), and it adds candidates.
        initial_capacity: first size of the candidate-pair buffer (grows on demand).
        radius_window: half-width [D0] of the window along the rod over which the stretch
            that thins the contact radius is averaged (:mod:`tightknot.contact.section_radius`);
            0 (default): each edge's own stretch. At 1 D0 the FEM cross-check's indent force
            is within -8 to +7 % of the fine-mesh FEM (-15 to +4 % with 0) and the axial
            force at the deepest crossing 1.07 times the FEM's (3.4 times with 0), and the study's
            knots tie in about as many Newton iterations; each iteration costs more (the
            Hessian couples whole windows; docs/fem_crosscheck.md). Not with a rigid-tube
            law (its radius does not thin), not in the batch (:mod:`tightknot.loading.batch`).
    """

    name = "contact"
    assembles_in_place = True
    keeps_apart = True

    def __init__(
        self,
        model: Model,
        law: RadialComplianceLaw | None = None,
        gauss_points: int = 2,
        exclusion_factor: float = math.pi / 2,
        hard_fraction: float = 0.05,
        core_fraction: float | None = None,
        core_stiffness: float = 1.0,
        hard_relative: float | None = None,
        local_thickness: bool = False,
        initial_capacity: int = 1024,
        radius_window: float = 0.0,
    ) -> None:
        init_warp()
        if not (math.isfinite(radius_window) and 0.0 <= radius_window <= 10.0):
            raise ValueError(f"radius_window must be in [0, 10] (D0), got {radius_window!r}")
        if gauss_points not in _GAUSS:
            raise ValueError(f"gauss_points must be 1, 2 or 3, got {gauss_points}")
        if not (math.isfinite(exclusion_factor) and exclusion_factor >= math.pi / 2):
            raise ValueError(f"exclusion_factor must be >= pi/2, got {exclusion_factor}")
        self.law = law or RadialComplianceLaw.from_json()
        rigid = self.law.rigid
        if core_fraction is None:
            core_fraction = 1.0 if rigid else 0.7
        if hard_relative is None:
            hard_relative = 0.98 if rigid else 0.0
        if not (0.0 < hard_fraction < 0.5):
            raise ValueError(f"hard_fraction must be in (0, 0.5), got {hard_fraction}")
        if not (0.0 <= hard_relative < core_fraction <= 1.0):
            raise ValueError("need 0 <= hard_relative < core_fraction <= 1 (fractions of the "
                             f"contact radius R), got {hard_relative}, {core_fraction}")
        if not (math.isfinite(core_stiffness) and core_stiffness > 0):
            raise ValueError(f"core_stiffness must be finite and > 0, got {core_stiffness}")
        self.model = model
        self.core_fraction = float(core_fraction)
        # Candidate window over the exclusion window: 1 = non-local pairs only.
        self._local_window = 0.5 if local_thickness else 1.0
        self.hard_relative = float(hard_relative)
        self.hard_fraction = float(hard_fraction)
        dev = model.device
        self.device = dev
        m = model
        diam = 2.0 * m.edge_radius
        self.edge_diameter = diam
        # A rigid tube has a hard radius: its contact radius does not thin with stretch.
        nu = np.array([0.0 if self.law.rigid else m.rods[r].material.poisson_ratio
                       for r in m.edge_rod])
        emod = np.array([m.rods[r].material.youngs_modulus for r in m.edge_rod])
        self.edge_modulus = emod
        f64 = wp.float64
        self._edge_vertex = m.wp("edge_vertex")
        self._edge_rod = wp.array(m.edge_rod, dtype=wp.int32, device=dev)
        self._rod_closed = wp.array([int(r.closed) for r in m.rods], dtype=wp.int32, device=dev)
        self._radius0 = wp.array(m.edge_radius, dtype=f64, device=dev)
        self._poisson = wp.array(nu, dtype=f64, device=dev)
        self.radius_window = float(radius_window)
        self._smooth = None
        if self.radius_window > 0.0:
            if self.law.rigid:
                raise ValueError("radius_window needs a compliant law: a rigid tube's "
                                 "radius does not thin with stretch")
            self._smooth = SmoothedRadius(m, self.radius_window, nu)
            self._in_radius = Staging(f64, dev)
        self._modulus = wp.array(emod, dtype=f64, device=dev)
        xi, w = _GAUSS[gauss_points]
        self._gxi = wp.array(xi, dtype=f64, device=dev)
        self._gw = wp.array(w, dtype=f64, device=dev)
        law_ = self.law
        self._law = wp.array([
            law_.k_line, law_.p_line + 1.0, 0.0, law_.k_point, law_.p_point + 1.0,
            math.cos(math.radians(law_.angle_line_deg)) ** 2,
            math.cos(math.radians(law_.angle_point_deg)) ** 2, hard_relative,
            core_fraction, hard_fraction, core_stiffness,
            U_MIN, (1.0 - U_MIN) / TABLE_INTERVALS,
        ], dtype=f64, device=dev)
        self._line_table = wp.array(kernel_table("line", law_.p_line + 1.0, law_.onset_band),
                                    dtype=f64, device=dev)
        self._point_table = wp.array(kernel_table("point", law_.p_point + 1.0,
                                                  law_.onset_band), dtype=f64, device=dev)
        self.exclusion = exclusion_factor * diam
        self._exclusion = wp.array(self.exclusion, dtype=f64, device=dev)
        self._hard = wp.array(hard_fraction * diam, dtype=f64, device=dev)
        # Interaction range of an edge: its radius, grown if the edge is compressed
        # (r0 lam^-nu: 1.1 r0 covers lam >= 0.83 at nu = 1/2), so that two edges whose
        # Gauss points can interact (distance < r_a + r_b) have overlapping bounds.
        self._margin = wp.array(_MARGIN * m.edge_radius, dtype=f64, device=dev)
        self._zero_dx = wp.zeros(m.vertex_count, dtype=wp.vec3d, device=dev)
        self._capacity = int(initial_capacity)
        self._alloc(self._capacity)
        self.last_pairs = np.zeros((0, 2), dtype=np.int32)
        self.last_overlap = np.zeros(0)
        #: Edge rest lengths of the last evaluation (the load path changes them): the
        #: exclusion window of the step bound and of the checks is measured with these.
        self.rest = model.edge_rest_length.copy()
        #: (rest lengths, their arc tables) of the last ``_arcs`` call.
        self._arcs_memo: tuple[np.ndarray, tuple[wp.array, wp.array]] | None = None
        # Placeholders for the kernel's unused Hessian targets.
        self._no_tables = (wp.full(1, -1, dtype=wp.int64, device=dev),
                           wp.zeros(model.vertex_count + 1, dtype=wp.int32, device=dev),
                           wp.full(1, wp.vec3i(-1, -1, -1), dtype=wp.vec3i, device=dev),
                           wp.full(model.vertex_count, wp.vec3i(-1, -1, -1), dtype=wp.vec3i,
                                   device=dev))
        self._no_csc = wp.zeros(1, dtype=wp.float64, device=dev)
        # Inputs and outputs reused from call to call, and the launches recorded over them
        # (tightknot.rods.staging): the per-call arrays and argument packing of the four
        # kernels were most of this layer's Python time on small rods.
        self._in_x = Staging(wp.vec3d, dev)
        self._in_dx = Staging(wp.vec3d, dev)
        self._in_rest = Staging(wp.float64, dev)
        self._lower = wp.empty(m.edge_count, dtype=wp.vec3, device=dev)
        self._upper = wp.empty(m.edge_count, dtype=wp.vec3, device=dev)
        self._grad_out = wp.zeros(m.vertex_count, dtype=wp.vec3d, device=dev)
        self._missing = wp.zeros(1, dtype=wp.int32, device=dev)
        self._energy = Output(wp.float64, dev)
        self._overlap = Output(wp.float64, dev)
        self._dR = Output(wp.float64, dev)
        self._no_radius = wp.zeros(1, dtype=wp.float64, device=dev)
        self._alpha = Output(wp.float64, dev)
        self._dist = Output(wp.float64, dev)
        self._half_hard_memo: tuple[float, np.ndarray, wp.array] | None = None
        self._launches = Launches()
        self._missing_pairs = np.zeros((0, 2), dtype=np.int64)

    # -- buffers and detection -------------------------------------------------------------
    def _alloc(self, capacity: int) -> None:
        self._pairs = wp.zeros(capacity, dtype=wp.vec2i, device=self.device)
        self._count = wp.zeros(1, dtype=wp.int32, device=self.device)

    def _arcs(self, rest: np.ndarray) -> tuple[wp.array, wp.array]:
        # Rest arcs change once per load step but are asked for at every evaluation and
        # step bound (a Python loop over the rods and two device copies each time): reused
        # while the rest lengths are the same.
        memo = self._arcs_memo
        if memo is not None and np.array_equal(memo[0], rest):
            return memo[1]
        out = self._arcs_of(rest)
        self._arcs_memo = (np.array(rest, dtype=np.float64), out)
        return out

    def _arcs_of(self, rest: np.ndarray) -> tuple[wp.array, wp.array]:
        m = self.model
        arcs = np.zeros((m.edge_count, 2))
        lengths = np.zeros(len(m.rods))
        for r, rod in enumerate(m.rods):
            le = rest[rod.edge_slice]
            s1 = np.cumsum(le)
            arcs[rod.edge_slice, 0] = s1 - le
            arcs[rod.edge_slice, 1] = s1
            lengths[r] = s1[-1]
        return (wp.array(arcs, dtype=wp.vec2d, device=self.device),
                wp.array(lengths, dtype=wp.float64, device=self.device))

    def _candidates(self, wx: wp.array, wdx: wp.array, margin: wp.array,
                    arcs: wp.array, rod_len: wp.array) -> wp.array:
        m = self.model
        dev = self.device
        lower, upper = self._lower, self._upper
        self._launches.launch(ck.edge_bounds_kernel, m.edge_count, dev,
                              [self._edge_vertex, wx, wdx, margin], [lower, upper])
        bvh = wp.Bvh(lower, upper)
        while True:
            self._count.zero_()
            # Not a recorded launch: the BVH is new at every call.
            wp.launch(ck.candidate_pairs_kernel, dim=m.edge_count, device=dev,
                      inputs=[self._edge_vertex, self._edge_rod, self._rod_closed, bvh.id,
                              lower, upper, arcs,
                              rod_len, self._exclusion, self._local_window, self._capacity],
                      outputs=[self._count, self._pairs])
            n = int(self._count.numpy()[0])
            if n <= self._capacity:
                return self._pairs[:n]
            if n > MAX_CANDIDATES:
                # Pairs per contact grow as (D/l)^2: a fine mesh of a knot whose strands
                # touch over many diameters outgrows memory (measured: 1.9e6 candidates for
                # a trefoil of 1e4 vertices, about 2e8 at 1e5, where memory ran out).
                raise ContactCapacityError(
                    f"{n} candidate contact pairs exceed the limit {MAX_CANDIDATES}: "
                    f"{m.vertex_count} vertices are too many for this contact set (edges of "
                    f"{np.median(self.model.edge_rest_length) / np.median(self.edge_diameter):.2g}"
                    " D); use fewer nodes (pairs grow as the square of the vertex count)")
            # Overflow: grow and query again, never drop a candidate.
            self._capacity = int(2 ** math.ceil(math.log2(n * 1.25)))
            self._alloc(self._capacity)

    # -- the energy term -------------------------------------------------------------------
    def _launch(self, x: np.ndarray, rest: np.ndarray, want_grad: bool, hess_mode: int,
                tables: tuple[wp.array, ...] | None = None,
                csc: wp.array | None = None, radius: wp.array | None = None) -> tuple:
        """Detect and evaluate every candidate pair; hess_mode 0 none, 1 per-pair 144
        entries, 2 added into the CSC data ``csc`` through the block ``tables``. ``radius``:
        the contact radius of each edge [m] (the smoothed radius); the kernel then also
        writes each pair's dE/dR, d2E/dR2 and d(grad)/dR into ``self._dR`` (14 per pair)."""
        dev = self.device
        self.rest = np.array(rest, dtype=np.float64)
        wx = self._in_x.put(x)
        arcs, rod_len = self._arcs(rest)
        pairs = self._candidates(wx, self._zero_dx, self._margin, arcs, rod_len)
        npairs = pairs.shape[0]
        # The gradient and the missing-block count are returned: fresh for each call, as
        # callers may hold them; zeroed reused arrays for the kernel's sums.
        grad, missing = self._grad_out, self._missing
        grad.zero_()
        missing.zero_()
        if npairs == 0:
            return pairs, np.zeros(0), wp.clone(grad), None, np.zeros(0), wp.clone(missing)
        # The kernel writes every pair's energy and overlap (no zeroing needed).
        energy = self._energy.get(npairs)
        overlap = self._overlap.get(npairs)
        hess = (wp.zeros(npairs * 144, dtype=wp.float64, device=dev) if hess_mode == 1
                else self._no_csc)
        if tables is None:
            tables = self._no_tables
        if csc is None:
            csc = self._no_csc
        wrest = self._in_rest.put(rest)
        self._launches.launch(
            ck.contact_pair_kernel, npairs, dev,
            [self._edge_vertex, self._edge_rod, self._rod_closed, self._radius0,
             self._poisson, self._modulus, self._gxi, self._gw,
             self._law, self._line_table, self._point_table, wx, self._own(pairs), wrest,
             arcs, rod_len, self._exclusion, self._local_window,
             int(want_grad or hess_mode > 0), hess_mode,
             self._no_radius if radius is None else radius, int(radius is not None), *tables],
            [energy, grad, hess, overlap, csc, missing,
             self._no_radius if radius is None else self._dR.get(14 * npairs)],
            variant=(int(want_grad or hess_mode > 0), hess_mode))
        return (pairs, self._energy.numpy(npairs), wp.clone(grad), hess,
                self._overlap.numpy(npairs), wp.clone(missing))

    def _own(self, pairs: wp.array) -> wp.array:
        """The candidate buffer itself when ``pairs`` is its prefix (as ``_candidates``
        returns it), so that the recorded launches see the same array at every call; the
        kernels read only the first ``dim`` pairs."""
        if pairs.ptr == self._pairs.ptr and pairs.device == self._pairs.device:
            return self._pairs
        return pairs

    def evaluate(
        self, x: np.ndarray, rest: np.ndarray, want_grad: bool = True, want_hess: bool = True
    ) -> tuple[float, np.ndarray | None, tuple[np.ndarray, np.ndarray, np.ndarray] | None]:
        """Contact energy [J], gradient over vertex positions (N, 3) [N], Hessian COO
        triplets over global dofs."""
        m = self.model
        geo = self._geometry(x, rest)
        pairs, e_pair, grad, hess, overlap, _ = self._launch(
            x, rest, want_grad, int(want_hess), radius=self._radius_array(geo))
        self._remember(pairs, overlap)
        if pairs.shape[0] == 0:
            empty = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))
            return 0.0, (np.zeros((m.vertex_count, 3)) if want_grad else None), (
                empty if want_hess else None)
        e = float(e_pair.sum())
        g = grad.numpy().copy() if want_grad else None
        coo = None
        if want_hess:
            # Only pairs that interact carry a Hessian (most candidates do not).
            active = np.flatnonzero(e_pair != 0.0)
            npairs = active.size
            hvals = hess.numpy().reshape(-1, 144)[active].ravel()
            dofs = self._pair_dofs(self.last_pairs[active])
            rows = np.broadcast_to(dofs[:, :, None], (npairs, 12, 12)).ravel()
            cols = np.broadcast_to(dofs[:, None, :], (npairs, 12, 12)).ravel()
            coo = (rows, cols, hvals)
        if geo is not None and (want_grad or want_hess):
            g_s, h_s = self._smoothed_terms(geo, e_pair, want_hess)
            if g is not None:
                g += g_s
            if coo is not None:
                coo = tuple(np.concatenate([u, v]) for u, v in zip(coo, h_s, strict=True))
        return e, g, coo

    def evaluate_into(self, x: np.ndarray, rest: np.ndarray, tables: tuple[wp.array, ...],
                      data: wp.array) -> tuple:
        """Energy [J] and gradient (N, 3) [N]; the Hessian is added into ``data``, the CSC
        data array of the system's pattern (zeroed by the caller), through its block
        ``tables`` (:meth:`tightknot.solvers.pattern.ContactPattern.warp_tables`). Blocks of
        new contacts missing from the tables are signalled by None for the gradient: the
        caller grows its pattern by :meth:`missing_blocks` and calls again. With a radius
        window a third item holds the Hessian terms of the smoothed radius (COO over global
        dofs), which couple whole windows and so lie outside the pair blocks."""
        geo = self._geometry(x, rest)
        pairs, e_pair, grad, _, overlap, missing = self._launch(
            x, rest, True, 2, tables, data, radius=self._radius_array(geo))
        self._remember(pairs, overlap)
        if int(missing.numpy()[0]) > 0:
            self._missing_pairs = self.last_pairs[e_pair != 0.0]
            return float(e_pair.sum()), None
        g = grad.numpy().copy()
        if geo is None:
            return float(e_pair.sum()), g
        g_s, h_s = self._smoothed_terms(geo, e_pair, True)
        return float(e_pair.sum()), g + g_s, h_s

    def missing_blocks(self) -> np.ndarray:
        """Vertex-block keys of the interacting pairs of the last :meth:`evaluate_into` that
        found a block missing from the tables."""
        return pair_blocks(self.model.edge_vertex, self._missing_pairs, self.model.vertex_count)

    def check_state(self, x: np.ndarray) -> None:
        """:meth:`check_no_intersection` (the system's check of a start)."""
        self.check_no_intersection(x)

    # -- the stretch-smoothed radius (radius_window > 0) ----------------------------------
    def _geometry(self, x: np.ndarray, rest: np.ndarray) -> dict[str, np.ndarray] | None:
        """Tangents, lengths, smoothed radii and their derivatives (None without window)."""
        if self._smooth is None:
            return None
        return self._smooth.radii(x, np.asarray(rest, dtype=np.float64))

    def _radius_array(self, geo: dict[str, np.ndarray] | None) -> wp.array | None:
        return None if geo is None else self._in_radius.put(geo["rho"])

    def _smoothed_terms(self, geo: dict[str, np.ndarray], e_pair: np.ndarray,
                        want_hess: bool) -> tuple[np.ndarray, tuple | None]:
        """The smoothed radius's gradient term (V, 3) [N] and Hessian COO (or None)."""
        active = np.flatnonzero(e_pair != 0.0)
        pr = self.last_pairs[active]
        d_r = self._dR.numpy(14 * e_pair.size).reshape(-1, 14)[active]
        g, big_g, c = self._smooth.gradient(geo, pr, d_r[:, 0])
        if not want_hess:
            return g, None
        return g, self._smooth.hessian(geo, pr, self._pair_dofs(pr), d_r[:, 1], d_r[:, 2:],
                                       big_g, c)

    def _pair_dofs(self, pairs: np.ndarray) -> np.ndarray:
        """The 12 position dofs of each edge pair's vertices [a0, a1, b0, b1], (P, 12)."""
        m = self.model
        ev = m.edge_vertex.astype(np.int64)
        verts = np.concatenate([ev[pairs[:, 0]], ev[pairs[:, 1]]], axis=1)  # (P, 4)
        return (m.vertex_dof.astype(np.int64)[verts][:, :, None] + np.arange(3)).reshape(-1, 12)

    def section_stretch(self, x: np.ndarray, rest: np.ndarray) -> np.ndarray:
        """The stretch that thins each edge's section [-]: its own, or the window mean."""
        if self._smooth is not None:
            return self._smooth.stretch(x, np.asarray(rest, dtype=np.float64))
        ev = self.model.edge_vertex
        return np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1) / rest

    def active_blocks(self) -> np.ndarray:
        """Vertex-block keys of the pairs that interacted at the last evaluation."""
        active = self.last_pairs[self.last_overlap > 0.0]
        return pair_blocks(self.model.edge_vertex, active, self.model.vertex_count)

    def _remember(self, pairs: wp.array, overlap: np.ndarray) -> None:
        self.last_pairs = pairs.numpy().astype(np.int64) if pairs.shape[0] else np.zeros(
            (0, 2), dtype=np.int64)
        self.last_overlap = overlap.copy()

    # -- no passing through ----------------------------------------------------------------
    def max_step(self, x: np.ndarray, dx: np.ndarray) -> float:
        """Largest fraction of the step ``dx`` [m] (vertices) that keeps every non-local
        segment pair at least the hard limit apart along the straight path (1 = full)."""
        wx = self._in_x.put(x)
        wdx = self._in_dx.put(dx)
        arcs, rod_len = self._arcs(self.rest)
        # Sweep each edge's bounds over the step, inflated by half the hard limit.
        pairs = self._candidates(wx, wdx, self._half_hard(), arcs, rod_len)
        n = pairs.shape[0]
        if n == 0:
            return 1.0
        alpha = self._step_bounds(wx, wdx, pairs)
        return float(np.clip(alpha.min(), 0.0, 1.0))

    def _step_bounds(self, wx: wp.array, wdx: wp.array, pairs: wp.array
                     ) -> np.ndarray:
        """The step-bound kernel over ``pairs`` (step_bound_kernel): each pair's largest
        step fraction (host copy); the pairs' distances are left in ``self._dist``."""
        n = pairs.shape[0]
        alpha = self._alpha.get(n)  # written for every pair: no zeroing needed
        dist = self._dist.get(n)
        self._launches.launch(ck.step_bound_kernel, n, self.device,
                              [self._edge_vertex, wx, wdx, self._own(pairs), self._hard],
                              [alpha, dist])
        return self._alpha.numpy(n)

    def _half_hard(self) -> wp.array:
        # Kept while the hard fraction and the diameters are unchanged (they are public
        # attributes; a caller may change them between calls).
        memo = self._half_hard_memo
        if (memo is not None and memo[0] == self.hard_fraction
                and np.array_equal(memo[1], self.edge_diameter)):
            return memo[2]
        arr = wp.array(0.5 * self.hard_fraction * self.edge_diameter,
                       dtype=wp.float64, device=self.device)
        self._half_hard_memo = (self.hard_fraction, np.array(self.edge_diameter), arr)
        return arr

    def _pair_distances(self, x: np.ndarray, margin: wp.array) -> tuple[np.ndarray, ...]:
        """Non-local candidate edge pairs within ``margin`` bounds and their segment
        distances [m]; also the rest arcs of the edges."""
        wx = self._in_x.put(x)
        arcs, rod_len = self._arcs(self.rest)
        pairs = self._candidates(wx, self._zero_dx, margin, arcs, rod_len)
        n = pairs.shape[0]
        if n == 0:
            return np.zeros((0, 2), dtype=np.int32), np.zeros(0), arcs.numpy()
        self._step_bounds(wx, self._zero_dx, pairs)
        return pairs.numpy(), self._dist.numpy(n), arcs.numpy()

    def check_no_intersection(self, x: np.ndarray) -> None:
        """Refuse positions whose non-local segments are closer than the hard limit,
        saying where (rest arc lengths of the offending pair)."""
        pr, d, ar = self._pair_distances(x, self._half_hard())
        if not d.size:
            return
        dh = self.hard_fraction * self.edge_diameter
        hard = np.maximum(dh[pr[:, 0]], dh[pr[:, 1]])
        bad = np.flatnonzero(d < hard)
        if bad.size:
            k = bad[np.argmin(d[bad] / hard[bad])]
            a, b = pr[k]
            raise SelfIntersectionError(
                f"the rods intersect themselves: edges {a} and {b} (rest arc lengths "
                f"{ar[a][0]:.6g}..{ar[a][1]:.6g} m and {ar[b][0]:.6g}..{ar[b][1]:.6g} m) are "
                f"{d[k]:.4g} m apart, below the hard limit {hard[k]:.4g} m "
                f"({self.hard_fraction:g} D)")

    def _window_separations(self, pr: np.ndarray, ar: np.ndarray) -> tuple[np.ndarray, ...]:
        """For edge pairs ``pr`` with rest arcs ``ar``: whether both edges lie on one rod,
        the rest arc separations of their four end pairs (the shorter way round on a closed
        rod), each pair's rod length and closure, and its exclusion window."""
        m = self.model
        rod = m.edge_rod[pr]
        a, b = ar[pr[:, 0]], ar[pr[:, 1]]
        seps = np.abs(a[:, :, None] - b[:, None, :]).reshape(-1, 4)
        length = np.array([ar[r.edge_slice][-1, 1] for r in m.rods])[rod[:, 0]]
        closed = np.array([r.closed for r in m.rods])[rod[:, 0]]
        seps = np.where(closed[:, None], np.minimum(seps, length[:, None] - seps), seps)
        excl = np.maximum(self.exclusion[pr[:, 0]], self.exclusion[pr[:, 1]])
        return rod[:, 0] == rod[:, 1], seps, length, closed, excl

    def _nonlocal(self, pr: np.ndarray, ar: np.ndarray) -> np.ndarray:
        """Mask of the pairs that hold two points farther apart along the rod than the
        exclusion window (the candidates also hold closer pairs, for the local barrier)."""
        same, seps, _, _, excl = self._window_separations(pr, ar)
        return ~same | (seps.max(axis=1) >= excl)

    def _beyond_window(self, x: np.ndarray, pr: np.ndarray, d: np.ndarray,
                       ar: np.ndarray, grid: int = 17) -> np.ndarray:
        """Distances [m] of pairs of one rod that straddle the exclusion window, measured
        only between their points farther apart along the rod than the window (on a
        ``grid`` x ``grid`` set of point pairs): the whole segments' distance would be that
        of a tight bend's neighbouring points on a coarse mesh (a loose 40 D0 trefoil at 64
        vertices reported 0.63 D0 where its strands are 0.998 D0 apart)."""
        m = self.model
        same, seps, length, closed, excl = self._window_separations(pr, ar)
        a, b = ar[pr[:, 0]], ar[pr[:, 1]]
        partial = np.flatnonzero(same & (seps.min(axis=1) < excl))
        if not partial.size:
            return d
        d = d.copy()
        u = np.linspace(0.0, 1.0, grid)
        ev = m.edge_vertex
        for k in partial:
            ea, eb = pr[k]
            pa = x[ev[ea, 0]] + u[:, None] * (x[ev[ea, 1]] - x[ev[ea, 0]])
            pb = x[ev[eb, 0]] + u[:, None] * (x[ev[eb, 1]] - x[ev[eb, 0]])
            sa = a[k, 0] + u * (a[k, 1] - a[k, 0])
            sb = b[k, 0] + u * (b[k, 1] - b[k, 0])
            sep = np.abs(sa[:, None] - sb[None, :])
            if closed[k]:
                sep = np.minimum(sep, length[k] - sep)
            dist = np.linalg.norm(pa[:, None, :] - pb[None, :, :], axis=2)
            ok = sep >= excl[k]
            d[k] = dist[ok].min() if ok.any() else math.inf
        return d

    def min_distance(self, x: np.ndarray) -> tuple[float, int, int]:
        """Smallest non-local segment distance [m] among pairs within the interaction
        range, and its edge pair (inf, -1, -1 when none)."""
        pr, d, ar = self._pair_distances(x, self._margin)
        if d.size:
            keep = self._nonlocal(pr, ar)
            pr, d = pr[keep], d[keep]
        if d.size:
            d = self._beyond_window(x, pr, d, ar)
        if not d.size:
            return math.inf, -1, -1
        k = int(np.argmin(d))
        return float(d[k]), int(pr[k][0]), int(pr[k][1])


def pair_blocks(edge_vertex: np.ndarray, pairs: np.ndarray, vertex_count: int) -> np.ndarray:
    """Keys vr * V + vc of the 16 vertex blocks of each edge pair (a, b)."""
    ev = edge_vertex.astype(np.int64)
    verts = np.concatenate([ev[pairs[:, 0]], ev[pairs[:, 1]]], axis=1)  # (P, 4)
    return (verts[:, :, None] * vertex_count + verts[:, None, :]).ravel()
