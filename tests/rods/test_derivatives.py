"""Gradient and Hessian of the elastic energies against central finite differences.

Each energy (stretch, bend, twist) is checked on its own, by zeroing the stiffness of the
other two in a copy of the model, and together (total), on small rods (5 to 8 vertices) so
the dense difference loops stay fast.

Reference frames. A dof vector q has no frames of its own: as in the solver, the reference
directors at q are carried by time-parallel transport from a base state (Bergou 2010
sec. 4.1, ``ElasticForces.transport_frames``) and the reference twist is measured from them.

* Gradient: central differences of E(q +- h e_k), frames transported from the base state to
  each perturbed point. At the base point this transported reference twist has first
  derivative kb/(2|e|) (Bergou 2010 eq. 9), so the analytic gradient is the exact derivative.
* Hessian: central differences of the analytic gradient, frames transported for each
  perturbed point. The reference-twist gradient kb/(2|e|) evaluated at a point q' is the
  derivative of the twist with frames transported *to q'*, not from the base; transport is
  path dependent, so the gradient field is not the gradient of one function: its Jacobian
  is the (symmetric) Hessian of the energy with frames transported from the base, plus an
  antisymmetric part proportional to the twist m. The analytic Hessian (Jawed et al. 2018)
  is the symmetric part. So the tests compare it with the symmetrised difference Jacobian,
  and check on one case that it also equals second differences of the energy itself (which
  has no such ambiguity).

  The antisymmetric part is not just bounded but predicted: time-parallel transport of an
  edge's director is the Levi-Civita transport of its tangent on the unit sphere, so a small
  loop (a, b) in configuration space turns edge k's director by the solid angle its tangent
  sweeps, Omega_k = t_k . (a_k x b_k) / |e_k|^2 (a_k, b_k: the loop's changes of edge k).
  The reference twist then changes by Omega_1 - Omega_0, which by Stokes is
  a^T (Dw^T - Dw) b for the 1-form w = dm/dq. With the twist energy's gradient
  2 k g m w (+ terms whose antisymmetric parts cancel), the Jacobian's antisymmetric part is
  -k g m (Omega_1 - Omega_0) as a matrix, k g = GJ0/l_bar (l/l_bar)^-q. Its size relative
  to the Hessian is ~m / |kb| (up to 1 here, where theta is random in [-1, 1] rad; ~1e-4
  only when the twist is small), so it is compared with that prediction instead.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import warp as wp

from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.elastic import ElasticForces
from tightknot.rods.material import Material
from tightknot.rods.model import Model
from tightknot.rods.state import State
from tightknot.solvers.pattern import SparsePattern
from tightknot.solvers.system import RodSystem

# Relative step: h = STEP x the shortest edge for positions, STEP rad for twist angles. The
# central-difference truncation error is ~(h/ell)^2 with ell the length over which the
# energy's curvature changes (the edge, or ~0.17 edge next to a 170-degree hairpin):
# ~4e-9 (measured: <= 7e-9 gradient, 1.1e-8 Hessian, at the hairpin); the round-off
# 1e-16 E / h relative to a gradient ~E/ell is ~1e-11.
STEP = 1e-5
# Gradient and Hessian tolerance (relative to the largest entry, since single entries may
# vanish): the brief's 1e-6, two orders above the truncation error above.
REL = 1e-6
# Round-off of an energy evaluation, relative to the energy: a stencil term has a few dozen
# roundings, and a 1e-4 rad bend loses 12 digits in e0 x e1 (|kb| relative error 1e-12).
ROUNDOFF = 1e-11


def rot_z(angle: float) -> np.ndarray:
    """Rotation matrix about z by ``angle`` [rad]."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def chain(turns: list[float], lengths: list[float], lift: float = 0.0) -> np.ndarray:
    """Open polygon whose edges turn by ``turns`` [rad] in the xy plane (each tilted by
    ``lift`` [rad] about the edge normal, alternately, for a non-planar curve)."""
    d = np.array([1.0, 0.0, 0.0])
    pts = [np.zeros(3)]
    for k, ln in enumerate(lengths):
        if k:
            d = rot_z(turns[k - 1]) @ d
        z = lift * (1 if k % 2 else -1)
        e = np.array([d[0] * np.cos(z), d[1] * np.cos(z), np.sin(z)])
        pts.append(pts[-1] + ln * e)
    return np.array(pts)


