"""The sectioned contact level: the NumPy oracle's derivatives against finite differences,
the Warp kernels against the oracle, the section field's energies, the level inside a rod
system, bad input."""

import copy
import dataclasses
import math

import numpy as np
import pytest
import warp as wp

from tightknot.contact import sectioned
from tightknot.contact import sectioned_kernels as sk
from tightknot.contact.section_modes import mode_stiffness
from tightknot.contact.section_squeeze import rounded_penalty
from tightknot.contact.sectioned import SectionedLayer, SectionSettings
from tightknot.contact.sectioned_reference import (
    EdgeSection,
    PairSettings,
    mode_rotation,
    pair_terms,
)
from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material
from tightknot.rods.state import State
from tightknot.rods.term import BlockHessian
from tightknot.solvers.linear import SparseDirect
from tightknot.solvers.system import RodSystem

MODES = np.arange(2, 9)
K = 2 * MODES.size
GAUSS = (np.array([0.5 - 0.5 / math.sqrt(3.0), 0.5 + 0.5 / math.sqrt(3.0)]),
         np.array([0.5, 0.5]))


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _bend(x0: np.ndarray, x1: np.ndarray, towards: np.ndarray, angle: float
          ) -> tuple[np.ndarray, np.ndarray]:
    """The neighbours of edge x0 x1 on a rod that turns by ``angle`` [rad] at each vertex
    towards ``towards`` (their edges as long as this one, 0.9 and 1.1 times)."""
    e = x1 - x0
    t = _unit(e)
    n = _unit(towards - (towards @ t) * t)
    return (x0 - 0.9 * (math.cos(angle) * e + math.sin(angle) * np.linalg.norm(e) * n),
            x1 + 1.1 * (math.cos(angle) * e + math.sin(angle) * np.linalg.norm(e) * n))


def _pair(seed: int = 1, bend: float = 0.0) -> tuple[EdgeSection, EdgeSection]:
    """Two short crossing edges of unit-diameter rods overlapping by about 0.03 D, with
    random sections, frames carried from slightly different accepted tangents and a
    reference twist to the next edge's frame (D = 1: lengths in diameters). With ``bend``
    [rad], each edge's rod turns by that much at its vertices, towards the other rod
    (b's neighbours 0.9 and 1.1 edges long)."""
    rng = np.random.default_rng(seed)

    def edge(x0: np.ndarray, x1: np.ndarray, arc: tuple[float, float]) -> EdgeSection:
        t = _unit(x1 - x0 + 0.02 * rng.normal(size=3))
        return EdgeSection(x0=x0, x1=x1, t_ref=t, d1_ref=_unit(np.cross(t, rng.normal(size=3))),
                           coeffs0=0.01 * rng.normal(size=K), coeffs1=0.01 * rng.normal(size=K),
                           twist1=0.3 * rng.normal(), rest=0.97 * float(np.linalg.norm(x1 - x0)),
                           r0=0.5, arc=arc)

    a = edge(np.array([-0.05, 0.0, 0.0]), np.array([0.05, 0.01, 0.0]), (0.0, 0.1))
    b = edge(np.array([0.01, -0.04, 0.985]), np.array([-0.01, 0.06, 1.0]), (3.0, 3.1))
    if bend:
        a.x_prev, a.x_next = _bend(a.x0, a.x1, np.array([0.0, 0.0, 1.0]), bend)
        b.x_prev, b.x_next = _bend(b.x0, b.x1, np.array([0.0, 0.0, -1.0]), bend)
    return a, b


SETTINGS = PairSettings(modes=MODES, gauss_xi=GAUSS[0], gauss_w=GAUSS[1], samples=32,
                        kappa=1000.0, onset=1e-4)


def _near(e: EdgeSection) -> list[np.ndarray]:
    """An edge's neighbouring vertices (the ghosts' positions where it has none)."""
    return [2.0 * e.x0 - e.x1 if e.x_prev is None else e.x_prev,
            2.0 * e.x1 - e.x0 if e.x_next is None else e.x_next]


def _pack(a: EdgeSection, b: EdgeSection) -> np.ndarray:
    return np.concatenate([a.x0, a.x1, b.x0, b.x1, a.coeffs0, a.coeffs1, b.coeffs0,
                           b.coeffs1, *_near(a), *_near(b)])


def _unpack(a: EdgeSection, b: EdgeSection, q: np.ndarray) -> tuple[EdgeSection, EdgeSection]:
    a, b = copy.copy(a), copy.copy(b)
    a.x0, a.x1, b.x0, b.x1 = q[0:3], q[3:6], q[6:9], q[9:12]
    a.coeffs0, a.coeffs1 = q[12:12 + K], q[12 + K:12 + 2 * K]
    b.coeffs0, b.coeffs1 = q[12 + 2 * K:12 + 3 * K], q[12 + 3 * K:12 + 4 * K]
    nb = 12 + 4 * K
    # a ghost neighbour is no dof: it follows its edge's vertices
    for edge, at in ((a, nb), (b, nb + 6)):
        if edge.x_prev is not None:
            edge.x_prev = q[at:at + 3]
        if edge.x_next is not None:
            edge.x_next = q[at + 3:at + 6]
    return a, b


def central_differences(a: EdgeSection, b: EdgeSection, eps: float = 1e-7
                        ) -> tuple[np.ndarray, np.ndarray]:
    """The oracle's gradient and Hessian over the pair's local dofs (:func:`_pack`) by
    central differences (step ``eps``) of its energy and of its gradient."""
    q0 = _pack(a, b)
    g_fd = np.zeros(q0.size)
    h_fd = np.zeros((q0.size, q0.size))
    for i in range(q0.size):
        dq = np.zeros(q0.size)
        dq[i] = eps
        hi = pair_terms(*_unpack(a, b, q0 + dq), SETTINGS)
        lo = pair_terms(*_unpack(a, b, q0 - dq), SETTINGS)
        g_fd[i] = (hi["energy"] - lo["energy"]) / (2 * eps)
        h_fd[:, i] = (hi["grad"] - lo["grad"]) / (2 * eps)
    return g_fd, h_fd


