"""The sectioned contact level: each edge's cross-section is state, pressed by its partners.

Where the compliant level reads contact width, pressure and area off a law of centerline
distance, here the section's boundary, r(phi) = R + sum_{n=2..N} (a_n cos n phi + b_n sin n
phi), is a field along the rod: every vertex carries its coefficients c = (a_2, b_2, ...,
a_N, b_N) as degrees of freedom of the rod system (``State.extra``, 2 (N - 1) per vertex),
interpolated linearly along each edge (:mod:`tightknot.contact.sectioned_reference`: the
frames, the interpolation and the contact), and the section's deformation, its contact
width, pressure and area come out of the equilibrium (docs/sectioned_level.md). The energy
adds to the rod's elastic energy, per edge of rest length h with the coefficients c_0, c_1'
of its two vertices in its frame (c_1' = Q^T c_1, Q turning mode n by n m, m the reference
twist to the next edge's frame, that of the frames carried to the positions, so that the
energy is a function of positions and coefficients; its chain rule is
:mod:`tightknot.contact.section_twist`'s):

* **mode energy**, int (1/2) k_n |c(s)|^2 ds = (k_n h / 6) (|c_0|^2 + c_0 . c_1' + |c_1'|^2)
  per mode, the plane-strain stiffness of an incompressible disk k_n = 2 pi mu (n^2 - 1) / n,
  mu = E / 3 (:func:`tightknot.contact.section_modes.mode_stiffness`, confirmed by the FEM
  within 1 %);
* **axial gradient energy**, int (1/2) g_n |dc/ds|^2 ds = (1/2) g_n |c_1' - c_0|^2 / h with
  g_n = k_n l_n^2, l_n the decay lengths of a mode along the FEM's 3D rod
  (:class:`SectionCalibration`; modes above 4 at l_4 4 / n);
* **the mean radius from the area**, R^2 = r0^2 lambda^(-2 nu) - |c|^2 / 2 (Parseval): a
  squeezed section lengthens its edge, the incompressible Poisson effect;
* **contact between deformed boundaries**: a stiff rounded penalty on the penetration of
  each section's boundary samples into its partners' surfaces
  (:mod:`tightknot.contact.sectioned_reference`, kernels in
  :mod:`tightknot.contact.sectioned_kernels`), pressure kappa pen with kappa = penalty
  E / D0, the penalty the local compliance of the modes above N fitted to the FEM's
  plane-strain squeeze (:class:`SectionCalibration`).

The broad phase, the exclusion window, the step bound (no pass-through) and the independent
proximity check are the compliant level's (:class:`tightknot.contact.layer.ContactLayer`):
they act on the centerlines. Rods listed in ``rigid_rods`` keep round rigid sections of
their rest radius and own no section dofs (the FEM scenes' rigid counter-bodies).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import warp as wp

from tightknot.contact import sectioned_kernels as sk
from tightknot.contact.layer import ContactLayer
from tightknot.contact.rod_mean_radius import RodMeanRadius
from tightknot.contact.section_modes import mode_stiffness
from tightknot.contact.section_shift import MIN_CHORD, SectionShift, ShiftedCentreline
from tightknot.contact.section_twist import (
    TwistChain,
    TwistParts,
    turn_direction,
)
from tightknot.rods.model import Model
from tightknot.rods.staging import Staging
from tightknot.rods.term import BlockHessian

#: Smallest mode count: an ellipse (N = 2) cannot wrap a convex partner; the nip needs the
#: section to turn a concave face to it, which takes n = 3 and 4.
MIN_MODES = 4
#: Largest difference of two evaluations' frames (unit vectors, twist angles [rad]) for
#: which the second reuses the first's pairs in contact (frames carried to the same
#: positions differ by round-off only).
FRAME_MATCH = 1e-9
#: Chunks of pairs a pass kernel's launch on a CPU is split into, each on its own thread
#: (Warp's CPU kernels run on one thread and release the GIL while they run). A fixed
#: count, not the machine's cores, so that the results are the same on every machine.
CPU_CHUNKS = 2
#: Fewest pairs per chunk: below, a thread's hand-over (tens of microseconds) costs more
#: than the half kernel it saves.
MIN_CHUNK_PAIRS = 16

_POOL: ThreadPoolExecutor | None = None


def pair_chunks(count: int) -> list[tuple[int, int]]:
    """Half-open ranges of ``count`` pairs in :func:`interleaved` order: at most
    :data:`CPU_CHUNKS` chunks of at least :data:`MIN_CHUNK_PAIRS` pairs (one chunk when
    there are fewer), chunk c holding the pairs c, c + C, c + 2 C ..."""
    n = max(1, min(CPU_CHUNKS, count // MIN_CHUNK_PAIRS))
    sizes = [len(range(c, count, n)) for c in range(n)]
    edges = np.concatenate([[0], np.cumsum(sizes)]).astype(int).tolist()
    return list(zip(edges[:-1], edges[1:], strict=True))


def interleaved(count: int, chunks: int) -> np.ndarray:
    """The order of ``count`` pairs in which chunk c of :func:`pair_chunks` holds the
    pairs c, c + ``chunks``, c + 2 ``chunks`` ..."""
    return np.concatenate([np.arange(c, count, chunks) for c in range(chunks)])


def _chunk_pool() -> ThreadPoolExecutor:
    """The threads that launch the chunks after the first (one pool per process)."""
    global _POOL
    if _POOL is None:
        _POOL = ThreadPoolExecutor(max_workers=CPU_CHUNKS - 1,
                                   thread_name_prefix="tightknot-pass")
    return _POOL

#: Index of the penalty among a pass kernel's model arguments (``SectionedLayer._model_args``).
_PENALTY_ARG = 16
#: Index of the Gauss-Newton switch among them (:meth:`SectionedLayer.set_gauss_newton`).
_GAUSS_NEWTON_ARG = 19

_CALIBRATION_FILE = Path(__file__).resolve().parents[1] / "data" / "section_calibration.json"


@dataclass(frozen=True)
class SectionCalibration:
    """What the sectioned level takes from the FEM (docs/sectioned_level.md).

    Attributes:
        decay_length_over_d0: how far mode n spreads along a 3D rod of the FEM's solid, l_n
            / D0 (:func:`tightknot.fem.section_modes.rod_mode_decay`, fine mesh); modes above
            the largest measured n take l_N' N' / n (a surface wave's 1/n), reported.
        penalty_by_max_mode: the contact penalty over E/D0 for each mode count N, fitted to
            the FEM's plane-strain squeeze (:func:`tightknot.fem.section_calibration.
            calibrate_section_penalty`): the local compliance of the modes above N.
        calibrated_w_hat: the largest per-side approach w/D0 of the squeeze levels the
            penalty was fitted to (line contact).
        crossing_w_hat: the largest per-side approach w/D0 at which the FEM judged a
            crossing (the indent of the cross-check).
        source: where the numbers come from.
        judged_area_ratio: the smallest section area A/A0 at which the FEM judged the
            sections (the cross-check's deepest wrap level); 0 when not given.
    """

    decay_length_over_d0: dict[int, float]
    penalty_by_max_mode: dict[int, float]
    calibrated_w_hat: float
    crossing_w_hat: float
    source: str
    judged_area_ratio: float = 0.0

    @classmethod
    def from_json(cls, path: str | Path | None = None) -> SectionCalibration:
        """The shipped calibration (or the file ``path``); a file without the section's
        calibration is refused, naming what it lacks."""
        where = Path(path) if path is not None else _CALIBRATION_FILE
        d = json.loads(where.read_text())
        missing = [k for k in ("decay_length_over_d0", "penalty_by_max_mode") if k not in d]
        if missing:
            raise ValueError(f"{where} holds no section calibration ({', '.join(missing)} "
                             "missing): the sectioned level needs one "
                             "(tightknot.fem.section_calibration)")
        decay = {int(k): float(v) for k, v in d["decay_length_over_d0"].items()}
        if not all(n in decay for n in (2, 3, 4)):
            raise ValueError(f"{where}: the decay lengths of modes 2, 3 and 4 are required")
        pen = {int(k): float(v["penalty"]) for k, v in d["penalty_by_max_mode"].items()}
        date = d.get("provenance", {}).get("date", "?")
        fitted = float(d.get("fem", {}).get("fitted_w_over_d0", [0.0, 0.0])[1])
        return cls(decay, pen, fitted, float(d.get("validated_crossing_w_over_d0", 0.0)),
                   f"FEM calibration {where.name} ({date})",
                   float(d.get("validated_min_area_ratio", 0.0)))

    def decay_length(self, n: int) -> tuple[float, bool]:
        """l_n / D0 of mode ``n`` and whether it was measured (else extrapolated)."""
        if n in self.decay_length_over_d0:
            return self.decay_length_over_d0[n], True
        top = max(self.decay_length_over_d0)
        return self.decay_length_over_d0[top] * top / n, False

    def penalty(self, max_mode: int) -> float:
        """The calibrated penalty [E/D0] of ``max_mode`` modes."""
        if max_mode not in self.penalty_by_max_mode:
            known = sorted(self.penalty_by_max_mode)
            raise ValueError(f"section_modes {max_mode} has no calibrated penalty (the "
                             f"calibration covers {known[0]} to {known[-1]})")
        return self.penalty_by_max_mode[max_mode]


@dataclass(frozen=True)
class SectionSettings:
    """Settings of the sectioned level.

    Attributes:
        max_mode: highest Fourier mode N of the boundary (>= 4).
        samples: boundary samples per section M (angles 2 pi (k + 1/2) / M), >= 4 N: a
            round section between samples sits r (1 - cos(pi/M)) inside their polygon
            (6e-4 D0 at M = 64, below the smallest approach the FEM compares).
        penalty: penalty stiffness over E/D0 [-] (pressure kappa pen, kappa = penalty E/D0);
            None: the calibrated one of ``max_mode`` (:class:`SectionCalibration`).
        onset: the penalty's rounded onset over D0 [-].
        bend_shift: centre each section's boundary on the tight bend's offset centreline,
            x + (nu R^2 / 2) kappa (Saint-Venant's anticlastic flexure,
            :mod:`tightknot.contact.section_shift`); False (the default): on the
            centreline. Off by default: it meets the FEM's clasp from 0.67 D0 of clamp
            travel on, but costs time and moves the rigid wrap's second tension off the
            target (docs/sectioned_level.md, "The bend's section shift").
        bend_shift_chord: the chord [D0] the shift's curvature is taken over, each side
            (2 D0: of the chords tried, the one the FEM's clasp and wraps agree with best,
            docs/sectioned_level.md; at least 0.75).
        thinning: the stretch that thins the sections, R^2 = r0^2 lam^(-2 nu) - |c|^2 / 2:
            "edge" (the default), each edge's own; "rod", its rod's mean stretch L/L0, as
            the compliant level's default since issue 17
            (:mod:`tightknot.contact.rod_mean_radius`). With "edge" the contact energy
            drops as the edges it presses stretch, which pulls them apart (axial contact
            forces up to twice the normal ones in the FEM wrap, docs/sectioned_level.md,
            "Resolution"); with "rod" the gradient is exact and the Hessian's dense part
            through each rod's length (rank 2 per rod, solved by the Woodbury identity)
            comes from central differences of the kernel in the rod's stretch (it costs
            two more kernel launches per rod and Hessian). Not with ``bend_shift``.
    """

    max_mode: int = 8
    samples: int = 64
    penalty: float | None = None
    onset: float = 1e-4
    bend_shift: bool = False
    bend_shift_chord: float = 2.0
    thinning: str = "edge"

    def __post_init__(self) -> None:
        if self.thinning not in ("edge", "rod"):
            raise ValueError(f"section thinning must be 'edge' or 'rod', got "
                             f"{self.thinning!r}")
        if self.thinning == "rod" and self.bend_shift:
            raise ValueError("section thinning 'rod' and bend_shift are not built together "
                             "(the shift's stretch is the offset line's own)")
        if (isinstance(self.max_mode, bool) or int(self.max_mode) != self.max_mode
                or self.max_mode < MIN_MODES):
            raise ValueError(f"section_modes must be an integer >= {MIN_MODES} (an ellipse "
                             f"cannot wrap a convex partner), got {self.max_mode!r}")
        if int(self.samples) != self.samples or self.samples < 4 * self.max_mode:
            raise ValueError(f"section samples must be an integer >= 4 x section_modes = "
                             f"{4 * self.max_mode}, got {self.samples!r}")
        if self.penalty is not None and not (math.isfinite(self.penalty) and self.penalty > 0.0):
            raise ValueError(f"section penalty must be finite and > 0, got {self.penalty!r}")
        if not isinstance(self.bend_shift, bool):
            raise ValueError(f"section bend_shift must be true or false, got "
                             f"{self.bend_shift!r}")
        if not (isinstance(self.bend_shift_chord, (int, float))
                and math.isfinite(self.bend_shift_chord)
                and self.bend_shift_chord >= MIN_CHORD):
            raise ValueError(f"section bend_shift_chord must be >= {MIN_CHORD} D0 (shorter "
                             f"chords turn the zigzag mode over), got "
                             f"{self.bend_shift_chord!r}")
        if not (math.isfinite(self.onset) and 0.0 < self.onset < 0.01):
            raise ValueError(f"section penalty onset must be in (0, 0.01) D0, got "
                             f"{self.onset!r}")

    @property
    def coeff_count(self) -> int:
        """Section coefficients per edge, 2 (N - 1)."""
        return 2 * (self.max_mode - 1)


class SectionedLayer(ContactLayer):
    """The sectioned contact level of a model (module docstring).

    Args:
        model: the rods.
        settings: the section's modes, samples and penalty.
        rigid_rods: indices of rods whose sections stay round and rigid (rest radius).
        **layer: the compliant layer's settings for the broad phase, exclusion window and
            step bound (``gauss_points``, ``exclusion_factor``, ``hard_fraction``).
    """

    assembles_in_place = False

    def __init__(self, model: Model, settings: SectionSettings | None = None,
                 rigid_rods: Sequence[int] = (),
                 calibration: SectionCalibration | None = None, **layer) -> None:
        self.section = settings or SectionSettings()
        if self.section.coeff_count > sk.MAX_COEFF:
            raise ValueError(f"section_modes must be <= {sk.MAX_COEFF // 2 + 1}, got "
                             f"{self.section.max_mode}")
        super().__init__(model, **layer)
        #: The FEM calibration the section's gradient energy and penalty come from.
        self.calibration = calibration or SectionCalibration.from_json()
        #: The contact penalty over E/D0 (the calibrated one unless the settings give one).
        self.penalty = (self.section.penalty if self.section.penalty is not None
                        else self.calibration.penalty(self.section.max_mode))
        m = model
        k = self.section.coeff_count
        rigid = set(int(r) for r in rigid_rods)
        bad = [r for r in rigid if not 0 <= r < len(m.rods)]
        if bad:
            raise ValueError(f"rigid_rods: no rod {bad[0]} (the model has {len(m.rods)})")
        #: Whether each edge's and each vertex's section is rigid.
        self.edge_rigid = np.array([int(r) in rigid for r in m.edge_rod], dtype=bool)
        self.vertex_rigid = np.array([int(r) in rigid for r in m.vertex_rod], dtype=bool)
        offset = np.full(m.vertex_count, -1, dtype=np.int64)
        deformable = np.flatnonzero(~self.vertex_rigid)
        offset[deformable] = np.arange(deformable.size) * k
        #: First coefficient of each vertex's section in the term's dofs (-1: rigid).
        self.vertex_offset = offset
        self.dof_count = int(deformable.size * k)
        self.modes = np.arange(2, self.section.max_mode + 1)
        #: Rest radius r0 [m] and Poisson ratio of each edge.
        self.edge_r0 = np.asarray(m.edge_radius, dtype=np.float64)
        self.edge_nu = np.array([m.rods[r].material.poisson_ratio for r in m.edge_rod])
        # Mode stiffness k_n [Pa] and gradient stiffness g_n = k_n l_n^2 [N] per edge
        # (a_n and b_n alike).
        stiff = np.array([[mode_stiffness(int(n), e) for n in self.modes]
                          for e in self.edge_modulus])
        lengths = np.array([self.calibration.decay_length(int(n))[0] for n in self.modes])
        self.mode_stiff = np.repeat(stiff, 2, axis=1)
        d0 = 2.0 * self.edge_r0
        self.grad_stiff = self.mode_stiff * (np.repeat(lengths, 2)[None, :]
                                             * d0[:, None]) ** 2
        #: Which decay lengths were extrapolated (modes above 4).
        self.extrapolated_modes = [int(n) for n in self.modes
                                   if not self.calibration.decay_length(int(n))[1]]
        ev = m.edge_vertex.astype(np.int64)
        self._ev = ev
        # The joint after each edge (its reference twist turns the next vertex's section
        # into the edge's frame), -1 at the end of an open rod.
        nxt = np.full(m.edge_count, -1, dtype=np.int64)
        if m.joint_count:
            nxt[m.joint_edge[:, 0]] = np.arange(m.joint_count)
        self._next_joint = nxt
        self._section_edges = np.flatnonzero(~self.edge_rigid)
        #: The offset centreline the boundaries are centred on (None: the centreline).
        self.shift = (SectionShift(m, np.array([r not in rigid for r in range(len(m.rods))]),
                                   self.section.bend_shift_chord)
                      if self.section.bend_shift else None)
        # Nodes of the Hessian's blocks: each vertex's 3 coordinates and its K coefficients.
        nodes = m.vertex_count
        pos = m.vertex_dof.astype(np.int64)[:, None] + np.arange(3)
        sec = np.where(offset[:, None] >= 0, m.dof_count + offset[:, None] + np.arange(k), -1)
        self._node_dofs = np.concatenate([pos, sec], axis=1)
        # The end twists' chain rule (the joint after each deformable edge): the twists are
        # the centreline's, with or without the bend shift
        twist_joint = np.where(self.edge_rigid, -1, nxt)
        #: The chain rule through the end twists.
        self.twist_chain = TwistChain(twist_joint, m.joint_vertex, m.vertex_dof,
                                      self._node_dofs, m.dof_count + self.dof_count)
        # The node pairs the section energy always couples (each deformable edge's ends).
        se = ev[self._section_edges]
        pairs = np.concatenate([se, se[:, ::-1], se[:, [0, 0]], se[:, [1, 1]]])
        self._section_keys = np.unique(pairs[:, 0] * nodes + pairs[:, 1])
        # term dof -> (its vertex, its index within the vertex's node)
        self._dof_node = np.repeat(deformable, k)
        self._dof_local = 3 + np.tile(np.arange(k), deformable.size)
        dev = self.device
        f64 = wp.float64
        ends = np.zeros((m.edge_count, 2), dtype=np.int32)
        # each edge's neighbouring vertices on its rod, before its first and after its
        # second (its partition weight's chords); -1 at an open end
        neighbour = np.full((m.edge_count, 2), -1, dtype=np.int64)
        for rod in m.rods:
            sl = rod.edge_slice
            n_e = sl.stop - sl.start
            if not rod.closed:
                ends[sl.start, 0] = 1
                ends[sl.stop - 1, 1] = 1
            for j in range(n_e):
                e = sl.start + j
                if j > 0 or rod.closed:
                    neighbour[e, 0] = ev[sl.start + (j - 1) % n_e, 0]
                if j < n_e - 1 or rod.closed:
                    neighbour[e, 1] = ev[sl.start + (j + 1) % n_e, 1]
        #: The vertex before and after each edge on its rod (-1 at an open end).
        self.edge_neighbour = neighbour
        g_xi, g_w = self.settings.gauss
        samples = int(self.section.samples)
        sample_cos = wp.zeros(samples, dtype=f64, device=dev)
        sample_sin = wp.zeros(samples, dtype=f64, device=dev)
        wp.launch(sk.sample_directions, samples, [samples], [sample_cos, sample_sin],
                  device=dev)
        edge_r0 = wp.array(self.edge_r0, dtype=f64, device=dev)
        edge_nu = wp.array(self.edge_nu, dtype=f64, device=dev)
        edge_rigid = wp.array(self.edge_rigid.astype(np.int32), dtype=wp.int32, device=dev)
        vertex_offset = wp.array(offset.astype(np.int32), dtype=wp.int32, device=dev)
        rod_mean = int(self.section.thinning == "rod")
        self._model_args = [
            self.broad_phase.edge_vertex, self.broad_phase.edge_rod,
            self.broad_phase.rod_closed, edge_r0, edge_nu,
            wp.array(self.edge_modulus, dtype=f64, device=dev), edge_rigid, vertex_offset,
            wp.array(ends, dtype=wp.vec2i, device=dev),
            self.broad_phase.edge_exclusion,
            wp.array(g_xi, dtype=f64, device=dev), wp.array(g_w, dtype=f64, device=dev),
            sample_cos, sample_sin, k, samples, float(self.penalty), float(self.section.onset),
            rod_mean, 0, wp.array(neighbour.astype(np.int32), dtype=wp.vec2i, device=dev),
        ]
        assert self._model_args[_PENALTY_ARG] == float(self.penalty)
        assert self._model_args[_GAUSS_NEWTON_ARG] == 0
        #: The factor on the penalty of the contact kernels (:meth:`set_penalty_scale`).
        self.penalty_scale = 1.0
        #: Whether the contact's Hessian is its Gauss-Newton part (:meth:`set_gauss_newton`).
        self.gauss_newton = False
        # the inputs of sk.section_bounds before the state's, and its outputs
        self._bounds_args = [self.broad_phase.edge_vertex, vertex_offset, edge_r0, edge_nu,
                             edge_rigid, k, rod_mean]
        self._vertex_amp = wp.zeros(m.vertex_count, dtype=f64, device=dev)
        self._edge_rbase = wp.zeros(m.edge_count, dtype=f64, device=dev)
        #: Pass kernels launched once (their modules loaded; :meth:`_launch`).
        self._launched: set[str] = set()
        #: Each rod's mean stretch (the sections' thinning with ``thinning="rod"``).
        self.rod_mean = (RodMeanRadius(m, self.edge_nu) if self.section.thinning == "rod"
                         else None)
        self._in_lam = Staging(f64, dev)
        self._in_lam_fd = Staging(f64, dev)
        self._in_coeff = Staging(f64, dev)
        self._in_t = Staging(wp.vec3d, dev)
        self._in_d1 = Staging(wp.vec3d, dev)
        self._in_twist = Staging(f64, dev)
        self._in_rest = Staging(f64, dev)
        self._in_margin = Staging(f64, dev)
        # the state (x, extra, rest, frames) of the last energy-only evaluation and its
        # pairs in contact (:meth:`contact_energy`)
        self._energy_only: tuple | None = None

    def set_penalty_scale(self, scale: float) -> None:
        """Scale the contact penalty by ``scale`` in (0, 1] (1: the calibrated level): a
        homotopy that lets round sections settle into a tight knot's contacts gradually
        (:func:`tightknot.loading.tie.section_finish`)."""
        if not (math.isfinite(scale) and 0.0 < scale <= 1.0):
            raise ValueError(f"penalty scale must be in (0, 1], got {scale!r}")
        self._model_args[_PENALTY_ARG] = float(self.penalty) * float(scale)
        self.penalty_scale = float(scale)
        self._energy_only = None

    def set_gauss_newton(self, on: bool) -> None:
        """Evaluate the contact's Gauss-Newton Hessian (``on``) instead of its exact one:
        per sample only the penalty's curvature times the outer product of the
        penetration's gradient, positive semidefinite, without the gap's own curvature
        weighed by the penalty's slope (which makes a deep contact's exact Hessian
        indefinite). Energy and gradient are unchanged; the chain rule through the
        sections' reference twist (:mod:`tightknot.contact.section_twist`) is applied to
        this Hessian and the gradient as to the exact one."""
        self._model_args[_GAUSS_NEWTON_ARG] = int(bool(on))
        self.gauss_newton = bool(on)

    def set_shift_scale(self, scale: float) -> None:
        """Apply the fraction ``scale`` in (0, 1] of the bend shift (a continuation path's
        stage, :func:`tightknot.loading.tie.section_finish`); no effect without the
        shift."""
        if self.shift is not None:
            self.shift.set_scale(scale)
            self._energy_only = None

    # -- the section field -----------------------------------------------------------------
    def end_twist(self, m_ref: np.ndarray) -> np.ndarray:
        """Per edge, the reference twist [rad] from its frame to the frame its second
        vertex's section is stored in (the next edge's; 0 at the end of an open rod)."""
        nxt = self._next_joint
        out = np.zeros(nxt.size)
        has = nxt >= 0
        out[has] = m_ref[nxt[has]]
        return out

    def vertex_sections(self, extra: np.ndarray) -> np.ndarray:
        """Each vertex's (V, K) coefficients [m] as stored, in the frame of the edge it
        starts (zero on rigid sections)."""
        k = self.section.coeff_count
        full = np.zeros((self.model.vertex_count, k))
        if extra.size:
            full[~self.vertex_rigid] = extra.reshape(-1, k)
        return full

    def edge_sections(self, extra: np.ndarray, m_ref: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
        """Each edge's (E, K) coefficients [m] at its first vertex and at its second, both
        in the edge's frame (zero on rigid sections)."""
        full = self.vertex_sections(extra)
        c0 = full[self._ev[:, 0]]
        c1 = _rotate(full[self._ev[:, 1]], self.modes, self.end_twist(m_ref), transpose=True)
        return c0, c1

    def slid_sections(self, extra: np.ndarray, old_frames: tuple[np.ndarray, np.ndarray],
                      new_frames: tuple[np.ndarray, np.ndarray], k: int,
                      rotation: np.ndarray) -> np.ndarray:
        """The section dofs [m] of a single open rod whose material slid by ``k`` edges along
        it (vertex i takes vertex i - k's place) and turned by ``rotation`` (3 x 3): each
        vertex's coefficients move with it, re-expressed in the new frame of the edge that
        stores them (``new_frames`` = (t_ref, d1_ref)) from the turned old one (mode n by n
        times the angle between the two directors); vertices with no source get round
        sections."""
        m = self.model
        nk = self.section.coeff_count
        n = m.vertex_count
        if len(m.rods) != 1 or m.rods[0].closed or self.dof_count != n * nk:
            raise ValueError("sections slide along a single open deformable rod only")
        src = np.arange(n) - int(k)
        ok = (src >= 0) & (src < n)
        last_edge = m.edge_count - 1
        store_new = np.minimum(np.arange(n), last_edge)
        store_old = np.minimum(np.clip(src, 0, n - 1), last_edge)
        t_new, d1_new = new_frames[0][store_new], new_frames[1][store_new]
        d1_old = old_frames[1][store_old] @ rotation.T
        d1_old -= np.einsum("ij,ij->i", d1_old, t_new)[:, None] * t_new
        angle = np.arctan2(np.einsum("ij,ij->i", np.cross(d1_old, d1_new), t_new),
                           np.einsum("ij,ij->i", d1_old, d1_new))
        old = extra.reshape(n, nk)
        out = np.zeros((n, nk))
        out[ok] = _rotate(old[src[ok]], self.modes, angle[ok])
        return out.ravel()

    def _section_edge_terms(self, extra: np.ndarray, m_ref: np.ndarray, rest: np.ndarray
                            ) -> tuple[np.ndarray, ...]:
        """Per deformable edge (``_section_edges``) the pieces of the section energy: its end
        twist [rad], alpha and beta [N/m] per coefficient, its vertices' first dofs among
        the term's and their (E, K) dof indices, and c_0, c_1, c_1' = Q^T c_1 [m]."""
        k = self.section.coeff_count
        e = self._section_edges
        h = rest[e]
        twist = self.end_twist(m_ref)[e]
        # per edge and coefficient: alpha = k h / 3 + g / h, beta = k h / 6 - g / h
        alpha = self.mode_stiff[e] * h[:, None] / 3.0 + self.grad_stiff[e] / h[:, None]
        beta = self.mode_stiff[e] * h[:, None] / 6.0 - self.grad_stiff[e] / h[:, None]
        off0 = self.vertex_offset[self._ev[e, 0]]
        off1 = self.vertex_offset[self._ev[e, 1]]
        idx0 = off0[:, None] + np.arange(k)
        idx1 = off1[:, None] + np.arange(k)
        c0 = extra[idx0]
        c1 = extra[idx1]
        c1r = _rotate(c1, self.modes, twist, transpose=True)  # c_1' = Q^T c_1
        return twist, alpha, beta, off0, off1, idx0, idx1, c0, c1, c1r

    def section_energy(self, extra: np.ndarray, m_ref: np.ndarray, rest: np.ndarray,
                       want_grad: bool, want_hess: bool
                       ) -> tuple[float, np.ndarray | None, tuple | None]:
        """Mode and axial-gradient energy [J] of the vertex sections ``extra`` [m] at edge
        rest lengths ``rest`` [m] and joint reference twists ``m_ref`` [rad] (module
        docstring), its gradient over ``extra`` and its Hessian COO over the term's dofs."""
        k = self.section.coeff_count
        e = self._section_edges
        grad = np.zeros(extra.size) if (want_grad or want_hess) else None
        if e.size == 0:
            empty = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))
            return 0.0, grad, (empty if want_hess else None)
        twist, alpha, beta, off0, off1, idx0, idx1, c0, c1, c1r = self._section_edge_terms(
            extra, m_ref, rest)
        energy = float(np.sum(0.5 * alpha * (c0 * c0 + c1 * c1) + beta * c0 * c1r))
        if grad is not None:
            np.add.at(grad, idx0, alpha * c0 + beta * c1r)
            np.add.at(grad, idx1, alpha * c1 + beta * _rotate(c0, self.modes, twist))
        coo = None
        if want_hess:
            # per mode: alpha I on (c0, c0) and (c1, c1), beta Q^T on (c0, c1), beta Q on
            # (c1, c0); Q = [[cos, sin], [-sin, cos]] of n m
            ang = self.modes[None, :] * twist[:, None]
            cs, sn = np.cos(ang), np.sin(ang)
            a_n = alpha[:, 0::2]
            b_n = beta[:, 0::2]
            base0 = off0[:, None] + 2 * np.arange(k // 2)[None, :]
            base1 = off1[:, None] + 2 * np.arange(k // 2)[None, :]
            zero = np.zeros_like(a_n)
            rows, cols, vals = [], [], []
            for r_i, c_i, blk in ((base0, base0, (a_n, zero, zero, a_n)),
                                  (base1, base1, (a_n, zero, zero, a_n)),
                                  (base0, base1, (b_n * cs, -b_n * sn, b_n * sn, b_n * cs)),
                                  (base1, base0, (b_n * cs, b_n * sn, -b_n * sn, b_n * cs))):
                for (dr, dc), val in zip(((0, 0), (0, 1), (1, 0), (1, 1)), blk, strict=True):
                    rows.append((r_i + dr).ravel())
                    cols.append((c_i + dc).ravel())
                    vals.append(val.ravel())
            coo = (np.concatenate(rows), np.concatenate(cols), np.concatenate(vals))
        return energy, grad, coo

    # -- contact between deformed boundaries ---------------------------------------------
    def _partition_reach(self, x: np.ndarray, e: np.ndarray, length: np.ndarray,
                         radius: np.ndarray) -> np.ndarray:
        """How far [m] past its vertices each edge (vectors ``e``, lengths ``length`` [m]
        at positions ``x``) has its partition weight reach along its axis within
        ``radius`` [m] of it (the kernels' ``reach_range``): half an edge on a straight
        rod, more on the outside of a bend. A chord at more than 78 degrees to its edge (a
        vertex turning by more than about 157 degrees, a rod folded through itself) is
        taken at 78 degrees."""
        ev = self._ev
        t = e / length[:, None]
        nb = self.edge_neighbour
        prev = np.where(nb[:, :1] >= 0, x[np.maximum(nb[:, 0], 0)], 2.0 * x[ev[:, 0]] - x[ev[:, 1]])
        nxt = np.where(nb[:, 1:] >= 0, x[np.maximum(nb[:, 1], 0)], 2.0 * x[ev[:, 1]] - x[ev[:, 0]])
        out = np.zeros(e.shape[0])
        for c in (x[ev[:, 1]] - prev, nxt - x[ev[:, 0]]):
            norm = np.linalg.norm(c, axis=1)
            along = np.maximum(np.einsum("ij,ij->i", t, c), 0.2 * norm)
            across = np.linalg.norm(np.cross(c, t), axis=1)
            out = np.maximum(out, (0.25 * norm**2 + radius * across) / along)
        return out

    def _margins(self, x: np.ndarray, extra: np.ndarray, rest: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Each edge's reach [m]: its largest boundary radius (the rest radius grown by 10 %
        for compression, plus 1.5 times its vertices' mode amplitudes, sum_n sqrt(a_n^2 +
        b_n^2), each) and how far its partition weight reaches past its vertices within
        that radius (:meth:`_partition_reach`: half its length on a straight rod); and that
        last part alone, in rest arc [m]."""
        ev = self._ev
        e = x[ev[:, 1]] - x[ev[:, 0]]
        length = np.linalg.norm(e, axis=1)
        lam = length / rest
        if self.rod_mean is not None:
            lam = np.minimum(lam, self.rod_mean.stretch(x, rest))
        reach = 1.1 * self.edge_r0 * np.maximum(1.0, lam ** (-self.edge_nu))
        if extra.size:
            k = self.section.coeff_count
            vsum = np.zeros(self.model.vertex_count)
            pairs = extra.reshape(-1, k // 2, 2)
            vsum[~self.vertex_rigid] = np.sqrt(np.sum(pairs * pairs, axis=2)).sum(axis=1)
            reach += 1.5 * (vsum[ev[:, 0]] + vsum[ev[:, 1]])
        past = self._partition_reach(x, e, length, reach)
        return reach + past, past * rest / length

    def _candidates(self, x: np.ndarray, extra: np.ndarray, rest: np.ndarray
                    ) -> tuple[wp.array, wp.array, wp.array, wp.array]:
        broad = self.broad_phase
        wx = broad.x_in.put(x)
        arcs, rod_len = broad.arcs(rest)
        margins, past_arc = self._margins(x, extra, rest)
        margin = self._in_margin.put(margins)
        # A sample's projection reaches past a partner edge's vertices (half an edge on a
        # straight rod): keep pairs whose edges lie up to that much (in rest arc) inside
        # the exclusion window.
        reach = float(np.max(past_arc)) / float(np.min(self.exclusion))
        pairs = broad.candidates(wx, broad.zero_dx, margin, arcs, rod_len,
                                 window=max(0.0, self.settings.candidate_window - reach))
        return wx, pairs, arcs, rod_len

    def _launch(self, kernel: wp.Kernel, wx: wp.array, pairs: wp.array,
                data: list[wp.array], derivatives: bool = False, report: bool = False,
                slots: np.ndarray | None = None, block_count: int = 0
                ) -> dict[str, np.ndarray]:
        """Launch ``kernel`` over both passes of ``pairs`` with the state arrays ``data``
        (coefficients, frames, end twists, rest lengths, arcs, rod lengths); with
        ``derivatives``, the Hessian goes into ``block_count`` node-pair blocks, pair p's
        72 at ``slots[p]`` (36 per pass, :meth:`_pass_nodes`). On a CPU the pairs are split into
        :func:`pair_chunks`, launched on as many threads."""
        dev = self.device
        f64 = wp.float64
        threads = 2 * pairs.shape[0]
        nl = 18 + 4 * self.section.coeff_count
        ng = len(self.settings.gauss[0])
        ns = ng * self.section.samples if report else 0
        with_lam = derivatives and self.rod_mean is not None
        energy = wp.zeros(threads, dtype=f64, device=dev)
        grad = wp.zeros(threads * nl if derivatives else 1, dtype=f64, device=dev)
        s_pen = wp.zeros(max(threads * ns, 1), dtype=f64, device=dev)
        s_wt = wp.zeros(max(threads * ns, 1), dtype=f64, device=dev)
        dlam = wp.zeros(2 * threads if with_lam else 1, dtype=f64, device=dev)
        tcol = wp.zeros(2 * threads * nl if derivatives else 1, dtype=f64, device=dev)
        b = 3 + self.section.coeff_count
        w_slots = wp.array(slots.astype(np.int32).ravel() if derivatives else np.zeros(1, np.int32),
                           dtype=wp.int32, device=dev)
        coeff, rest, lam = data[0], data[4], data[-1]
        nv, ne = self.model.vertex_count, self.model.edge_count
        wp.launch(sk.section_bounds, nv + ne, [*self._bounds_args, wx, coeff, rest, lam],
                  [self._vertex_amp, self._edge_rbase], device=dev)
        npairs = pairs.shape[0]
        chunks = (pair_chunks(npairs) if wp.get_device(dev).is_cpu else [(0, npairs)])
        order = None
        if len(chunks) > 1:
            # Chunk c takes every C-th pair from c: the pairs in contact come in runs (a
            # crossing's edges are neighbours), which contiguous chunks would give to one
            # thread.
            order = interleaved(npairs, len(chunks))
            buf = wp.array(pairs.numpy()[order], dtype=wp.vec2i, device=dev)
            if derivatives:
                w_slots = wp.array(slots.astype(np.int32)[order].ravel(), dtype=wp.int32,
                                   device=dev)
        else:
            buf = self.broad_phase.buffer_of(pairs)
        # Each chunk adds its Hessian into blocks of its own (summed below in chunk
        # order, so that the result does not depend on which thread ends first).
        blocks = [wp.zeros(block_count * b * b if derivatives else 1, dtype=f64, device=dev)
                  for _ in chunks]

        def run(i: int) -> None:
            lo, hi = chunks[i]

            def part(a: wp.array, per: int, used: bool = True) -> wp.array:
                # chunk i's view of a per-pair array (an unused one is a 1-entry stub)
                return a[per * lo:per * hi] if used else a

            wp.launch(kernel, 2 * (hi - lo),
                      [*self._model_args, wx, *data, self._vertex_amp, self._edge_rbase,
                       part(buf, 1), part(w_slots, 72, derivatives)],
                      [part(energy, 2), part(grad, 2 * nl, derivatives), blocks[i],
                       part(s_pen, 2 * ns, report), part(s_wt, 2 * ns, report),
                       part(dlam, 4, with_lam), part(tcol, 4 * nl, derivatives)],
                      device=dev)

        if len(chunks) > 1 and kernel.key in self._launched:
            pending = [_chunk_pool().submit(run, i) for i in range(1, len(chunks))]
            run(0)
            for job in pending:
                job.result()
        else:
            # the first launch of a kernel loads its module: not from two threads at once
            for i in range(len(chunks)):
                run(i)
            self._launched.add(kernel.key)

        def unpermuted(a: wp.array, width: int) -> np.ndarray:
            """Pass outputs (``width`` numbers per pass) back in the pairs' order."""
            flat = a.numpy().reshape(npairs, 2 * width)
            if order is None:
                return flat.reshape(-1, width)
            back = np.empty_like(flat)
            back[order] = flat
            return back.reshape(-1, width)

        out = {"energy": unpermuted(energy, 1).ravel()}
        if derivatives:
            out["grad"] = unpermuted(grad, nl)
            total = blocks[0].numpy()
            for more in blocks[1:]:
                total = total + more.numpy()
            out["blocks"] = total.reshape(block_count, b, b)
            out["twist_col"] = unpermuted(tcol, 2 * nl)
        if with_lam:
            out["dlam"] = unpermuted(dlam, 2)
        if report:
            out["pen"] = unpermuted(s_pen, ns).reshape(threads, ng, self.section.samples)
            out["weight"] = unpermuted(s_wt, ns).reshape(threads, ng, self.section.samples)
        return out

    def _state_arrays(self, extra: np.ndarray, t_ref: np.ndarray, d1_ref: np.ndarray,
                      m_ref: np.ndarray, rest: np.ndarray, arcs: wp.array,
                      rod_len: wp.array, x: np.ndarray) -> list[wp.array]:
        """The kernels' Data-in arrays after the positions (``x`` [m]: the boundaries'
        centres, whose rods' mean stretch thins the sections with ``thinning="rod"``)."""
        lam = (self.rod_mean.stretch(x, rest) if self.rod_mean is not None
               else np.zeros(1))
        return [self._in_coeff.put(extra if extra.size else np.zeros(1)),
                self._in_t.put(t_ref), self._in_d1.put(d1_ref),
                self._in_twist.put(self.end_twist(m_ref)), self._in_rest.put(rest), arcs,
                rod_len, self._in_lam.put(lam)]

    def _rod_sums(self, pairs: np.ndarray, dlam: np.ndarray) -> np.ndarray:
        """G_r = dE/ds_r [J] per rod: the passes' dE/dlam (``dlam``, (2 P, 2): each pass's
        A and B side, pass 2p taking ``pairs[p]`` as (A, B) and 2p + 1 as (B, A)) summed
        over the rods of their edges."""
        nrod = len(self.model.rods)
        rod_of = np.asarray(self.model.edge_rod, dtype=np.int64)
        order = _pass_edges(pairs)
        return (np.bincount(rod_of[order[:, 0]], dlam[:, 0], nrod)
                + np.bincount(rod_of[order[:, 1]], dlam[:, 1], nrod))

    def _rod_mean_low_rank(self, geo: dict[str, np.ndarray], wx: wp.array, wp_act: wp.array,
                           data: list[wp.array], slots: np.ndarray, block_count: int,
                           act_pairs: np.ndarray, dofs: np.ndarray
                           ) -> tuple[np.ndarray, np.ndarray]:
        """The dense part of the Hessian through the rods' mean stretches s_r
        (``thinning="rod"``; the chain rule of :mod:`tightknot.contact.rod_mean_radius`,
        ``geo`` its :meth:`~tightknot.contact.rod_mean_radius.RodMeanRadius.radii`):
        U C U^T with U = [grad s_r .., w_r ..] over the extended dofs and C = [[S, I], [I,
        0]], w_r = d(grad E)/ds_r at fixed dofs and S_rq = d^2 E / ds_r ds_q. Both come from
        central differences of the derivative kernel in each deformable rod's stretch
        (step 1e-6: truncation 1e-12, round-off 1e-10 of the entries)."""
        m = self.model
        rod_of = np.asarray(m.edge_rod, dtype=np.int64)
        lam = geo["s"][rod_of]
        rods = sorted({int(r) for r in rod_of[act_pairs.ravel()]
                       if not self.edge_rigid[m.rods[int(r)].edge_slice.start]})
        ext = m.dof_count + self.dof_count
        keep = dofs >= 0
        eps = 1e-6
        w_cols, s_cols = [], []
        for r in rods:
            sides = []
            for sign in (1.0, -1.0):
                lam_r = lam.copy()
                lam_r[rod_of == r] += sign * eps
                out = self._launch(sk.DERIVATIVES, wx, wp_act,
                                   [*data[:-1], self._in_lam_fd.put(lam_r)], derivatives=True,
                                   slots=slots, block_count=block_count)
                # the gradient at fixed stretch (the chain term G grad s is not in w)
                full = np.bincount(dofs[keep], weights=out["grad"][keep], minlength=ext)
                sides.append((full, self._rod_sums(act_pairs, out["dlam"])))
            w_cols.append((sides[0][0] - sides[1][0]) / (2.0 * eps))
            s_cols.append((sides[0][1] - sides[1][1]) / (2.0 * eps))
        k = len(rods)
        s_mat = np.array([[s_cols[j][rods[i]] for j in range(k)] for i in range(k)])
        s_mat = 0.5 * (s_mat + s_mat.T)
        grads = np.zeros((ext, k))
        grads[:m.dof_count] = self.rod_mean.stretch_columns(geo, np.array(rods))
        u = np.column_stack([grads, *w_cols])
        c = np.block([[s_mat, np.eye(k)], [np.eye(k), np.zeros((k, k))]])
        return u, c

    def _add_stretch_blocks(self, hess: BlockHessian, geo: dict[str, np.ndarray],
                            big_g: np.ndarray) -> None:
        """Add sum_r G_r Hess s_r (:meth:`~tightknot.contact.rod_mean_radius.RodMeanRadius.
        stretch_blocks`, one 6 x 6 block per edge) to ``hess``'s position blocks
        (``thinning="rod"``). Only the deformable edges' rods have G_r != 0 (a rigid
        section does not thin), and their end pairs are among the blocks (the section
        energy's)."""
        nodes = self.model.vertex_count
        ev = self._ev[self._section_edges]
        blk = self.rod_mean.stretch_blocks(geo, big_g)[self._section_edges]
        hk = hess.keys[:, 0] * nodes + hess.keys[:, 1]
        for r in range(2):
            for c in range(2):
                slot = np.searchsorted(hk, ev[:, r] * nodes + ev[:, c])
                np.add.at(hess.blocks[:, :3, :3], slot,
                          blk[:, 3 * r:3 * r + 3, 3 * c:3 * c + 3])

    def _pass_nodes(self, pairs: np.ndarray) -> np.ndarray:
        """The vertices of each pass (2 P, 6): A's two, B's two, and B's neighbours on its
        rod (-1 at an open end); pass 2p takes (a, b), pass 2p + 1 takes (b, a)."""
        ev = self._ev
        order = _pass_edges(pairs)
        return np.concatenate([ev[order[:, 0]], ev[order[:, 1]],
                               self.edge_neighbour[order[:, 1]]], axis=1)

    def _pass_dofs(self, pairs: np.ndarray) -> np.ndarray:
        """Extended dofs (model dofs, then model.dof_count + the term's) of each pass's
        local dofs (2 P, L): pass 2p takes (a, b), pass 2p + 1 takes (b, a); -1 for the
        coefficients of a rigid section and for a neighbour past an open end."""
        m = self.model
        k = self.section.coeff_count
        nodes = self._pass_nodes(pairs)
        verts = nodes[:, :4]
        vdof = m.vertex_dof.astype(np.int64)
        pos = (vdof[verts][:, :, None] + np.arange(3)).reshape(-1, 12)
        off = self.vertex_offset[verts]  # (2P, 4)
        sec = np.where(off[:, :, None] >= 0, m.dof_count + off[:, :, None] + np.arange(k), -1)
        nb = nodes[:, 4:]
        near = np.where(nb[:, :, None] >= 0, vdof[np.maximum(nb, 0)][:, :, None] + np.arange(3),
                        -1).reshape(-1, 6)
        return np.concatenate([pos, sec.reshape(-1, 4 * k), near], axis=1)

    def contact_energy(self, x: np.ndarray, extra: np.ndarray,
                       frames: tuple[np.ndarray, np.ndarray, np.ndarray], rest: np.ndarray,
                       want_grad: bool, want_hess: bool
                       ) -> tuple[float, np.ndarray | None, np.ndarray | None, tuple | None]:
        """Contact energy [J] of the deformed sections at positions ``x`` [m], vertex
        sections ``extra`` [m] and edge rest lengths ``rest`` [m], carried in the
        ``frames`` (t_ref, d1_ref, m): its gradient over positions (V, 3) and over the
        term's dofs, and its Hessian in node blocks (the section energy's node pairs
        included, zero), all at the end twists of ``m`` held fixed."""
        return self._contact_energy(x, extra, frames, rest, want_grad, want_hess, False)[:4]

    def _contact_energy(self, x: np.ndarray, extra: np.ndarray,
                        frames: tuple[np.ndarray, np.ndarray, np.ndarray], rest: np.ndarray,
                        want_grad: bool, want_hess: bool, twist: bool
                        ) -> tuple[float, np.ndarray | None, np.ndarray | None, tuple | None,
                                   TwistParts | None]:
        """Contact energy [J] of the deformed sections at positions ``x`` [m], vertex
        sections ``extra`` [m] and edge rest lengths ``rest`` [m], carried in the accepted
        ``frames`` (t_ref, d1_ref, m_ref); its gradient over positions (V, 3) and over the
        term's dofs, and its Hessian in node blocks (the section energy's node pairs
        included, zero); with ``twist`` and derivatives, also the derivatives in the end
        twists (:class:`~tightknot.contact.section_twist.TwistParts`, else None)."""
        m = self.model
        rest = np.asarray(rest, dtype=np.float64)
        self.energy.last_rest = rest.copy()
        shifted = self.shift.at(x, rest) if self.shift is not None else None
        if shifted is not None:
            x = shifted.x
        wx, pairs, arcs, rod_len = self._candidates(x, extra, rest)
        data = self._state_arrays(extra, *frames, rest, arcs, rod_len, x)
        npairs = pairs.shape[0]
        g_x = np.zeros((m.vertex_count, 3)) if (want_grad or want_hess) else None
        g_c = np.zeros(self.dof_count) if (want_grad or want_hess) else None
        empty = self._empty_blocks() if want_hess else None
        if npairs == 0:
            self._energy_only = None
            return 0.0, g_x, g_c, empty, None
        derivatives = want_grad or want_hess
        last = self._energy_only
        if (derivatives and last is not None and np.array_equal(last[0], x)
                and np.array_equal(last[1], extra) and np.array_equal(last[2], rest)
                and all(np.allclose(a, b, rtol=0.0, atol=FRAME_MATCH)
                        for a, b in zip(last[3], frames, strict=True))):
            # The Newton loop asks for the derivatives where it last evaluated the energy
            # alone, in the frames carried there (equal to round-off): the pairs in
            # contact are those found then.
            act_pairs = last[4]
            energy = None
        else:
            first = self._launch(sk.ENERGY, wx, pairs, data)
            energy = float(first["energy"].sum())
            active = np.flatnonzero(first["energy"].reshape(-1, 2).sum(axis=1) > 0.0)
            act_pairs = pairs.numpy().astype(np.int64)[active]
            self._energy_only = None
            if not derivatives:
                if math.isfinite(energy):
                    self._energy_only = (x.copy(), np.array(extra, copy=True), rest.copy(),
                                         tuple(np.array(f, copy=True) for f in frames),
                                         act_pairs)
                return energy, g_x, g_c, empty, None
            if not math.isfinite(energy):
                return energy, g_x, g_c, empty, None
        if act_pairs.shape[0] == 0:
            return 0.0 if energy is None else energy, g_x, g_c, empty, None
        wp_act = wp.array(act_pairs.astype(np.int32), dtype=wp.vec2i, device=self.device)
        slots, keys = None, None
        if want_hess:
            nodes = self._pass_nodes(act_pairs)  # (2A, 6)
            # a neighbour past an open end has no rows (the kernel folds it onto B's
            # vertices): its slots name B's first vertex's blocks, which the pass has
            nodes[:, 4:] = np.where(nodes[:, 4:] >= 0, nodes[:, 4:], nodes[:, 2:3])
            pair_keys = (nodes[:, :, None] * m.vertex_count + nodes[:, None, :]).reshape(-1)
            keys, inverse = np.unique(np.concatenate([self._section_keys, pair_keys]),
                                      return_inverse=True)
            slots = inverse[self._section_keys.size:].reshape(-1, 72)
        else:  # a gradient only: the kernel's Hessian goes to one discarded block
            slots = np.zeros((act_pairs.shape[0], 72), dtype=np.int64)
        out = self._launch(sk.DERIVATIVES, wx, wp_act, data, derivatives=True, slots=slots,
                           block_count=1 if keys is None else keys.size)
        if energy is None:
            energy = float(out["energy"].sum())
            if not math.isfinite(energy):
                return energy, g_x, g_c, empty, None
        dofs = self._pass_dofs(act_pairs)  # (2A, L)
        keep = dofs >= 0
        full = np.bincount(dofs[keep], weights=out["grad"][keep],
                           minlength=m.dof_count + self.dof_count)
        g_x = full[m.position_dofs]
        geo = big_g = None
        if self.rod_mean is not None:
            # the chain rule through the rods' mean stretches (rod_mean_radius)
            geo = self.rod_mean.radii(x, rest)
            big_g = self._rod_sums(act_pairs, out["dlam"])
            g_x = g_x + self.rod_mean.chain_gradient(geo, big_g)
        g_c = full[m.dof_count:]
        hess = None
        if want_hess:
            hess = BlockHessian(self._node_dofs,
                                np.stack([keys // m.vertex_count, keys % m.vertex_count], axis=1),
                                out["blocks"])
            if geo is not None:
                self._add_stretch_blocks(hess, geo, big_g)
                hess.low_rank = self._rod_mean_low_rank(geo, wx, wp_act, data, slots,
                                                        keys.size, act_pairs, dofs)
        parts = self._contact_twist_parts(act_pairs, extra, out, dofs) if twist else None
        if shifted is not None:
            # derivatives over the offset centreline carried to the centreline
            if hess is not None:
                hess = shifted.pull_back_hessian(hess, g_x)
            g_x = shifted.pull_back_gradient(g_x)
            if parts is not None:
                parts = self._shifted_twist_parts(parts, shifted)
        return energy, g_x, g_c, hess, parts

    def _shifted_twist_parts(self, parts: TwistParts, shifted: ShiftedCentreline
                             ) -> TwistParts:
        """The contact's twist parts with their columns C_e over the offset centreline's
        positions carried to the centreline's (J^T C_e; the end twists themselves are the
        centreline's, so their first derivatives and M_ef stay)."""
        col = parts.col_dof
        local = self.twist_chain.dof_local[col]
        is_pos = local < 3  # a node's first three dofs are its position
        src, w, c, val = shifted.pull_back_entries(self.twist_chain.dof_node[col[is_pos]],
                                                   local[is_pos], parts.col_value[is_pos])
        pos_dof = self._node_dofs[w, c]
        return TwistParts(parts.first,
                          np.concatenate([parts.col_edge[~is_pos], parts.col_edge[is_pos][src]]),
                          np.concatenate([col[~is_pos], pos_dof]),
                          np.concatenate([parts.col_value[~is_pos], val]),
                          parts.pair_edge, parts.pair_value)

    def _contact_twist_parts(self, act_pairs: np.ndarray, extra: np.ndarray,
                             out: dict[str, np.ndarray], dofs: np.ndarray) -> TwistParts:
        """The contact's derivatives in the end twists (module :mod:`~tightknot.contact.
        section_twist`) from the derivative kernel's outputs ``out`` over the passes of
        ``act_pairs`` (their extended dofs ``dofs``, :meth:`_pass_dofs`)."""
        k = self.section.coeff_count
        nl = 18 + 4 * k
        ev = self._ev
        order = _pass_edges(act_pairs)
        full = self.vertex_sections(extra)
        grad, tcol = out["grad"], out["twist_col"]
        keep = dofs >= 0
        first = np.zeros(self.model.edge_count)
        col_edge, col_dof, col_value, turns, cols = [], [], [], [], []
        for side, node in ((0, 1), (1, 3)):
            # side A's end twist turns its second vertex (local node 1), B's node 3
            e = order[:, side]
            v = turn_direction(full[ev[e, 1]], self.modes)
            coeff = slice(12 + node * k, 12 + (node + 1) * k)
            first += np.bincount(e, np.einsum("pk,pk->p", grad[:, coeff], v),
                                 minlength=first.size)
            col = tcol[:, side * nl:(side + 1) * nl]
            col_edge.append(np.broadcast_to(e[:, None], dofs.shape)[keep])
            col_dof.append(dofs[keep])
            col_value.append(col[keep])
            turns.append(v)
            cols.append(col)
        a1 = slice(12 + k, 12 + 2 * k)
        b1 = slice(12 + 3 * k, 12 + 4 * k)
        m_aa = np.einsum("pk,pk->p", turns[0], cols[0][:, a1])
        m_bb = np.einsum("pk,pk->p", turns[1], cols[1][:, b1])
        m_ab = np.einsum("pk,pk->p", turns[1], cols[0][:, b1])
        a, b = order[:, 0], order[:, 1]
        pair_edge = np.concatenate([np.stack([a, a], axis=1), np.stack([b, b], axis=1),
                                    np.stack([a, b], axis=1), np.stack([b, a], axis=1)])
        return TwistParts(first, np.concatenate(col_edge), np.concatenate(col_dof),
                          np.concatenate(col_value), pair_edge,
                          np.concatenate([m_aa, m_bb, m_ab, m_ab]))

    def _section_twist_parts(self, extra: np.ndarray, m_ref: np.ndarray,
                             rest: np.ndarray) -> TwistParts:
        """The section energy's derivatives in the end twists (its coupling term beta c_0 .
        Q^T c_1 alone depends on them; :meth:`section_energy`)."""
        k = self.section.coeff_count
        e = self._section_edges
        twist, _, beta, _, _, idx0, idx1, c0, _, c1r = self._section_edge_terms(
            extra, m_ref, rest)
        t1 = turn_direction(c1r, self.modes)
        first = np.zeros(self.model.edge_count)
        first[e] = np.sum(beta * c0 * t1, axis=1)
        col0 = beta * t1
        col1 = -beta * turn_direction(_rotate(c0, self.modes, twist), self.modes)
        n2 = np.repeat(self.modes.astype(np.float64) ** 2, 2)
        second = -np.sum(n2 * beta * c0 * c1r, axis=1)
        base = self.model.dof_count
        return TwistParts(first, np.repeat(e, 2 * k),
                          np.concatenate([base + idx0, base + idx1], axis=1).ravel(),
                          np.concatenate([col0, col1], axis=1).ravel(),
                          np.stack([e, e], axis=1), second)

    def _empty_blocks(self) -> BlockHessian:
        """The section energy's node pairs with zero blocks."""
        nodes = self.model.vertex_count
        keys = self._section_keys
        b = 3 + self.section.coeff_count
        return BlockHessian(self._node_dofs, np.stack([keys // nodes, keys % nodes], axis=1),
                            np.zeros((keys.size, b, b)))

    def _add_coo(self, hess: BlockHessian, coo: tuple) -> None:
        """Add a COO Hessian over the term's own dofs into ``hess``'s blocks (its node
        pairs are among them)."""
        rows, cols, vals = coo
        nodes = self.model.vertex_count
        key = self._dof_node[rows] * nodes + self._dof_node[cols]
        hk = hess.keys[:, 0] * nodes + hess.keys[:, 1]
        slot = np.searchsorted(hk, key)
        b = hess.blocks.shape[1]
        flat = hess.blocks.reshape(-1)
        np.add.at(flat, (slot * b + self._dof_local[rows]) * b + self._dof_local[cols], vals)

    # -- measurements ----------------------------------------------------------------------
    def boundary_centres(self, x: np.ndarray, rest: np.ndarray) -> np.ndarray:
        """The centres [m] (V, 3) of the sections' boundaries at positions ``x`` [m] and
        edge rest lengths ``rest`` [m]: the offset centreline with ``bend_shift``, else
        ``x`` itself."""
        if self.shift is None:
            return np.asarray(x, dtype=np.float64)
        return self.shift.at(x, np.asarray(rest, dtype=np.float64)).x

    def sample_passes(self, x: np.ndarray, extra: np.ndarray,
                      frames: tuple[np.ndarray, np.ndarray, np.ndarray], rest: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Every pass of the candidate pairs at the boundaries' centres ``x`` [m] (sections
        ``extra`` [m], ``frames``, edge rest lengths ``rest`` [m]): its sample edge
        (``owner``, A), the partner edge whose surface it samples (``partner``, B), and
        per Gauss circle and boundary sample of A the penetration [m] into B's surface and
        the weight the energy gives it (B's partition of unity times the exclusion ramp;
        0 where the pass skips the sample). Shapes (P,), (P,), (P, G, M), (P, G, M)."""
        wx, pairs, arcs, rod_len = self._candidates(x, extra, rest)
        ng, ms = len(self.settings.gauss[0]), self.section.samples
        if not pairs.shape[0]:
            empty = np.zeros((0, ng, ms))
            return np.zeros(0, np.int64), np.zeros(0, np.int64), empty, empty
        data = self._state_arrays(extra, *frames, rest, arcs, rod_len, x)
        out = self._launch(sk.REPORT, wx, pairs, data, report=True)
        order = _pass_edges(pairs.numpy().astype(np.int64))
        return order[:, 0], order[:, 1], out["pen"], out["weight"]

    def weight_sums(self, x: np.ndarray, extra: np.ndarray,
                    frames: tuple[np.ndarray, np.ndarray, np.ndarray], rest: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
        """At every sample in contact (arguments as :meth:`sample_passes`): the sum of
        its passes' weights, one but inside a rod's exclusion ramp, past an open end or on
        the inside of a partner bent tighter than rho kappa about 0.7
        (docs/sectioned_level.md, "The partner's partition of unity on a bent partner"),
        and its weighted penetration [m]."""
        owner, _, pen, weight = self.sample_passes(x, extra, frames, rest)
        sums, pens = _per_sample(owner, pen, weight, self.model.edge_count)
        touch = pens > 0.0
        return sums[touch], pens[touch]

    def section_report(self, x: np.ndarray, extra: np.ndarray,
                       frames: tuple[np.ndarray, np.ndarray, np.ndarray], rest: np.ndarray
                       ) -> dict[str, np.ndarray]:
        """Per-vertex section outputs of a state (positions ``x`` [m], sections ``extra``
        [m], accepted ``frames``, edge rest lengths ``rest`` [m]), read off the state:

        * ``contact_width_fraction``: L_c, the part of the deformed boundary's length whose
          samples penetrate a partner (any), over the boundary's length, at the vertex's
          edges' Gauss circles (the larger of the vertex's edges);
        * ``peak_pressure_over_E``, ``mean_pressure_over_E``: the traction the energy
          applies at those samples over E, largest and mean: the penalty's slope
          phi'(pen) in each partner edge's pass, weighed by the pass's partition and
          exclusion weights as the energy weighs it, summed over the passes (a sample's
          value, not a patch's mean: docs/fem_crosscheck.md);
        * ``force_per_length``: the contact force per unit rest length [N/m] (sum of the
          samples' tractions times their rest area, over the edge; per edge too,
          ``force_per_length_edges``);
        * ``contact_weight_sum_mean``: over the samples in contact, the sum of each one's
          passes' weights (one along a straight partner, not along a bent one:
          :meth:`weight_sums`), their mean weighed by the weighted penetration (a number;
          None without contact);
        * ``half_width``: L_c pi D0 / 4 [m], the half-width of each of two opposite
          contacts sharing the width;
        * ``area_ratio``: A/A0 = lambda^(-2 nu), lambda the stretch of the vertex's edges
          (their rod's mean with ``thinning="rod"``; the modes keep the area,
          docs/sectioned_level.md);
        * per Gauss circle, where the contact is evaluated: ``circle_contact_width_fraction``
          and ``circle_peak_pressure_over_E`` (edges, circles), ``edge_area_ratio``
          (edges,), ``circle_u`` (circles,: each circle's place along its edge, 0 at its
          first vertex) and ``edge_vertex`` (edges, 2): a profile along a rod at the
          circles' own places (:func:`tightknot.fem.profile_compare.circle_profile`), where
          a vertex's value is the largest of the four circles within 0.79 of an edge of it.
        """
        m = self.model
        rest = np.asarray(rest, dtype=np.float64)
        ev = self._ev
        n_e, n_v = m.edge_count, m.vertex_count
        ng = len(self.settings.gauss[0])
        ms = self.section.samples
        x = self.boundary_centres(x, rest)  # the boundaries' centres and mean stretch
        emod = self.edge_modulus
        press = np.zeros((n_e, ng, ms))
        owner, partner, pen, weight = self.sample_passes(x, extra, frames, rest)
        weight_sum = _weight_sum_mean(owner, pen, weight, n_e)
        if owner.size:
            # The traction the energy applies at a sample: the penalty's slope in each
            # partner edge's pass, weighed as the energy weighs it (the partition of unity
            # over the partner's edges, the exclusion ramp), summed over the passes. The
            # largest pass alone would report a neighbour edge's surface, extended with a
            # small weight, wherever the partner's radius steps at a vertex.
            e_pair = 2.0 * emod[owner] * emod[partner] / (emod[owner] + emod[partner])
            d_pair = self.edge_r0[owner] + self.edge_r0[partner]
            penalty = self.penalty * self.penalty_scale  # the kernels' (the homotopy's)
            kappa = (penalty * e_pair / d_pair)[:, None, None]
            onset = (self.section.onset * d_pair)[:, None, None]
            g = np.maximum(pen, 0.0)
            dphi = np.where(g < onset, kappa * g * g / (2.0 * onset),
                            kappa * (g - 0.5 * onset))
            t = np.maximum(weight, 0.0) * dphi
            touch = np.flatnonzero((t > 0.0).any(axis=(1, 2)))  # the passes in contact
            press += _row_sums(owner[touch], t[touch], n_e)
        # the deformed boundary's length element r ds at each sample, per Gauss circle
        c0, c1 = self.edge_sections(extra, frames[2])
        phis = 2.0 * math.pi * (np.arange(ms) + 0.5) / ms
        npk = np.outer(phis, self.modes)
        basis = np.empty((ms, self.section.coeff_count))
        slope = np.empty_like(basis)
        basis[:, 0::2], basis[:, 1::2] = np.cos(npk), np.sin(npk)
        slope[:, 0::2], slope[:, 1::2] = -self.modes * np.sin(npk), self.modes * np.cos(npk)
        length = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1)
        lam = (length / rest if self.rod_mean is None
               else self.rod_mean.stretch(x, rest))
        big_r0 = self.edge_r0 * lam ** (-self.edge_nu)
        in_contact = press > 0.0
        width = np.zeros((n_e, ng))
        for gi, u in enumerate(self.settings.gauss[0]):
            c = (1.0 - u) * c0 + u * c1
            big_r = np.sqrt(np.maximum(big_r0**2 - 0.5 * np.sum(c * c, axis=1), 0.0))
            r = big_r[:, None] + c @ basis.T
            dr = c @ slope.T
            ds = np.sqrt(r * r + dr * dr)
            width[:, gi] = np.sum(ds * in_contact[:, gi], axis=1) / np.sum(ds, axis=1)
        d0 = 2.0 * self.edge_r0
        has = in_contact.any(axis=2)
        mean_p = np.where(has, press.sum(axis=2) / np.maximum(in_contact.sum(axis=2), 1), 0.0)
        g_w = np.asarray(self.settings.gauss[1])
        area_s = self.edge_r0 * 2.0 * math.pi / ms  # rest area per unit rest length
        f_len = area_s * np.einsum("egs,g->e", press, g_w)

        to_vertex = m.vertex_max_of_edges
        stretch_v = m.vertex_mean_of_edges(lam)
        nu_v = np.zeros(n_v)
        nu_v[ev[:, 0]] = self.edge_nu
        nu_v[ev[:, 1]] = self.edge_nu
        lc = to_vertex(width.max(axis=1))
        return {"contact_width_fraction": lc,
                "peak_pressure_over_E": to_vertex(press.max(axis=(1, 2)) / emod),
                "mean_pressure_over_E": to_vertex(mean_p.max(axis=1) / emod),
                "force_per_length": to_vertex(f_len),
                "force_per_length_edges": f_len,
                "contact_weight_sum_mean": weight_sum,
                "half_width": 0.25 * math.pi * to_vertex(d0) * lc,
                "area_ratio": stretch_v ** (-2.0 * nu_v),
                "circle_contact_width_fraction": width,
                "circle_peak_pressure_over_E": press.max(axis=2) / emod[:, None],
                "edge_area_ratio": lam ** (-2.0 * self.edge_nu),
                "circle_u": np.asarray(self.settings.gauss[0], dtype=np.float64),
                "edge_vertex": ev}

    # -- the energy term -----------------------------------------------------------------
    def evaluate(self, x: np.ndarray, rest: np.ndarray, want_grad: bool = True,
                 want_hess: bool = True):
        """Not available: the sectioned level's energy needs its section dofs
        (:meth:`evaluate_with_dofs`, which a :class:`tightknot.solvers.system.RodSystem`
        calls)."""
        raise TypeError("the sectioned contact level is evaluated with its section dofs "
                        "(evaluate_with_dofs)")

    def evaluate_with_dofs(self, x: np.ndarray, extra: np.ndarray,
                           frames: tuple[np.ndarray, np.ndarray, np.ndarray],
                           rest: np.ndarray, want_grad: bool, want_hess: bool,
                           twist: np.ndarray | None = None):
        """Section and contact energy [J] at positions ``x`` [m], vertex sections ``extra``
        [m] and edge rest lengths ``rest`` [m], the sections carried in the accepted
        ``frames`` (t_ref, d1_ref, m_ref); gradients over positions and coefficients;
        Hessian in node blocks over the extended dofs (rods/term.py). ``twist``: the
        reference twist [rad] of the frames carried to ``x`` (the system's trial frames),
        which the sections then turn with, its chain rule in the derivatives
        (:mod:`tightknot.contact.section_twist`; with the bend shift too: the twists are
        the centreline's); None: the accepted ``m_ref``, held."""
        extra = np.asarray(extra, dtype=np.float64)
        rest = np.asarray(rest, dtype=np.float64)
        chain = twist is not None
        if chain:
            frames = (frames[0], frames[1], np.asarray(twist, dtype=np.float64))
        derivatives = want_grad or want_hess
        e_s, g_s, h_s = self.section_energy(extra, frames[2], rest, want_grad, want_hess)
        e_c, g_x, g_c, h_c, parts = self._contact_energy(
            x, extra, frames, rest, want_grad, want_hess, chain and derivatives)
        g_own = None if g_s is None else g_s + g_c
        if want_hess:
            self._add_coo(h_c, h_s)
        if chain and derivatives:
            both = [self._section_twist_parts(extra, frames[2], rest)]
            if parts is not None:
                both.append(parts)
            g_x, h_c = self.twist_chain.apply(x, TwistParts.join(both), g_x,
                                              h_c if want_hess else None)
        return e_s + e_c, g_x, g_own, h_c


def _rotate(c: np.ndarray, modes: np.ndarray, angle: np.ndarray, transpose: bool = False
            ) -> np.ndarray:
    """Rows of coefficients (E, K) turned by Q(angle) per row (Q^T with ``transpose``):
    mode n by n angle (:func:`tightknot.contact.sectioned_reference.mode_rotation`)."""
    ang = modes[None, :] * np.asarray(angle)[:, None]
    cs, sn = np.cos(ang), np.sin(ang)
    if transpose:
        sn = -sn
    a, b = c[:, 0::2], c[:, 1::2]
    out = np.empty_like(c)
    out[:, 0::2] = cs * a + sn * b
    out[:, 1::2] = -sn * a + cs * b
    return out


def _pass_edges(pairs: np.ndarray) -> np.ndarray:
    """Each pass's sample edge A and partner edge B (2 P, 2): pass (thread) 2 p samples pair
    p's first edge against its second, 2 p + 1 the reverse."""
    return np.stack([pairs, pairs[:, ::-1]], axis=1).reshape(-1, 2)


def _per_sample(owner: np.ndarray, pen: np.ndarray, weight: np.ndarray, edge_count: int
                ) -> tuple[np.ndarray, np.ndarray]:
    """Per edge, Gauss circle and sample: the sum of the passes' weights and the weighted
    penetration [m] (the passes of :meth:`SectionedLayer.sample_passes`)."""
    w = np.maximum(weight, 0.0)
    return (_row_sums(owner, w, edge_count),
            _row_sums(owner, w * np.maximum(pen, 0.0), edge_count))


def _row_sums(owner: np.ndarray, values: np.ndarray, count: int) -> np.ndarray:
    """Per row index r < ``count``: the sum of the ``values`` rows whose ``owner`` is r
    (``np.add.at`` into zeros, in the same order, by one ``np.bincount``)."""
    inner = int(np.prod(values.shape[1:], dtype=np.int64))
    idx = (np.asarray(owner, dtype=np.int64)[:, None] * inner + np.arange(inner)).ravel()
    sums = np.bincount(idx, weights=values.reshape(-1), minlength=count * inner)
    return sums.reshape((count,) + values.shape[1:])


def _weight_sum_mean(owner: np.ndarray, pen: np.ndarray, weight: np.ndarray,
                     edge_count: int) -> float | None:
    """The mean over the samples in contact of their passes' weight sums, weighed by their
    weighted penetration (None without contact)."""
    if not owner.size:
        return None
    sums, pens = _per_sample(owner, pen, weight, edge_count)
    total = float(pens.sum())
    return float((sums * pens).sum() / total) if total > 0.0 else None