def configurations() -> dict[str, dict]:
    """Named test configurations: builder arguments plus a rest-length factor."""
    rng = np.random.default_rng(42)
    le = 0.01
    s = np.linspace(0, 2 * np.pi, 6, endpoint=False)
    ring = np.c_[np.cos(s), np.sin(s), 0.3 * np.sin(2 * s)] * 0.01 + 1e-3 * rng.standard_normal(
        (6, 3))
    return {
        "generic": dict(pts=chain([0.5, -0.8, 1.1, 0.3], [le, 1.2 * le, 0.9 * le, le, 1.1 * le],
                                  lift=0.2), nu=0.3, rest=rng.uniform(0.8, 1.2, 5)),
        # Bend angles ~1e-4 rad; not moved off the built shape (move=0), which keeps them.
        "near_straight": dict(pts=chain([1e-4, -1e-4, 1e-4, 1e-4], [le] * 5, lift=1e-4 / 2),
                              nu=0.5, rest=np.full(5, 0.9), move=0.0),
        "hairpin_170deg": dict(pts=chain([np.radians(170), np.radians(-170), np.radians(170)],
                                         [le] * 4, lift=0.05), nu=0.5, rest=np.full(4, 1.1),
                               move=0.0),
        "compressed": dict(pts=chain([0.4, 0.6, -0.5], [le] * 4, lift=0.1), nu=0.0,
                           rest=np.full(4, 1.3)),
        "stretched": dict(pts=chain([0.4, 0.6, -0.5, 0.9], [le] * 5, lift=0.1), nu=0.45,
                          rest=np.full(5, 0.7)),
        "closed": dict(pts=ring, nu=0.3, rest=rng.uniform(0.85, 1.15, 6), closed=True,
                       link=1),
        "no_twist": dict(pts=chain([0.5, -0.8, 1.1], [le] * 4, lift=0.2), nu=0.5,
                         rest=rng.uniform(0.8, 1.2, 4), twist=False),
    }


CONFIGS = configurations()


def only(model: Model, term: str) -> Model:
    """A copy of ``model`` whose energy is ``term`` alone ("total": all three)."""
    zero = {
        "stretch": ("joint_bend_stiffness", "joint_twist_stiffness"),
        "bend": ("edge_mu_area", "joint_twist_stiffness"),
        "twist": ("edge_mu_area", "joint_bend_stiffness"),
        "total": (),
    }[term]
    m = dataclasses.replace(model, wp_arrays={},
                            **{k: np.zeros_like(getattr(model, k)) for k in zero})
    m.upload()
    return m


class Probe:
    """Energy, gradient and Hessian of a model as functions of the full dof vector, frames
    carried from a fixed base state by time-parallel transport."""

    def __init__(self, model: Model, base: State, rest: np.ndarray) -> None:
        self.model, self.base, self.rest = model, base, rest
        self.pattern = SparsePattern(model, np.ones(model.dof_count, dtype=bool))
        self.forces = ElasticForces(model, self.pattern.joint_slot, self.pattern.edge_slot)

    def _eval(self, q: np.ndarray, want_grad: bool, hess: wp.array | None):
        m, b = self.model, self.base
        x = q[m.position_dofs]
        theta = q[m.edge_dof] if m.twist else b.theta
        _, _, m_ref = self.forces.transport_frames(x, b.d1_ref, b.t_ref, b.m_ref)
        return self.forces.evaluate(x, theta, m_ref, self.rest, want_grad, hess)

    def energy(self, q: np.ndarray) -> float:
        return self._eval(q, False, None)[0].total

    def grad(self, q: np.ndarray) -> np.ndarray:
        return self._eval(q, True, None)[1]

    def hess(self, q: np.ndarray) -> np.ndarray:
        data = wp.zeros(self.pattern.nnz, dtype=wp.float64, device=self.model.device)
        self._eval(q, True, data)
        return self.pattern.matrix(data.numpy()).toarray()


def build(cfg: dict) -> tuple[Model, State, np.ndarray, np.ndarray]:
    """Model, base state (moved off the initial frames, random theta), rest lengths, steps."""
    rng = np.random.default_rng(5)
    b = RodBuilder(twist=cfg.get("twist", True))
    closed = cfg.get("closed", False)
    b.add_rod(cfg["pts"], 1e-3, Material(poisson_ratio=cfg["nu"]), closed=closed,
              link_offset=cfg.get("link", 0))
    model = b.finalize()
    st = State.initial(model)
    # Move the vertices a little and carry the frames along, so the base reference twist is
    # neither zero nor the initial one; random theta makes every twist m non-zero.
    le = model.edge_rest_length.min()
    x = st.x + cfg.get("move", 0.02) * le * rng.standard_normal(st.x.shape)
    d1, t, m_ref = ElasticForces(model).transport_frames(x, st.d1_ref, st.t_ref, st.m_ref)
    base = State(x, rng.uniform(-1, 1, model.edge_count), d1, t, m_ref, st.v, st.theta_dot)
    rest = model.edge_rest_length * cfg["rest"]
    h = np.full(model.dof_count, STEP * le)
    if model.twist:
        h[model.edge_dof] = STEP
    return model, base, rest, h