def test_oracle_derivatives_match_finite_differences() -> None:
    a, b = _pair()
    ref = pair_terms(a, b, SETTINGS)
    assert ref["energy"] > 0.0 and ref["pen_a"].max() > 0.01  # a real contact
    g_fd, h_fd = central_differences(a, b)
    # exact: central differences of a C2 energy leave truncation eps^2 and round-off
    # 1e-16 E / eps (measured 3.6e-10 of the largest entry)
    assert np.max(np.abs(ref["grad"] - g_fd)) <= 1e-7 * np.max(np.abs(g_fd))
    pos = slice(0, 12)
    h = ref["hess"]
    # over the vertex positions the Hessian is exact but for the frames' second
    # derivatives by central differences (measured 1.4e-4 of the block here, with 0.027 D of
    # penetration); an omitted term of the positions would be O(1)
    err = np.linalg.norm(h[pos, pos] - h_fd[pos, pos]) / np.linalg.norm(h_fd[pos, pos])
    assert err < 2e-3
    # the sections' rows exact too (measured 5e-6, the differences' own error; 2.5e-3 when
    # the mean radii's second derivatives in the coefficients are left out, terms of
    # relative order pen / R), the whole within the frames' differences (measured 1.6e-4)
    sec = slice(12, None)
    assert np.linalg.norm(h[sec] - h_fd[sec]) / np.linalg.norm(h_fd[sec]) < 1e-4
    assert np.linalg.norm(h - h_fd) / np.linalg.norm(h_fd) < 1e-3


def _pass_to_pair(flip: int) -> np.ndarray:
    """The pair's local dof (oracle order: x_a0, x_a1, x_b0, x_b1, the four vertices'
    coefficients, x_a_prev, x_a_next, x_b_prev, x_b_next) of each local dof of the kernel's
    pass ``flip`` (x_A0, x_A1, x_B0, x_B1, the coefficients, x_Bprev, x_Bnext; pass 1 takes
    A = b)."""
    nb = 12 + 4 * K
    if flip == 0:
        return np.r_[0:nb, nb + 6:nb + 12]
    return np.r_[6:12, 0:6, 12 + 2 * K:12 + 4 * K, 12:12 + 2 * K, nb:nb + 6]


def _kernel_pass(a: EdgeSection, b: EdgeSection, rigid_b: bool, gauss_newton: int = 0
                 ) -> tuple[float, np.ndarray, np.ndarray]:
    """Energy, gradient and Hessian of the pair from the Warp kernel (both passes, node
    blocks unpacked to the pair's local dofs, :func:`_pass_to_pair`); ``gauss_newton``:
    its Gauss-Newton Hessian. Vertices 4 .. 7 are a's and b's neighbours (x_prev, x_next;
    a ghost where the edge has none)."""
    f = wp.float64

    def arr(x, dt):
        return wp.array(np.asarray(x), dtype=dt)

    nl = 18 + 4 * K
    npair = 24 + 4 * K
    phi = 2.0 * np.pi * (np.arange(32) + 0.5) / 32
    offs = [0, K, -1 if rigid_b else 2 * K, -1 if rigid_b else 3 * K, -1, -1, -1, -1]
    near = [[4 if a.x_prev is not None else -1, 5 if a.x_next is not None else -1],
            [6 if b.x_prev is not None else -1, 7 if b.x_next is not None else -1]]
    model = [arr([[0, 1], [2, 3]], wp.vec2i), arr([0, 1], wp.int32), arr([0, 0], wp.int32),
             arr([0.5, 0.5], f), arr([0.5, 0.5], f), arr([1.0, 1.0], f),
             arr([0, int(rigid_b)], wp.int32), arr(offs, wp.int32),
             arr([[int(a.first_open), int(a.last_open)], [int(b.first_open), int(b.last_open)]],
                 wp.vec2i), arr([0.0, 0.0], f), arr(GAUSS[0], f),
             arr(GAUSS[1], f), arr(np.cos(phi), f), arr(np.sin(phi), f), K, 32, 1000.0,
             1e-4, 0, gauss_newton, arr(near, wp.vec2i)]

    def ghost(p, q, other):
        return 2.0 * q - other if p is None else p

    x = arr(np.array([a.x0, a.x1, b.x0, b.x1, ghost(a.x_prev, a.x0, a.x1),
                      ghost(a.x_next, a.x1, a.x0), ghost(b.x_prev, b.x0, b.x1),
                      ghost(b.x_next, b.x1, b.x0)]), wp.vec3d)
    coeff = arr(np.concatenate([a.coeffs0, a.coeffs1, b.coeffs0, b.coeffs1]), f)
    rest, lam = arr([a.rest, b.rest], f), arr([1.0], f)
    bounds = [wp.zeros(8, dtype=f), wp.zeros(2, dtype=f)]  # per vertex, per edge
    wp.launch(sk.section_bounds, 10, [model[0], model[7], model[3], model[4], model[6], K, 0,
                                      x, coeff, rest, lam], bounds)
    # node-pair blocks of the 8 vertices; each pass's 6 nodes (a ghost: B's first vertex)
    nodes = [[0, 1, 2, 3, near[1][0] if near[1][0] >= 0 else 2,
              near[1][1] if near[1][1] >= 0 else 2],
             [2, 3, 0, 1, near[0][0] if near[0][0] >= 0 else 0,
              near[0][1] if near[0][1] >= 0 else 0]]
    slots = np.array([[8 * n + m for n in nd for m in nd] for nd in nodes]).ravel()
    data = [x, coeff,
            arr([a.t_ref, b.t_ref], wp.vec3d), arr([a.d1_ref, b.d1_ref], wp.vec3d),
            arr([a.twist1, b.twist1], f), rest,
            arr([a.arc, b.arc], wp.vec2d), arr([1.0, 1.0], f), lam, *bounds,
            arr([[0, 1]], wp.vec2i), arr(slots, wp.int32)]
    bsz = 3 + K
    outs = [wp.zeros(2, dtype=f), wp.zeros(2 * nl, dtype=f),
            wp.zeros(64 * bsz * bsz, dtype=f), wp.zeros(1, dtype=f), wp.zeros(1, dtype=f),
            wp.zeros(1, dtype=f), wp.zeros(4 * nl, dtype=f)]
    wp.launch(sk.DERIVATIVES, 2, model + data, outs)
    g = outs[1].numpy().reshape(2, nl)
    grad = np.zeros(npair)
    for flip in range(2):
        grad[_pass_to_pair(flip)] += g[flip]
    blocks = outs[2].numpy().reshape(8, 8, bsz, bsz)
    # vertex n's pair dofs: positions, then its coefficients (none for 4 .. 7)
    nb = 12 + 4 * K
    local = [np.r_[3 * n:3 * n + 3, 12 + K * n:12 + K * (n + 1)] for n in range(4)]
    local += [np.r_[nb + 3 * j:nb + 3 * j + 3] for j in range(4)]
    hess = np.zeros((npair, npair))
    for i in range(8):
        for j in range(8):
            rows, cols = local[i], local[j]
            hess[np.ix_(rows, cols)] += blocks[i, j][:rows.size, :cols.size]
    tw = outs[6].numpy().reshape(2, 2, nl)  # pass, side (A, B), pass-local dof
    _kernel_pass.twist = np.zeros((2, 2, npair))
    for flip in range(2):
        for side in range(2):
            _kernel_pass.twist[flip, side, _pass_to_pair(flip)] = tw[flip, side]
    return float(outs[0].numpy().sum()), grad, hess


