"""The tight bend's section shift (tightknot.contact.section_shift): its size on a circle,
its derivatives carried back through the Jacobian against finite differences, and the
sectioned level with it inside a rod system."""

import math

import numpy as np
import pytest

from tightknot.contact.section_shift import MIN_CHORD, SectionShift
from tightknot.contact.sectioned import SectionedLayer, SectionSettings
from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material
from tightknot.rods.state import State
from tightknot.rods.term import BlockHessian
from tightknot.solvers.system import RodSystem

D0 = 0.0085
MAT = Material(1.25e6, 0.5, 1160.0)


def _model(curves: list[np.ndarray], closed: bool = False):
    b = RodBuilder(twist=False)
    for c in curves:
        b.add_rod(c, D0, MAT, closed=closed)
    return b.finalize()


def _circle(rho: float, n: int, closed: bool) -> np.ndarray:
    phi = np.linspace(0.0, 2.0 * math.pi if closed else math.pi, n, endpoint=not closed)
    return np.c_[rho * np.cos(phi), rho * np.sin(phi), np.zeros(n)]


@pytest.mark.parametrize("closed", [False, True])
def test_a_circle_shifts_its_sections_toward_its_centre(closed: bool) -> None:
    # On a circle of radius rho the shift is nu R^2 kappa / 2 toward the centre, kappa
    # the chords' curvature 2 sin(L / 2 rho) / L over arcs L of m edges (1 / rho less
    # (L / rho)^2 / 24 of it, 0.5 % here); an open rod's vertices closer than MIN_CHORD
    # to an end stay, those within a chord of it take the chord to the end.
    rho = 3.0 * D0
    model = _model([_circle(rho, 121, closed)], closed)
    shift = SectionShift(model, chord=1.0)
    x = model.vertex_initial_position
    out = shift.at(x, model.edge_rest_length).x
    moved = out - x
    radial = -np.einsum("ij,ij->i", moved, x / np.linalg.norm(x, axis=1)[:, None])
    h = float(np.median(model.edge_rest_length))
    m = math.ceil(D0 / h)
    inner = slice(None) if closed else slice(m, -m)
    step = 2.0 * math.pi / 121 if closed else math.pi / 120  # angle between vertices
    # nu R^2 |t_1 - t_0| / (L0_bar + L1_bar): chords m steps long, edges chords of a step
    expect = 0.5 * (0.5 * D0) ** 2 * 2.0 * math.sin(0.5 * m * step) / (
        2.0 * m * 2.0 * rho * math.sin(0.5 * step))
    assert expect == pytest.approx(0.5 * 0.5 * (0.5 * D0) ** 2 / rho, rel=0.01)
    assert np.allclose(radial[inner], expect, rtol=1e-9)
    assert np.max(np.abs(moved[inner] + radial[inner, None] * x[inner]
                         / np.linalg.norm(x[inner], axis=1)[:, None])) < 1e-12 * rho
    if not closed:
        least = math.ceil(MIN_CHORD * D0 / h)
        assert np.all(moved[:least] == 0.0) and np.all(moved[-least:] == 0.0)
        assert np.all(radial[least:m] > 0.0) and np.all(radial[-m:-least] > 0.0)
        # a shorter chord on one side still reads the circle's curvature (to 1 %)
        assert np.allclose(radial[least:m], expect, rtol=0.01)


def test_a_fraction_of_the_shift_moves_the_sections_that_fraction() -> None:
    # section_finish's homotopy applies a fraction of the shift: the offset scales with it
    # (its Jacobian with it: the pull-back test below holds at any scale), the bend it
    # reports does not.
    model = _model([_circle(3.0 * D0, 61, False)])
    shift = SectionShift(model, chord=1.0)
    x, rest = model.vertex_initial_position, model.edge_rest_length
    whole = shift.at(x, rest).x - x
    kappa_r = shift.max_kappa_r(x, rest)
    shift.set_scale(0.25)
    assert np.allclose(shift.at(x, rest).x - x, 0.25 * whole, rtol=0.0,
                       atol=1e-12 * np.abs(whole).max())
    assert shift.max_kappa_r(x, rest) == pytest.approx(kappa_r, rel=1e-12)
    for bad in (0.0, -0.5, 1.5, float("nan")):
        with pytest.raises(ValueError, match="scale"):
            shift.set_scale(bad)