def fd_gradient(energy, q: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Central differences of ``energy``; also returns E(q+h) - E(q-h) per dof."""
    de = np.empty(q.size)
    for k in range(q.size):
        qp, qm = q.copy(), q.copy()
        qp[k] += h[k]
        qm[k] -= h[k]
        de[k] = energy(qp) - energy(qm)
    return de / (2 * h), de


def fd_jacobian(grad, q: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Central differences of the vector function ``grad``: column k is d grad / d q_k."""
    cols = []
    for k in range(q.size):
        qp, qm = q.copy(), q.copy()
        qp[k] += h[k]
        qm[k] -= h[k]
        cols.append((grad(qp) - grad(qm)) / (2 * h[k]))
    return np.stack(cols, axis=1)


def rel_err(a: np.ndarray, b: np.ndarray) -> float:
    """max |a - b| over max |b|."""
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def check_gradient(energy, grad, q: np.ndarray, h: np.ndarray) -> float:
    """Assert the analytic gradient equals central differences; return the relative error."""
    e0 = energy(q)
    g = grad(q)
    g_fd, de = fd_gradient(energy, q, h)
    # Guard: the differences must be far above the energy's round-off, or they measure
    # noise. Every entry that matters (above 1e-3 of the largest) must move E by >= 1e3 x
    # round-off, so its difference keeps >= 3 digits beyond the 1e-6 test.
    noise = ROUNDOFF * abs(e0)
    big = np.abs(g) > 1e-3 * np.max(np.abs(g))
    assert big.any()
    assert np.all(np.abs(de[big]) > 1e3 * noise), np.min(np.abs(de[big])) / noise
    err = rel_err(g_fd, g)
    assert err < REL, err
    return err


def holonomy_antisym(model: Model, base: State, rest: np.ndarray) -> np.ndarray:
    """Predicted antisymmetric part of the Jacobian of the twist gradient at the base state,
    -k g m (Omega_1 - Omega_0) as a (dof_count, dof_count) matrix (module docstring)."""
    n = model.dof_count
    out = np.zeros((n, n))
    if not model.twist:
        return out
    x = base.x
    for j in range(model.joint_count):
        ea, eb = model.joint_edge[j]
        v = model.joint_vertex[j]
        e0, e1 = x[v[1]] - x[v[0]], x[v[2]] - x[v[1]]
        ell, lbar = np.linalg.norm(e0) + np.linalg.norm(e1), rest[ea] + rest[eb]
        kg = (model.joint_twist_stiffness[j] / lbar
              * (ell / lbar) ** -model.joint_thinning_exponent[j])
        m = base.theta[eb] - base.theta[ea] + base.m_ref[j]
        for sign, (va, vb), e in ((-1.0, (v[0], v[1]), e0), (1.0, (v[1], v[2]), e1)):
            t = e / np.linalg.norm(e)
            # a^T M b = t . (a x b) / |e|^2 for edge changes a, b.
            M = -np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]]) / (e @ e)
            E = np.zeros((3, n))  # dofs -> change of this edge vector
            E[:, model.vertex_dof[vb] + np.arange(3)] += np.eye(3)
            E[:, model.vertex_dof[va] + np.arange(3)] -= np.eye(3)
            out += (-kg * m * sign) * (E.T @ M @ E)
    return out


def check_hessian(grad, hess, q: np.ndarray, h: np.ndarray, antisym: np.ndarray):
    """Assert the analytic Hessian equals the symmetric part of the difference Jacobian of
    the analytic gradient, and its antisymmetric part equals ``antisym`` (the transport's
    holonomy; zero for stretch and bend); return both relative errors."""
    H = hess(q)
    # Assembled symmetric up to the rounding order of block sums such as H00 - H01 - H10 + H11
    # (a few ulps of the largest entry).
    assert np.max(np.abs(H - H.T)) <= 1e-14 * np.max(np.abs(H))
    J = fd_jacobian(grad, q, h)
    sym, anti = 0.5 * (J + J.T), 0.5 * (J - J.T)
    err = rel_err(sym, H)
    # Same difference accuracy as the symmetric part, relative to the Hessian's scale.
    err_anti = float(np.max(np.abs(anti - antisym)) / np.max(np.abs(H)))
    assert err < REL, err
    assert err_anti < REL, err_anti
    return err, err_anti


def terms(model: Model) -> list[str]:
    return ["stretch", "bend", "twist", "total"] if model.twist else ["stretch", "bend", "total"]