def _keep(rigid_b: bool) -> np.ndarray:
    """The pair's dofs but a rigid b's coefficients."""
    return (np.r_[0:12 + 2 * K, 12 + 4 * K:24 + 4 * K] if rigid_b
            else np.r_[0:24 + 4 * K])


@pytest.mark.parametrize(("rigid_b", "bend"), [(False, 0.0), (True, 0.0), (False, 0.4),
                                               (True, 0.4)])
def test_kernel_matches_the_oracle(rigid_b: bool, bend: float) -> None:
    # straight rods (the neighbours ghosts) and rods bent 0.4 rad at each vertex towards
    # each other (the partition's chords from real neighbours)
    a, b = _pair(bend=bend)
    b.rigid = rigid_b
    ref = pair_terms(a, b, SETTINGS)
    assert ref["energy"] > 0.0  # a contact (seed 3's deformable pair touches nowhere)
    energy, grad, hess = _kernel_pass(a, b, rigid_b)
    keep = _keep(rigid_b)  # b rigid: no dofs
    # the same formulas in float64, the frames' differences included: round-off only
    # (measured 1e-15 for energy and gradient, 8e-13 for the Hessian)
    assert energy == pytest.approx(ref["energy"], rel=1e-12)
    assert np.max(np.abs(grad[keep] - ref["grad"][keep])) <= 1e-12 * np.max(np.abs(ref["grad"]))
    rh = ref["hess"][np.ix_(keep, keep)]
    assert np.max(np.abs(hess[np.ix_(keep, keep)] - rh)) <= 1e-10 * np.max(np.abs(rh))


@pytest.mark.parametrize("rigid_b", [False, True])
def test_the_gauss_newton_hessian_is_the_penetrations_outer_products(rigid_b: bool) -> None:
    # SectionedLayer.set_gauss_newton: per sample a_s wt phi''(pen) grad(pen) grad(pen)^T,
    # here with the penetrations' gradients by central differences of the oracle's, so
    # positive semidefinite; energy and gradient those of the exact kernel, bit for bit.
    a, b = _pair()
    b.rigid = rigid_b
    q0 = _pack(a, b)
    energy, grad, hess = _kernel_pass(a, b, rigid_b)
    e_gn, g_gn, h_gn = _kernel_pass(a, b, rigid_b, gauss_newton=1)
    assert e_gn == energy and np.array_equal(g_gn, grad)
    ref = pair_terms(a, b, SETTINGS)
    assert ref["energy"] > 0.0
    eps = 1e-7
    jac = np.zeros((2, ref["pen_a"].size, q0.size))
    for i in range(q0.size):
        dq = np.zeros(q0.size)
        dq[i] = eps
        hi = pair_terms(*_unpack(a, b, q0 + dq), SETTINGS, want_hess=False)
        lo = pair_terms(*_unpack(a, b, q0 - dq), SETTINGS, want_hess=False)
        for side, key in enumerate(("pen_a", "pen_b")):
            jac[side, :, i] = (hi[key] - lo[key]) / (2 * eps)
    expected = np.zeros((q0.size, q0.size))
    for side, (edge, key) in enumerate(((a, "a"), (b, "b"))):
        pen, wt = ref[f"pen_{key}"], ref[f"weight_{key}"]
        a_s = 0.5 * np.repeat(GAUSS[1], 32) * edge.rest * edge.r0 * 2.0 * np.pi / 32
        d2phi = rounded_penalty(pen, SETTINGS.kappa, SETTINGS.onset)[2]
        c = np.where((pen > 0.0) & (wt > 0.0), a_s * wt * d2phi, 0.0)
        expected += jac[side].T @ (c[:, None] * jac[side])
    keep = _keep(rigid_b)
    ex = expected[np.ix_(keep, keep)]
    # the penetrations are smooth: their differences carry truncation eps^2 and round-off
    # 1e-16 / eps (measured 5e-10 and 4e-10 of the largest entry)
    assert np.max(np.abs(h_gn[np.ix_(keep, keep)] - ex)) <= 1e-6 * np.max(np.abs(ex))
    # the exact Hessian of this contact is indefinite; the Gauss-Newton one is not
    assert np.linalg.eigvalsh(hess[np.ix_(keep, keep)])[0] < 0.0
    lam = np.linalg.eigvalsh(h_gn[np.ix_(keep, keep)])
    assert lam[0] >= -1e-12 * lam[-1]


def test_kernel_twist_columns_are_the_gradients_derivatives_in_the_end_twists() -> None:
    # The kernel's second derivatives against each edge's end twist (the chain rule's
    # columns, tightknot/contact/section_twist.py) against central differences of the
    # oracle's gradient in that twist: pass 0's A side and pass 1's B side are edge a's.
    a, b = _pair()
    _kernel_pass(a, b, False)
    cols = _kernel_pass.twist
    for edge, own, other in ((a, (0, 0), (1, 1)), (b, (0, 1), (1, 0))):
        col = cols[own] + cols[other]
        eps = 1e-6
        edge.twist1 += eps
        hi = pair_terms(a, b, SETTINGS)["grad"]
        edge.twist1 -= 2 * eps
        lo = pair_terms(a, b, SETTINGS)["grad"]
        edge.twist1 += eps
        fd = (hi - lo) / (2 * eps)
        # the columns carry the Hessian's own error, the frames' differences (measured
        # 4.9e-6 and 2.6e-6, the same at steps 1e-5 to 1e-7); a wrong sign or a missing
        # (n J)^T grad term is O(1)
        assert np.linalg.norm(col - fd) <= 1e-4 * np.linalg.norm(fd)
        assert np.linalg.norm(fd) > 0.0