def test_a_straight_rod_does_not_shift() -> None:
    z = np.linspace(0.0, 4.0 * D0, 30)
    model = _model([np.c_[np.zeros(30), np.zeros(30), z]])
    x = model.vertex_initial_position
    assert np.max(np.abs(SectionShift(model).at(x, model.edge_rest_length).x - x)) < 1e-18


def _wavy(n: int, seed: int) -> np.ndarray:
    s = np.linspace(0.0, 5.0 * D0, n)
    rng = np.random.default_rng(seed)
    return np.c_[s, 0.6 * D0 * np.sin(s / D0), 0.3 * D0 * np.cos(0.7 * s / D0)] \
        + 0.02 * D0 * rng.normal(size=(n, 3))


def test_the_pull_back_matches_finite_differences() -> None:
    # F(x~, c) = g . z + z^T A z / 2 over z = (x~_v, c_v) of a few node pairs, c two own
    # dofs per node; its gradient and Hessian over (x, c), carried back through the
    # shift, against central differences of F(x~(x), c).
    model = _model([_wavy(40, 0), _wavy(40, 1) + np.array([0.0, 0.0, 0.8 * D0])])
    shift = SectionShift(model)
    nv = model.vertex_count
    rest = model.edge_rest_length
    rng = np.random.default_rng(2)
    b = 5
    node_dofs = np.arange(nv * b).reshape(nv, b)
    pairs = np.array([[5, 50], [6, 51], [20, 60], [21, 61], [21, 60], [30, 30]])
    keys = np.unique(np.concatenate([pairs, pairs[:, ::-1]]), axis=0)
    blocks = np.zeros((keys.shape[0], b, b))
    for i, (p, q) in enumerate(keys):
        if p <= q:
            blk = rng.normal(size=(b, b)) / D0**2
            blocks[i] = blk if p != q else blk + blk.T
            j = np.flatnonzero((keys[:, 0] == q) & (keys[:, 1] == p))[0]
            blocks[j] = blocks[i].T
    g0 = rng.normal(size=(nv, b)) / D0
    c = 0.01 * D0 * rng.normal(size=(nv, 2))
    dense = np.zeros((nv * b, nv * b))
    for (p, q), blk in zip(keys, blocks, strict=True):
        dense[p * b:(p + 1) * b, q * b:(q + 1) * b] += blk

    def energy(x: np.ndarray) -> tuple[float, np.ndarray]:
        z = np.c_[shift.at(x, rest).x, c].ravel()
        gz = g0.ravel() + dense @ z
        return float(g0.ravel() @ z + 0.5 * z @ dense @ z), gz.reshape(nv, b)

    x = model.vertex_initial_position.copy()
    _, gz = energy(x)
    sh = shift.at(x, rest)
    grad = sh.pull_back_gradient(gz[:, :3])
    hess = sh.pull_back_hessian(BlockHessian(node_dofs, keys, blocks), gz[:, :3])
    full = np.zeros((nv * b, nv * b))
    for (p, q), blk in zip(hess.keys, hess.blocks, strict=True):
        full[p * b:(p + 1) * b, q * b:(q + 1) * b] += blk
    # J^T A J of a symmetric A and the curvature term are symmetric: the own dofs' columns
    # (not differenced below) mirror their rows
    assert np.max(np.abs(full - full.T)) <= 1e-12 * np.max(np.abs(full))
    rows, cols = hess.masks()
    assert np.all(hess.blocks[~rows, 3:, :] == 0.0) and np.all(hess.blocks[:, 3:, :3][~rows] == 0)
    assert np.all(hess.blocks[~cols, :, 3:] == 0.0)
    assert hess.keys.shape[0] > keys.shape[0]  # the chords' far ends join in
    eps = 1e-7 * D0
    pos = np.arange(nv)[:, None] * b + np.arange(3)
    for v in (5, 6, 21, 30, 33, 50, 60):
        for k in range(3):
            d = np.zeros_like(x)
            d[v, k] = eps
            e_hi, g_hi = energy(x + d)
            e_lo, g_lo = energy(x - d)
            # central differences of a smooth energy: truncation eps^2, round-off
            # 1e-16 E / eps (measured 1e-9 relative)
            assert grad[v, k] == pytest.approx((e_hi - e_lo) / (2 * eps), rel=1e-6, abs=1e-9)
            col_fd = (shift.at(x + d, rest).pull_back_gradient(g_hi[:, :3])
                      - shift.at(x - d, rest).pull_back_gradient(g_lo[:, :3])) / (2 * eps)
            col = full[pos.ravel(), v * b + k].reshape(nv, 3)
            assert np.max(np.abs(col - col_fd)) <= 1e-6 * np.max(np.abs(col_fd))
            # the own dofs' rows: c enters unshifted, so d(g_c)/dx = the Hessian's column
            own = full[(np.arange(nv)[:, None] * b + np.arange(3, b)).ravel(), v * b + k]
            own_fd = ((g_hi - g_lo)[:, 3:] / (2 * eps)).ravel()
            assert np.max(np.abs(own - own_fd)) <= 1e-6 * max(np.max(np.abs(own_fd)), 1e-30)