@pytest.mark.parametrize("name", list(CONFIGS))
def test_gradient_and_hessian(name: str) -> None:
    model, base, rest, h = build(CONFIGS[name])
    q = base.dofs(model)
    for term in terms(model):
        p = Probe(only(model, term), base, rest)
        assert p.energy(q) > 0, term  # the term is present in this configuration
        check_gradient(p.energy, p.grad, q, h)
        with_twist = term in ("twist", "total")
        anti = holonomy_antisym(model, base, rest) if with_twist else 0.0 * np.eye(q.size)
        check_hessian(p.grad, p.hess, q, h, anti)
        if term == "stretch" and model.twist:
            # The stretch does not see the twist angles at all.
            g = p.grad(q)
            assert np.all(g[model.edge_dof] == 0.0)


def test_twist_jacobian_asymmetry_is_real_and_vanishes_without_twist() -> None:
    """The antisymmetric part predicted above is real (a large fraction of the Hessian with
    O(1) twist, so comparing with the plain FD Jacobian would fail), and it vanishes (to
    difference noise) when every joint's twist m is zero."""
    model, base, rest, h = build(CONFIGS["generic"])
    p = Probe(only(model, "twist"), base, rest)
    q = base.dofs(model)
    H = p.hess(q)
    J = fd_jacobian(p.grad, q, h)
    # Measured 0.52 here: four orders above REL, so the plain Jacobian would fail the test.
    assert np.max(np.abs(J - J.T)) / 2 / np.max(np.abs(H)) > 1e-2
    # theta = -m_ref (cumulatively) makes m = 0 at every joint of an open rod.
    q0 = q.copy()
    q0[model.edge_dof] = np.concatenate([[0.0], -np.cumsum(base.m_ref)])
    _, _, m_ref = p.forces.transport_frames(base.x, base.d1_ref, base.t_ref, base.m_ref)
    m = np.diff(q0[model.edge_dof]) + m_ref
    assert np.max(np.abs(m)) < 1e-15  # a few ulps of the O(0.1) reference twists
    H0 = p.hess(q0)
    J0 = fd_jacobian(p.grad, q0, h)
    # 1e-7: difference noise, below the truncation estimate of STEP.
    assert np.max(np.abs(J0 - J0.T)) / 2 / np.max(np.abs(H0)) < 1e-7


def test_hessian_equals_second_differences_of_energy() -> None:
    """Independent of the gradient: H_ij = [E(++) - E(+-) - E(-+) + E(--)] / (4 h_i h_j)
    with frames transported from the base to each point, for the total energy."""
    model, base, rest, h = build(CONFIGS["generic"])
    p = Probe(model, base, rest)
    q = base.dofs(model)
    H = p.hess(q)
    # Second differences: round-off ~1e-16 E / h^2 and truncation ~(h/ell)^2, balanced at
    # h ~ 1e-4 ell, both ~1e-8 relative; 1e-5 leaves a margin for the round-off constant.
    hh = h * 10.0
    n = q.size
    H_fd = np.empty((n, n))
    for i in range(n):
        for j in range(i, n):
            val = 0.0
            for si, sj, w in ((1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)):
                qq = q.copy()
                qq[i] += si * hh[i]
                qq[j] += sj * hh[j]
                val += w * p.energy(qq)
            H_fd[i, j] = H_fd[j, i] = val / (4 * hh[i] * hh[j])
    err = rel_err(H_fd, H)
    assert err < 1e-5, err


def test_free_dofs_with_a_clamp() -> None:
    """RodSystem's free-dof gradient and Hessian (clamped start) against differences of its
    total potential; the system transports frames from its state for each evaluation."""
    cfg = CONFIGS["generic"]
    model, base, rest, h = build(cfg)
    bcs = BoundaryConditions(model).clamp(0, "start")
    st = base.copy()
    system = RodSystem(model, st, bcs)
    system.rest = rest  # pre-stretched, as after a load step with a rest-length change
    u = system.free_vector()
    hu = h[system.pattern.free_dofs]
    assert u.size == model.dof_count - 7  # two vertices and one twist angle clamped

    def energy(v: np.ndarray) -> float:
        return system.evaluate(v, want_grad=False, want_hess=False)[0]

    def grad(v: np.ndarray) -> np.ndarray:
        return system.evaluate(v, want_grad=True, want_hess=False)[1]

    def hess(v: np.ndarray) -> np.ndarray:
        return system.evaluate(v, want_grad=True, want_hess=True)[2].toarray()

    check_gradient(energy, grad, u, hu)
    free = system.pattern.free_dofs
    anti = holonomy_antisym(model, st, rest)[np.ix_(free, free)]
    check_hessian(grad, hess, u, hu, anti)
    # The analytic free Hessian is the full one restricted to the free dofs.
    full = Probe(model, st, rest).hess(st.dofs(model))
    np.testing.assert_array_equal(hess(u), full[np.ix_(free, free)])