def _straight_rod(n: int = 20, length: float = 3.0, twist: bool = False
                  ) -> tuple[RodSystem, SectionedLayer]:
    d0 = 0.0085
    b = RodBuilder(twist=twist)
    z = np.linspace(0.0, length * d0, n + 1)
    b.add_rod(np.c_[np.zeros(n + 1), np.zeros(n + 1), z], d0, Material(1.25e6, 0.5, 1160.0))
    model = b.finalize()
    system = RodSystem(model, State.initial(model), BoundaryConditions(model))
    layer = SectionedLayer(model, SectionSettings(max_mode=8))
    system.add_term(layer)
    return system, layer


def test_a_uniform_section_field_has_no_gradient_energy() -> None:
    # A straight rod's frames are parallel (zero reference twist): the same coefficients at
    # every vertex are a uniform field, whose energy is the mode energy alone,
    # sum_n (1/2) k_n (a_n^2 + b_n^2) L (docs/sectioned_level.md).
    system, layer = _straight_rod()
    c = 1e-4 * np.random.default_rng(0).normal(size=K)
    extra = np.tile(c, system.model.vertex_count)
    rest = system.model.edge_rest_length
    e, g, _ = layer.section_energy(extra, system.state.m_ref, rest, True, False)
    k = np.repeat([mode_stiffness(int(n), 1.25e6) for n in MODES], 2)
    assert e == pytest.approx(0.5 * float(np.sum(k * c * c)) * rest.sum(), rel=1e-12)


def test_a_field_turned_with_its_frames_has_no_gradient_energy() -> None:
    # Frames turned by a reference twist m between edges: a shape carried with the frames
    # (each vertex's coefficients in the frame of the edge it starts equal to Q(n m) times
    # the last vertex's) is the same physical field: its gradient energy must vanish. The
    # rod's last vertex is kept in the last edge's own frame.
    system, layer = _straight_rod(n=6)
    m_ref = np.full(system.model.joint_count, 0.3)
    c = 1e-4 * np.random.default_rng(1).normal(size=K)
    rows = [c]
    for _ in range(system.model.vertex_count - 2):
        rows.append(mode_rotation(MODES, 0.3) @ rows[-1])
    rows.append(rows[-1])
    rest = system.model.edge_rest_length
    e, _, _ = layer.section_energy(np.concatenate(rows), m_ref, rest, False, False)
    k = np.repeat([mode_stiffness(int(n), 1.25e6) for n in MODES], 2)
    assert e == pytest.approx(0.5 * float(np.sum(k * c * c)) * rest.sum(), rel=1e-10)


def test_section_energy_derivatives_match_finite_differences() -> None:
    system, layer = _straight_rod(n=8)
    rng = np.random.default_rng(2)
    extra = 1e-4 * rng.normal(size=layer.dof_count)
    m_ref = 0.2 * rng.normal(size=system.model.joint_count)
    rest = system.model.edge_rest_length
    _, g, coo = layer.section_energy(extra, m_ref, rest, True, True)
    h = np.zeros((extra.size, extra.size))
    np.add.at(h, (coo[0], coo[1]), coo[2])
    eps = 1e-9
    g_fd = np.array([(layer.section_energy(extra + eps * d, m_ref, rest, False, False)[0]
                      - layer.section_energy(extra - eps * d, m_ref, rest, False, False)[0])
                     / (2 * eps) for d in np.eye(extra.size)])
    # a quadratic energy: central differences are exact up to round-off
    assert np.max(np.abs(g - g_fd)) <= 1e-6 * np.max(np.abs(g))
    assert np.allclose(h, h.T)
    hv = h @ extra
    assert np.max(np.abs(hv - g)) <= 1e-10 * np.max(np.abs(g))  # E = x^T H x / 2


D0 = 0.0085  # [m]


def _crossing_rods(gap: float, stretch: float, settings: SectionSettings
                   ) -> tuple[RodSystem, SectionedLayer, np.random.Generator]:
    """Two crossing 3 D0 rods with a sectioned level, their axes ``gap`` D0 apart, the
    first one ``stretch`` times its rest length, positions jittered by 1e-4 D0."""
    mat = Material(1.25e6, 0.5, 1160.0)
    b = RodBuilder(twist=False)
    z = np.linspace(-1.5 * D0, 1.5 * D0, 25)
    b.add_rod(np.c_[np.zeros(25), np.zeros(25), z], D0, mat)
    b.add_rod(np.c_[z, np.full(25, gap * D0), np.zeros(25)], D0, mat)
    model = b.finalize()
    rng = np.random.default_rng(0)
    state = State.initial(model)
    state.x[:25] *= np.array([1.0, 1.0, stretch])
    state.x += 1e-4 * D0 * rng.normal(size=state.x.shape)
    system = RodSystem(model, state, BoundaryConditions(model))
    layer = SectionedLayer(model, settings)
    system.add_term(layer)
    return system, layer, rng


def test_the_level_in_a_rod_system_has_a_consistent_gradient_and_hessian() -> None:
    # Two crossing rods pressed 0.01 D0 into each other, sections deformed at random.
    system, _, rng = _crossing_rods(0.99, 1.0, SectionSettings(max_mode=6, samples=32))
    # the Hessian exact but for the frames' differences (measured 6e-6 here; 7e-3 without
    # the mean radii's second derivatives in the coefficients, at a 0.01 D0 overlap)
    check_derivatives(system, D0, rng, hess_tol=1e-4)