def test_entries_pulled_back_are_the_gradients_pull_back() -> None:
    # Sparse entries of a vector over x~ (the twist chain's columns, one per edge) carried
    # to x entry by entry sum to J^T v of the dense vector (the gradient's pull-back).
    model = _model([_wavy(40, 0)])
    shift = SectionShift(model).at(model.vertex_initial_position, model.edge_rest_length)
    rng = np.random.default_rng(3)
    vertex = rng.integers(0, model.vertex_count, size=30)
    comp = rng.integers(0, 3, size=30)
    value = rng.normal(size=30)
    dense = np.zeros((model.vertex_count, 3))
    np.add.at(dense, (vertex, comp), value)
    src, w, c, val = shift.pull_back_entries(vertex, comp, value)
    assert np.all(val != 0.0) and src.max() < vertex.size
    out = np.zeros_like(dense)
    np.add.at(out, (w, c), val)
    expect = shift.pull_back_gradient(dense)
    assert np.max(np.abs(out - expect)) <= 1e-14 * np.max(np.abs(expect))
    # each entry reaches its vertex's chord ends: more entries out than in
    assert src.size > vertex.size
    assert np.all(np.bincount(src, minlength=vertex.size) > 0)


def _bent_crossing(shift: bool) -> tuple[RodSystem, SectionedLayer]:
    """Two bent rods crossing at 90 degrees, their centrelines 0.86 D0 apart, each bent
    away from the other (bend radius 1.2 D0), sections deformed at random."""
    rb = 1.2 * D0
    s = np.linspace(-1.0, 1.0, 21)
    model = _model([np.c_[rb * np.sin(s), np.zeros_like(s), rb * (1.0 - np.cos(s))],
                    np.c_[np.zeros_like(s), rb * np.sin(s), -0.86 * D0 - rb * (1.0 - np.cos(s))]])
    state = State.initial(model)
    rng = np.random.default_rng(0)
    state.x += 1e-3 * D0 * rng.normal(size=state.x.shape)
    system = RodSystem(model, state, BoundaryConditions(model))
    layer = SectionedLayer(model, SectionSettings(max_mode=6, samples=32, bend_shift=shift))
    system.add_term(layer)
    return system, layer


def test_the_level_with_the_shift_has_a_consistent_gradient_and_hessian() -> None:
    from tests.contact.test_sectioned import check_derivatives

    system, layer = _bent_crossing(True)
    assert layer.shift is not None and layer.shift.count > 0
    # the shift's own derivatives are exact: the Hessian's miss is the kernel's (measured
    # 1.3e-4 to 1.7e-4 of the difference quotient here)
    check_derivatives(system, D0, np.random.default_rng(1))


def test_rods_bent_away_from_each_other_press_less_with_the_shift() -> None:
    # Each rod's centre of curvature lies away from the other, so each boundary moves
    # away from the crossing by its shift (about 0.05 D0 each here): the same centrelines
    # press less.
    energies = {}
    for shift in (False, True):
        system, _ = _bent_crossing(shift)
        system.evaluate(system.free_vector(), False, False)
        energies[shift] = system.last_split.extra["contact"]
    assert 0.0 < energies[True] < 0.5 * energies[False]


def test_the_level_reports_its_boundary_centres() -> None:
    system, layer = _bent_crossing(True)
    x, rest = system.state.x, system.rest
    centres = layer.boundary_centres(x, rest)
    assert np.array_equal(centres, layer.shift.at(x, rest).x)
    assert np.max(np.linalg.norm(centres - x, axis=1)) > 0.03 * D0
    plain, off = _bent_crossing(False)
    assert off.shift is None and np.array_equal(off.boundary_centres(x, rest), x)
    del plain