@pytest.mark.parametrize("bend_shift", [False, True])
def test_the_sections_turn_with_the_reference_twist_of_the_carried_frames(
        bend_shift: bool) -> None:
    # A bent rod (reference twists that move with its vertices) pressed by a crossing one:
    # the energy the system evaluates turns each section with the reference twist of the
    # frames carried to the trial positions, and its derivatives carry that twist's chain
    # rule (tightknot/contact/section_twist.py). Held at the accepted state's twist instead,
    # the gradient misses it by far more than the tolerance below. With the bend shift the
    # boundaries sit on the offset centreline and the twists stay the centreline's: the
    # chain's columns are carried back through the shift's Jacobian.
    mat = Material(1.25e6, 0.5, 1160.0)
    b = RodBuilder(twist=True)
    s = np.linspace(-1.0, 1.0, 21)
    b.add_rod(np.c_[1.5 * D0 * np.sin(s), 0.3 * D0 * s ** 2, 1.5 * D0 * (1.0 - np.cos(s))],
              D0, mat)
    z = np.linspace(-1.5 * D0, 1.5 * D0, 21)
    b.add_rod(np.c_[np.zeros(21), np.full(21, 0.98 * D0), z], D0, mat)
    model = b.finalize()
    rng = np.random.default_rng(4)
    state = State.initial(model)
    state.x += 1e-3 * D0 * rng.normal(size=state.x.shape)
    system = RodSystem(model, state, BoundaryConditions(model))
    layer = SectionedLayer(model, SectionSettings(max_mode=6, samples=32,
                                                  bend_shift=bend_shift))
    assert (layer.shift is not None and layer.shift.count > 0) == bend_shift
    system.add_term(layer)
    system.state.extra = 0.01 * D0 * rng.normal(size=layer.dof_count)
    system.accept(system.free_vector())  # the frames carried to the jittered positions
    n = system.pattern.n
    u = system.free_vector()
    system.evaluate(u)
    assert system.last_split.extra["contact"] > 0.0
    # the chain's part of the gradient: the held twist's gradient differs by it
    x, extra = system.positions(u), u[n:]
    held = layer.evaluate_with_dofs(x, extra, system.state.frames, system.rest, True,
                                    False)[1]
    chained = layer.evaluate_with_dofs(x, extra, system.state.frames, system.rest, True,
                                       False, twist=system.state.m_ref)[1]
    assert np.linalg.norm(chained - held) > 1e-3 * np.linalg.norm(chained)  # 9e-3 here
    # the gradient exact (measured 2e-9 relative; 2e-3 with the chain's part left out), the
    # Hessian but for the frames' second derivatives, which are differences (measured 1.9e-4)
    check_derivatives(system, D0, rng, hess_tol=2e-3, random_sections=False)


def test_the_twist_chain_keeps_and_grows_the_blocks_marks() -> None:
    # The bend shift's pulled-back Hessian marks the blocks that couple positions only (no
    # structural zeros in the matrix). The chain's entries keep those marks where they stay
    # on positions and mark a block's section rows or columns where they reach them, else
    # the system's matrix would drop them.
    from tightknot.contact.section_twist import TwistChain
    from tightknot.rods.term import BlockHessian

    b = 5  # 3 positions and 2 section dofs per node
    node_dofs = np.arange(3 * b).reshape(3, b)
    chain = TwistChain(np.array([-1]), np.zeros((0, 3), dtype=np.int64),
                       np.array([0, b, 2 * b]), node_dofs, 3 * b)
    blocks = np.zeros((2, b, b))
    blocks[:, :3, :3] = 1.0
    hess = BlockHessian(node_dofs, np.array([[0, 1], [1, 0]]), blocks,
                        np.array([False, False]), np.array([False, False]))
    # (node 0 position, node 1 section), (node 1 position, node 0 position), (node 2
    # position, node 2 position): a column grown, a marked block kept, a new block
    rows = np.array([0, b + 1, 2 * b])
    cols = np.array([b + 3, 2, 2 * b + 2])
    out = chain._merged(hess, rows, cols, np.array([2.0, 3.0, 4.0]))
    assert out.keys.tolist() == [[0, 1], [1, 0], [2, 2]]
    assert out.full_rows.tolist() == [False, False, False]
    assert out.full_cols.tolist() == [True, False, False]
    assert out.blocks[0, 0, 3] == 2.0 and out.blocks[1, 1, 2] == 1.0 + 3.0
    assert out.blocks[2, 0, 2] == 4.0
    # an unmarked Hessian (the level without the shift) stays unmarked: every block whole
    whole = chain._merged(BlockHessian(node_dofs, hess.keys, blocks), rows, cols,
                          np.array([2.0, 3.0, 4.0]))
    assert whole.full_rows is None and whole.full_cols is None


def test_sections_thinned_by_the_rods_mean_stretch_have_an_exact_gradient() -> None:
    # As above, with thinning="rod": every section of a rod thins with its mean stretch,
    # whose chain rule through all the rod's edges is the host's (the kernel's dE/dlam;
    # here 19 % of the contact gradient's norm). The rods press 0.03 D0 into each other:
    # the first one's 5 % stretch thins its radius by 2.5 %.
    system, layer, rng = _crossing_rods(
        0.97, 1.05, SectionSettings(max_mode=6, samples=32, thinning="rod"))
    assert layer.rod_mean.rod_stretch(system.state.x, system.rest)[0] == pytest.approx(
        1.05, rel=1e-3)
    # the Hessian with its dense part through the rods' lengths (central differences of
    # the kernel in each rod's stretch): measured 2e-5 relative here, 3e-4 without it
    check_derivatives(system, D0, rng, hess_tol=1e-4)


def test_derivatives_after_the_energy_alone_reuse_its_pairs() -> None:
    # The Newton loop asks for the derivatives at the trial whose energy it just evaluated
    # alone: contact_energy then takes that evaluation's pairs in contact instead of
    # launching the energy kernel again. The result is that of a fresh evaluation (the
    # same passes; the energy summed over fewer zeros: round-off), and frames that differ
    # (here a reference twist turned by 0.1 rad) launch it again.
    system, layer, rng = _crossing_rods(0.97, 1.0, SectionSettings(max_mode=6, samples=32))
    x, rest, frames = system.state.x, system.rest, system.state.frames
    extra = 0.002 * D0 * rng.normal(size=layer.dof_count)
    fresh = layer.contact_energy(x, extra, frames, rest, True, True)
    kernels = []
    launch = layer._launch

    def counted(kernel, *args, **kw):
        kernels.append(kernel)
        return launch(kernel, *args, **kw)

    layer._launch = counted
    layer.contact_energy(x, extra, frames, rest, False, False)
    reused = layer.contact_energy(x, extra, frames, rest, True, True)
    assert kernels == [sk.ENERGY, sk.DERIVATIVES]
    assert fresh[0] > 0.0 and reused[0] == pytest.approx(fresh[0], rel=1e-12)
    for a, b in ((fresh[1], reused[1]), (fresh[2], reused[2]),
                 (fresh[3].blocks, reused[3].blocks)):
        assert np.array_equal(a, b)
    turned = (frames[0], frames[1], frames[2] + 0.1)
    kernels.clear()
    layer.contact_energy(x, extra, frames, rest, False, False)
    layer.contact_energy(x, extra, turned, rest, True, True)
    assert kernels == [sk.ENERGY, sk.ENERGY, sk.DERIVATIVES]


def test_pass_kernels_split_over_threads_give_the_unsplit_result(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # On a CPU a pass kernel's launch is split into chunks of pairs on threads. Each
    # pass's outputs (energy, gradient, the mean-stretch derivative, the report's samples)
    # are the unsplit launch's bit for bit: a pass is computed by one thread alone, in
    # any chunk. The Hessian blocks are summed chunk by chunk (round-off: 1e-13 relative
    # allowed, a few ulps of the sums of up to a few dozen terms).
    assert sectioned.pair_chunks(31) == [(0, 31)]
    assert sectioned.pair_chunks(33) == [(0, 17), (17, 33)]
    assert np.array_equal(sectioned.interleaved(5, 2), [0, 2, 4, 1, 3])
    system, layer, rng = _crossing_rods(
        0.97, 1.05, SectionSettings(max_mode=6, samples=32, thinning="rod"))
    x, rest, frames = system.state.x, system.rest, system.state.frames
    extra = 0.002 * D0 * rng.normal(size=layer.dof_count)
    monkeypatch.setattr(sectioned, "MIN_CHUNK_PAIRS", 1)
    runs = []
    for chunks in (1, 3):
        monkeypatch.setattr(sectioned, "CPU_CHUNKS", chunks)
        monkeypatch.setattr(sectioned, "_POOL", None)
        sizes = []
        launch = layer._launch

        def counted(kernel, wx, pairs, *args, sizes=sizes, launch=launch, **kw):
            sizes.append(len(sectioned.pair_chunks(pairs.shape[0])))
            return launch(kernel, wx, pairs, *args, **kw)

        layer._launch = counted
        for _ in range(2):  # the second time on the pool's threads (the first loads)
            energy, g_x, g_c, hess = layer.contact_energy(x, extra, frames, rest, True, True)
            report = layer.section_report(x, extra, frames, rest)
        del layer._launch
        assert set(sizes) == {chunks}
        runs.append((energy, g_x, g_c, hess, report))
    (e1, gx1, gc1, h1, r1), (e3, gx3, gc3, h3, r3) = runs
    assert e1 > 0.0 and r1["contact_width_fraction"].max() > 0.0
    assert e3 == pytest.approx(e1, rel=1e-14)
    assert np.array_equal(gx1, gx3) and np.array_equal(gc1, gc3)
    assert np.array_equal(h1.keys, h3.keys)
    assert np.abs(h3.blocks - h1.blocks).max() <= 1e-13 * np.abs(h1.blocks).max()
    for key, value in r1.items():
        assert np.array_equal(value, r3[key]), key


def test_a_grown_pattern_is_the_one_built_afresh() -> None:
    # Node pairs that come into contact within a load step are merged into the kept union
    # of the rods' pattern and the section blocks (RodSystem._own_grow): the matrix is the
    # one a union built afresh over the same pairs gives, pattern and values bit for bit.
    system, _, _ = _crossing_rods(0.995, 1.0, SectionSettings(max_mode=6, samples=32))
    calls = []
    place = system._with_own_hessian

    def recorded(hmat, own):
        calls.append((hmat, own, system._own_pattern))
        return place(hmat, own)

    system._with_own_hessian = recorded
    grow = system._own_grow
    grows = []
    system._own_grow = lambda *a: grows.append(a[2].size) or grow(*a)
    system.evaluate(system.free_vector())
    kept = system._own_pattern["keys"].size
    system.state.x[25:, 1] -= 0.03 * D0  # the second rod pressed 0.035 D0 in
    grown = system.evaluate(system.free_vector())[2]
    cache = system._own_pattern
    assert grows and cache["keys"].size == kept + grows[-1] > kept  # grown, not rebuilt
    hmat, own, _ = calls[-1]
    order = np.argsort(cache["keys"])
    system._own_union(hmat, own.node_dofs, cache["keys"][order], cache["full_rows"][order],
                      cache["full_cols"][order])
    afresh = place(hmat, own)
    for name in ("indptr", "indices", "data"):
        assert np.array_equal(getattr(grown, name), getattr(afresh, name)), name


def test_blocks_that_gain_rows_grow_the_kept_pattern_as_built_afresh() -> None:
    # A kept node pair whose block gains rows or columns past its positions (the bend
    # shift's and the twist chain's partial blocks, BlockHessian.full_rows/full_cols)
    # joins the kept union as a shadow pair with the new entries alone
    # (RodSystem._own_grow): twice in a row (rows, then columns), beside new pairs, the
    # matrix is the one a union built afresh gives, pattern and values bit for bit.
    system, _, rng = _crossing_rods(0.995, 1.0, SectionSettings(max_mode=6, samples=32))
    calls = []
    place = system._with_own_hessian
    system._with_own_hessian = lambda hmat, own: calls.append((hmat, own)) or place(hmat, own)
    system.evaluate(system.free_vector())
    hmat, own = calls[-1]
    n, b = own.keys.shape[0], own.blocks.shape[1]
    every = np.arange(n)

    def hessian(count: int, rows: np.ndarray, cols: np.ndarray) -> BlockHessian:
        return dataclasses.replace(own, keys=own.keys[:count],
                                   blocks=rng.normal(size=(count, b, b)),
                                   full_rows=rows[:count], full_cols=cols[:count])

    def afresh(h: BlockHessian):
        kept, system._own_pattern = system._own_pattern, None
        out = place(hmat, h)
        system._own_pattern = kept
        return out

    rows0, cols0 = every % 3 == 0, every % 4 == 0
    system._own_pattern = None
    place(hmat, hessian(n // 2, rows0, cols0))  # the kept union of half the pairs
    build = system._own_union
    more_rows = rows0 | (every % 2 == 0)
    for rows, cols in ((more_rows, cols0), (more_rows, every >= 0)):
        h = hessian(n, rows, cols)
        system._own_union = None  # growth only: a rebuild fails the test
        grown = place(hmat, h)
        assert system._own_pattern["shadow"].size > 0
        system._own_union = build
        fresh = afresh(h)
        for name in ("indptr", "indices", "data"):
            assert np.array_equal(getattr(grown, name), getattr(fresh, name)), name


def check_derivatives(system: RodSystem, d0: float, rng: np.random.Generator,
                      hess_tol: float = 0.03, random_sections: bool = True) -> None:
    """A rod system with a sectioned level, its sections deformed at random (0.002 D0;
    else the state's): the contact is on, the gradient is exact along three random
    directions (central differences; measured 1e-9 relative) and the Hessian within
    ``hess_tol`` of the differences of the gradient."""
    n = system.pattern.n
    u = system.free_vector()
    if random_sections:
        u[n:] = 0.002 * d0 * rng.normal(size=u.size - n)
    _, g, h = system.evaluate(u)
    assert system.last_split.extra["contact"] > 0.0
    step = 1e-3
    for _ in range(3):
        d = 1e-4 * d0 * rng.normal(size=u.size)
        e_hi = system.evaluate(u + step * d, False, False)[0]
        e_lo = system.evaluate(u - step * d, False, False)[0]
        g_hi = system.evaluate(u + step * d, True, False)[1]
        g_lo = system.evaluate(u - step * d, True, False)[1]
        assert g @ d == pytest.approx((e_hi - e_lo) / (2 * step), rel=1e-6)
        hd = (g_hi - g_lo) / (2 * step)
        assert np.linalg.norm(SparseDirect.matrix(h) @ d - hd) <= hess_tol * np.linalg.norm(hd)


@pytest.mark.parametrize(("kwargs", "word"), [({"max_mode": 3}, "section_modes"),
                                               ({"max_mode": 8.5}, "section_modes"),
                                               ({"samples": 16}, "samples"),
                                               ({"penalty": -1.0}, "penalty"),
                                               ({"onset": 0.5}, "onset"),
                                               ({"thinning": "mean"}, "thinning")])
def test_bad_settings_name_the_option(kwargs: dict, word: str) -> None:
    with pytest.raises(ValueError, match=word):
        SectionSettings(**kwargs)


def test_too_many_modes_for_the_kernels_are_refused() -> None:
    system, _ = _straight_rod(n=4)
    with pytest.raises(ValueError, match="section_modes must be <= 12"):
        SectionedLayer(system.model, SectionSettings(max_mode=13, samples=64))


def _boundary(layer: SectionedLayer, state: State, v: int, phis: np.ndarray) -> np.ndarray:
    """World points [m] of vertex v's section boundary at angles ``phis`` of its frame,
    relative to the vertex (the storage edge's reference frame)."""
    from tightknot.contact.sectioned_reference import mode_basis

    e = min(v, layer.model.edge_count - 1)
    t, d1 = state.t_ref[e], state.d1_ref[e]
    d2 = np.cross(t, d1)
    c = state.extra[layer.vertex_offset[v]:layer.vertex_offset[v] + K]
    r = 0.5 * 0.0085 + mode_basis(MODES, phis)[0] @ c
    return r[:, None] * (np.cos(phis)[:, None] * d1 + np.sin(phis)[:, None] * d2)


def test_sections_slide_and_turn_with_the_material() -> None:
    # A rod on a helix-free bent line: slide the material by 2 edges and turn it about x;
    # each vertex's boundary must arrive turned, two vertices on, whatever the new frames.
    d0 = 0.0085
    n = 12
    s = np.linspace(0.0, 3.0 * d0, n + 1)
    pts = np.c_[s, 0.2 * d0 * np.sin(s / d0), 0.1 * d0 * np.cos(s / d0)]
    b = RodBuilder(twist=False)
    b.add_rod(pts, d0, Material(1.25e6, 0.5, 1160.0))
    model = b.finalize()
    old = State.initial(model)
    layer = SectionedLayer(model, SectionSettings(max_mode=8))
    old.extra = 1e-4 * np.random.default_rng(4).normal(size=layer.dof_count)
    k, ang = 2, 0.7
    rot = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(ang), -math.sin(ang)],
                    [0.0, math.sin(ang), math.cos(ang)]])
    moved = np.empty_like(old.x)
    moved[k:] = old.x[:-k]
    moved[:k] = old.x[0] + (old.x[0] - old.x[1]) * np.arange(k, 0, -1)[:, None]
    new = State.initial(model, positions=moved @ rot.T)
    new.extra = layer.slid_sections(old.extra, (old.t_ref, old.d1_ref),
                                    (new.t_ref, new.d1_ref), k, rot)
    phis = np.linspace(0.0, 2.0 * math.pi, 9)[:-1]
    for v in range(n - 2):  # the last vertices change their storage edge's tangent
        a = _boundary(layer, old, v, phis) @ rot.T
        # the same radius in every direction, each state read in its own frame
        rb = np.array([np.linalg.norm(_boundary_at(layer, new, v + k, p)) for p in a])
        assert np.allclose(np.linalg.norm(a, axis=1), rb, rtol=1e-9), v
    assert np.all(new.extra.reshape(-1, K)[:k] == 0.0)  # no source: round