@pytest.mark.parametrize(("kwargs", "word"), [({"bend_shift": "yes"}, "bend_shift"),
                                               ({"bend_shift_chord": 0.5}, "bend_shift_chord"),
                                               ({"bend_shift_chord": math.nan},
                                                "bend_shift_chord")])
def test_bad_shift_settings_name_the_option(kwargs: dict, word: str) -> None:
    with pytest.raises(ValueError, match=word):
        SectionSettings(**kwargs)


def test_the_chord_length_reads_the_same_circle() -> None:
    # on a circle every chord length gives nearly its curvature, the same vertices shifting
    model = _model([_circle(3.0 * D0, 121, False)])
    x, rest = model.vertex_initial_position, model.edge_rest_length
    one, two = SectionShift(model, chord=1.0), SectionShift(model, chord=2.0)
    assert two.count == one.count
    moved = np.linalg.norm(two.at(x, rest).x - x, axis=1)
    assert np.count_nonzero(moved) == two.count
    expect = 0.5 * 0.5 * (0.5 * D0) ** 2 / (3.0 * D0)
    assert np.allclose(moved[moved > 0], expect, rtol=0.02)


def test_knot_measures_read_the_sections_centres() -> None:
    # Lambda_OC, gaps and contact maps are measured on the surfaces the contact keeps
    # apart: with the shift, on the offset centreline (a knot's shifted sections touch
    # where their centrelines are more than the summed radii apart).
    from tightknot.knots.scenes import closed_trefoil, contact_centres, vertex_radii

    shifted = closed_trefoil(16.37, nodes=60, contact=SectionSettings(bend_shift=True))
    plain = closed_trefoil(16.37, nodes=60, contact="compliant")
    x, rest = shifted.model.vertex_initial_position, shifted.model.edge_rest_length
    centres = contact_centres(shifted, x, rest)
    assert np.array_equal(centres, shifted.contact.boundary_centres(x, rest))
    assert np.max(np.linalg.norm(centres - x, axis=1)) > 0.01 * shifted.diameter
    assert contact_centres(plain, x, rest) is x
    # the sections thin by the offset centreline's (mean fibre's) stretch
    ev = shifted.model.edge_vertex
    lam = np.linalg.norm(centres[ev[:, 1]] - centres[ev[:, 0]], axis=1) / rest
    r_e, _ = vertex_radii(shifted, x, rest)
    assert np.allclose(r_e, shifted.model.edge_radius * lam ** -0.5, rtol=1e-12)


def test_the_largest_bend_is_read_off_the_shift() -> None:
    # kappa R on a circle of radius 3 D0: 1/6 less the chords' (L / rho)^2 / 24
    model = _model([_circle(3.0 * D0, 121, True)], True)
    kr = SectionShift(model, chord=1.0).max_kappa_r(model.vertex_initial_position,
                                                    model.edge_rest_length)
    assert kr == pytest.approx(1.0 / 6.0, rel=0.01) and kr < 1.0 / 6.0


def test_a_bend_tighter_than_the_fem_measured_is_reported() -> None:
    from tightknot.contact.report import contact_report
    from tightknot.contact.section_shift import MEASURED_KAPPA_R
    from tightknot.knots.scenes import closed_trefoil
    from tightknot.study.run import calibration_range

    for shift in (True, False):
        scene = closed_trefoil(16.37, nodes=60, contact=SectionSettings(bend_shift=shift))
        st = scene.state
        st.extra = np.zeros(scene.contact.dof_count)
        # the start with its rest lengths shortened to 0.7: its tightest chord bend kappa R
        # 0.39 / 0.7 = 0.56 (the tied knot's: 0.51 at 60 vertices)
        rest = 0.7 * scene.model.edge_rest_length
        rep = contact_report(scene.contact, st.x, rest, st)
        warnings = calibration_range(scene, rep, st.x, rest)["warnings"]
        said = [w for w in warnings if "bend shift" in w]
        if shift:
            assert scene.contact.shift.max_kappa_r(st.x, rest) > MEASURED_KAPPA_R
            assert len(said) == 1 and "extrapolated" in said[0]
        else:
            assert not said