def _boundary_at(layer: SectionedLayer, state: State, v: int, point: np.ndarray) -> np.ndarray:
    """The boundary point of vertex v's section in the direction of ``point`` (relative)."""
    e = min(v, layer.model.edge_count - 1)
    t, d1 = state.t_ref[e], state.d1_ref[e]
    d2 = np.cross(t, d1)
    phi = math.atan2(point @ d2, point @ d1)
    return _boundary(layer, state, v, np.array([phi]))[0]


def test_the_penalty_scale_scales_the_contact_and_nothing_else() -> None:
    # section_finish's homotopy grows the penalty: the contact energy, its gradient and
    # its Hessian are linear in the penalty (the rounded onset is a length), so at a
    # quarter of it they are a quarter, to round-off; the energy-only evaluation's pairs
    # are not reused across a change; the scale is refused outside (0, 1].
    system, layer, rng = _crossing_rods(0.97, 1.0, SectionSettings(max_mode=6, samples=32))
    x, rest, frames = system.state.x, system.rest, system.state.frames
    extra = 0.002 * D0 * rng.normal(size=layer.dof_count)
    full = layer.contact_energy(x, extra, frames, rest, True, True)
    layer.contact_energy(x, extra, frames, rest, False, False)
    layer.set_penalty_scale(0.25)
    quarter = layer.contact_energy(x, extra, frames, rest, True, True)
    assert full[0] > 0.0 and quarter[0] == pytest.approx(0.25 * full[0], rel=1e-12)
    for a, b in ((full[1], quarter[1]), (full[2], quarter[2]),
                 (full[3].blocks, quarter[3].blocks)):
        assert np.allclose(b, 0.25 * a, rtol=1e-12, atol=1e-12 * np.abs(a).max())
    layer.set_penalty_scale(1.0)
    again = layer.contact_energy(x, extra, frames, rest, True, True)
    assert again[0] == full[0]
    for bad in (0.0, 1.5, float("nan")):
        with pytest.raises(ValueError, match="penalty scale"):
            layer.set_penalty_scale(bad)


@pytest.mark.parametrize("step", [0.0, 0.3])
def test_the_reported_traction_is_the_one_the_energy_applies(step: float) -> None:
    # Rod A crosses rod B over a vertex where B's edges are stretched unevenly (1 - step,
    # 1 + step alternately), so that B's mean radius steps there (by 0.10 D0 at step
    # 0.3). The report's contact force on A, its edges' force per length times their rest
    # lengths, is the force the energy applies to A: each sample's traction is its
    # partner passes' penalty slopes weighed as the energy weighs them. Tolerance: the two
    # half-weight passes see the partner's surface differently (A's report -2.9 % at
    # step 0.3, +1.1 % without a step); the largest pass alone reports a neighbour edge's
    # thicker surface, extended with a small weight, and about twice the force at step 0.3.
    mat = Material(1.25e6, 0.5, 1160.0)
    b = RodBuilder(twist=False)
    z = np.linspace(-1.5 * D0, 1.5 * D0, 25)
    b.add_rod(np.c_[np.zeros(25), np.zeros(25), z], D0, mat)
    s = np.cumsum(np.r_[0.0, (z[1] - z[0]) * (1.0 + step * (-1.0) ** np.arange(24))])
    b.add_rod(np.c_[z, np.full(25, 0.97 * D0), np.zeros(25)], D0, mat)
    model = b.finalize()
    state = State.initial(model)
    state.x[25:, 0] = s - s[12]  # B's middle vertex under A
    system = RodSystem(model, state, BoundaryConditions(model))
    layer = SectionedLayer(model, SectionSettings(max_mode=6, samples=64))
    system.add_term(layer)
    x, rest, frames = system.state.x, system.rest, system.state.frames
    extra = np.zeros(layer.dof_count)
    for scale in (1.0, 0.25):  # and under section_finish's penalty homotopy
        layer.set_penalty_scale(scale)
        _, g_x, _, _ = layer.contact_energy(x, extra, frames, rest, True, False)
        force = float(np.linalg.norm(g_x[:25].sum(axis=0)))
        per_edge = layer.section_report(x, extra, frames, rest)["force_per_length_edges"]
        reported = float(per_edge[:24] @ rest[:24])
        assert force > 0.0
        assert reported == pytest.approx(force, rel=0.05)


def _straight_crossing() -> tuple:
    """Two straight rods of 24 edges crossing at 90 degrees near B's middle vertex, A
    pressed 0.03 D0 into B: the model, its rod system and the sectioned layer (N = 6)."""
    mat = Material(1.25e6, 0.5, 1160.0)
    b = RodBuilder(twist=False)
    z = np.linspace(-1.5 * D0, 1.5 * D0, 25)
    b.add_rod(np.c_[np.full(25, 0.3 * D0 / 12), np.zeros(25), z], D0, mat)
    b.add_rod(np.c_[z, np.full(25, 0.97 * D0), np.zeros(25)], D0, mat)
    model = b.finalize()
    system = RodSystem(model, State.initial(model), BoundaryConditions(model))
    layer = SectionedLayer(model, SectionSettings(max_mode=6, samples=64))
    system.add_term(layer)
    return model, system, layer


def test_on_a_straight_partner_the_passes_weights_sum_to_one() -> None:
    # The partner's surface is blended over its edges by hats that sum to one along a
    # straight partner (the calibration's and the cross-check's straight scenes rely on
    # it; on a bent one they do not: bench/partition_sum.py). Two straight rods crossing
    # over a vertex of B: every sample of A in contact gets weights summing to one.
    model, system, layer = _straight_crossing()
    st = system.state
    owner, partner, pen, weight = layer.sample_passes(st.x, np.zeros(layer.dof_count),
                                                      st.frames, system.rest)
    assert owner.shape == partner.shape and pen.shape == weight.shape == (owner.size, 2, 64)
    assert np.all(model.edge_rod[owner] != model.edge_rod[partner])
    on_a = owner < 24
    sums = np.zeros((24, 2, 64))
    hit = np.zeros((24, 2, 64), dtype=bool)
    np.add.at(sums, owner[on_a], weight[on_a])
    np.logical_or.at(hit, owner[on_a], (pen[on_a] > 0.0) & (weight[on_a] > 0.0))
    assert hit.sum() > 20
    assert np.allclose(sums[hit], 1.0, rtol=0.0, atol=1e-12)
    rep = layer.section_report(st.x, np.zeros(layer.dof_count), st.frames, system.rest)
    assert rep["contact_weight_sum_mean"] == pytest.approx(1.0, abs=1e-12)
    # apart, no sample is in contact: no mean (a summary then has nothing to warn of)
    x_apart = st.x.copy()
    x_apart[25:, 1] += 2.0 * D0
    rep = layer.section_report(x_apart, np.zeros(layer.dof_count), st.frames, system.rest)
    assert rep["contact_weight_sum_mean"] is None


def test_a_vertex_reports_the_largest_of_its_edges_circles() -> None:
    # The report per vertex (the knots' maps, the mid rows of the cross-check) is the
    # largest of the Gauss circles of the vertex's edges; the profiles along the contact
    # read the circles at their own places (tightknot.fem.profile_compare.circle_profile).
    model, system, layer = _straight_crossing()
    st = system.state
    rep = layer.section_report(st.x, np.zeros(layer.dof_count), st.frames, system.rest)
    width = rep["circle_contact_width_fraction"]
    assert width.shape == rep["circle_peak_pressure_over_E"].shape == (model.edge_count, 2)
    assert rep["circle_u"] == pytest.approx([0.5 - 0.5 / 3**0.5, 0.5 + 0.5 / 3**0.5])
    assert np.array_equal(rep["edge_vertex"], model.edge_vertex)
    assert np.count_nonzero(width) >= 4  # the contact spans several circles
    for v in range(model.vertex_count):
        edges = np.flatnonzero((model.edge_vertex == v).any(axis=1))
        assert rep["contact_width_fraction"][v] == width[edges].max()
        assert rep["peak_pressure_over_E"][v] == rep["circle_peak_pressure_over_E"][edges].max()
    lam = (np.linalg.norm(np.diff(st.x[model.edge_vertex], axis=1)[:, 0], axis=1)
           / system.rest)
    assert rep["edge_area_ratio"] == pytest.approx(lam ** -1.0, rel=1e-12)
