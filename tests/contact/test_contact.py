"""The self-contact layer: derivatives, the calibrated law on straight strands, the
exclusion window, the step bound, and refusing a start that already intersects itself."""

import math

import numpy as np
import pytest
import scipy.sparse as sp

from tightknot.contact.law import RadialComplianceLaw
from tightknot.contact.layer import ContactLayer, SelfIntersectionError
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material

D, E = 0.0085, 1.25e6
LAW = RadialComplianceLaw.from_json()


def two_rods(angle_deg: float, distance: float, n: int = 81, length: float = 20 * D,
             noise: float = 0.0, seed: int = 0):
    """Rod 0 along x; rod 1 crossing it at ``angle_deg`` in a plane ``distance`` above."""
    rng = np.random.default_rng(seed)
    s = np.linspace(-length / 2, length / 2, n)
    th = math.radians(angle_deg)
    b = RodBuilder(twist=False)
    b.add_rod(np.c_[s, 0 * s, 0 * s], D, Material(E, 0.5, 1160.0))
    b.add_rod(np.c_[s * math.cos(th), s * math.sin(th), 0 * s + distance]
              + noise * D * rng.standard_normal((n, 3)), D, Material(E, 0.5, 1160.0))
    return b.finalize()


def distance_for_overlap(delta_over_d: float) -> float:
    """Centerline distance of identical rods at pair overlap delta = D - d."""
    return (1.0 - delta_over_d) * D


@pytest.mark.parametrize("angle, gap, law", [
    (90.0, 0.9, LAW), (60.0, 0.7, LAW), (25.0, 0.8, LAW), (5.0, 0.85, LAW), (0.5, 0.95, LAW),
    # Inside the hard core's band (below 0.7 R), crossing and near parallel:
    (90.0, 0.45, LAW), (5.0, 0.55, LAW),
    # A rigid tube between its barrier's start (R) and its divergence (0.98 R):
    (5.0, 0.99, LAW.rigid_tube())])  # (positions jitter by 0.002 D there, not 0.01 D)
def test_gradient_and_hessian_match_finite_differences(angle: float, gap: float,
                                                        law: RadialComplianceLaw) -> None:
    # Crossing (90, 60), the line-to-point blend (25), near parallel (5, 0.5 deg); rest
    # lengths 3 % longer than the edges, so the sections are compressed and their radii
    # r0 (l/l_bar)^-nu enter the derivatives (of the law and of the hard core's band).
    m = two_rods(angle, gap * D, n=6, length=0.03, noise=0.002 if law.rigid else 0.01)
    cl = ContactLayer(m, law, gauss_points=2)
    x0 = m.vertex_initial_position.copy()
    rest = m.edge_rest_length * 1.03
    e0, _, _ = cl.evaluate(x0, rest, True, True)
    assert e0 > 0 and len(cl.last_pairs) > 0
    _check_derivatives(cl, x0, rest)


def _check_derivatives(cl: ContactLayer, x0: np.ndarray, rest: np.ndarray) -> None:
    """The contact gradient and Hessian at ``x0`` against central differences."""
    m = cl.model
    e0, g0, coo = cl.evaluate(x0, rest, True, True)
    dofs = m.position_dofs.ravel()
    h_full = sp.coo_matrix((coo[2], (coo[0], coo[1])), shape=(m.dof_count,) * 2).toarray()
    hess = h_full[np.ix_(dofs, dofs)]
    n = dofs.size
    step = 1e-7 * D  # central differences: truncation ~ step^2, round-off ~ 1e-16 E / step
    gfd = np.zeros(n)
    hfd = np.zeros((n, n))
    changes = []
    for k in range(n):
        dx = np.zeros(n)
        dx[k] = step
        ep, gp, _ = cl.evaluate(x0 + dx.reshape(-1, 3), rest, True, False)
        em, gm, _ = cl.evaluate(x0 - dx.reshape(-1, 3), rest, True, False)
        gfd[k] = (ep - em) / (2 * step)
        hfd[k] = (gp - gm).ravel() / (2 * step)
        changes.append(abs(ep - em))
    # Guard: the perturbations do move the energy well above its round-off.
    assert max(changes) > 1e6 * np.finfo(float).eps * e0
    g = g0.ravel()
    # 1e-6 relative (the target); measured 1e-9..2e-9.
    assert np.abs(gfd - g).max() <= 1e-6 * np.abs(g).max()
    assert np.abs(hfd - hess).max() <= 1e-6 * np.abs(hess).max()
    assert np.abs(hess - hess.T).max() <= 1e-12 * np.abs(hess).max()


@pytest.mark.parametrize("delta_over_d", [0.05, 0.1, 0.3, 0.6])
def test_parallel_strands_follow_the_line_law(delta_over_d: float) -> None:
    # Two parallel straight rods held at overlap delta = D - d: the contact force per unit
    # length at mid-rod is the line law's f = de_line/d delta = K m delta^(m-1), at every
    # overlap (the kernel is the law's Abel inverse). Quadrature with 2 Gauss points on
    # edges of D/8: measured within 0.3 % from delta = 0.05 D to 0.6 D; 2 % bound. The
    # hard core is moved out of the way (core_fraction 0.3) to see the law alone.
    d = (1.0 - delta_over_d) * D
    m = two_rods(0.0, d, n=161)
    cl = ContactLayer(m, LAW, gauss_points=2, core_fraction=0.3, hard_relative=0.0)
    _, g, _ = cl.evaluate(m.vertex_initial_position, m.edge_rest_length, True, False)
    h = m.edge_rest_length[0]
    f_model = -g[m.rods[1].vertex_start + 80, 2] / h
    mm = LAW.p_line + 1
    # The kernel acts at delta - b D past its onset band b (contact_law docstring).
    eff = delta_over_d * D - LAW.onset_band * D
    f_law = LAW.line_energy_coefficient(E, D) * mm * eff ** (mm - 1)
    assert f_model == pytest.approx(f_law, rel=0.02)
    # The same as the per-side force of the calibration at w = delta/2.
    assert f_law == pytest.approx(float(LAW.line_force_per_length(eff, E, D)))


@pytest.mark.parametrize("delta_over_d", [0.05, 0.1, 0.3, 0.6])
def test_crossed_strands_follow_the_point_law(delta_over_d: float) -> None:
    # Two rods crossing at 90 degrees: the total contact force is the point law's
    # F = K m delta^(m-1), at every overlap; measured within 0.7 %; 3 % bound (the law
    # alone: hard core out of the way, as above).
    d = (1.0 - delta_over_d) * D
    m = two_rods(90.0, d, n=161)
    cl = ContactLayer(m, LAW, gauss_points=2, core_fraction=0.3, hard_relative=0.0)
    _, g, _ = cl.evaluate(m.vertex_initial_position, m.edge_rest_length, True, False)
    f_model = -g[m.rods[1].vertex_slice, 2].sum()
    f_law = float(LAW.point_force(delta_over_d * D - LAW.onset_band * D, E, D))
    assert f_model == pytest.approx(f_law, rel=0.03)


def test_no_contact_beyond_the_diameter() -> None:
    m = two_rods(30.0, 1.001 * D)
    cl = ContactLayer(m, LAW)
    e, g, _ = cl.evaluate(m.vertex_initial_position, m.edge_rest_length, True, False)
    assert e == 0.0 and np.abs(g).max() == 0.0


def test_tight_u_turn_does_not_touch_itself() -> None:
    # A hairpin of centerline radius D/2 (the tightest bend a tube allows): its straight legs
    # are D apart, touching only at the limit. No point pair outside the exclusion window is
    # closer than D, so the energy must be zero.
    n_arc, r = 60, D / 2
    phi = np.linspace(-math.pi / 2, math.pi / 2, n_arc)
    arc = np.c_[r * np.cos(phi), r * np.sin(phi), 0 * phi]
    legs = np.linspace(-6 * D, 0, 80)[:-1]
    lower = np.c_[legs, -r + 0 * legs, 0 * legs]
    upper = np.c_[legs[::-1], r + 0 * legs, 0 * legs]
    pts = np.vstack([lower, arc, upper])
    b = RodBuilder(twist=False)
    b.add_rod(pts, D, Material(E, 0.5, 1160.0))
    m = b.finalize()
    cl = ContactLayer(m, LAW)
    e, _, _ = cl.evaluate(m.vertex_initial_position, m.edge_rest_length, False, False)
    assert e == 0.0
    # The same hairpin squeezed to legs 0.9 D apart does touch (the check can fail).
    squeezed = pts.copy()
    squeezed[:, 1] *= 0.9
    e2, _, _ = cl.evaluate(squeezed, m.edge_rest_length, False, False)
    assert e2 > 0.0


def _short_hairpin(radius: float, n_arc: int = 24) -> np.ndarray:
    """A U-turn of centerline ``radius`` with legs of 0.6 D: every point pair is inside or
    near the exclusion window (rod length about 1.2 D + pi radius)."""
    phi = np.linspace(-math.pi / 2, math.pi / 2, n_arc)
    arc = np.c_[radius * np.cos(phi), radius * np.sin(phi), 0 * phi]
    legs = np.linspace(-0.6 * D, 0, 8)[:-1]
    return np.vstack([np.c_[legs, -radius + 0 * legs, 0 * legs], arc,
                      np.c_[legs[::-1], radius + 0 * legs, 0 * legs]])


def test_a_fold_tighter_than_a_legal_bend_is_resisted() -> None:
    # Inside the exclusion window the law is off; the optional local-thickness barrier keeps
    # points an arc sep apart at least 0.7 D sin(sep/D) apart (the chord of the tightest
    # legal bend, radius D/2). A short hairpin of radius D/2 is legal. Folded to radius
    # 0.2 D (legs 0.4 D apart, pairs 0.8..1.6 D apart along the rod): resisted, and its
    # gradient and Hessian match finite differences (1e-6 relative, as above).
    def layer(pts: np.ndarray) -> tuple[ContactLayer, np.ndarray]:
        b = RodBuilder(twist=False)
        b.add_rod(pts, D, Material(E, 0.5, 1160.0))
        m = b.finalize()
        return ContactLayer(m, LAW, local_thickness=True), m
    cl, m = layer(_short_hairpin(D / 2))
    e_legal = cl.evaluate(m.vertex_initial_position, m.edge_rest_length, False, False)[0]
    cl, m = layer(_short_hairpin(0.2 * D))
    x0 = m.vertex_initial_position.copy()
    rest = m.edge_rest_length * 1.02
    e0, _, _ = cl.evaluate(x0, rest, True, True)
    # The legal hairpin's polygon touches its legs at the limit (1e-15 J of law energy
    # measured, its Gauss points lie on chords inside the circle); the fold is resisted.
    assert e0 > 1e9 * e_legal and e0 > 0.0
    _check_derivatives(cl, x0, rest)


def test_step_bound_prevents_passing_through() -> None:
    # Rod 1 crosses 1.2 D above rod 0; a step that moves it 3 D down would pass through.
    m = two_rods(90.0, 1.2 * D, n=21, length=6 * D)
    cl = ContactLayer(m, LAW, hard_fraction=0.1)
    x = m.vertex_initial_position
    dx = np.zeros_like(x)
    dx[m.rods[1].vertex_slice, 2] = -3.0 * D
    alpha = cl.max_step(x, dx, m.edge_rest_length)
    # The bound keeps the segments at least the hard limit apart: at alpha the gap is
    # 1.2 D - 3 D alpha >= 0.1 D, i.e. alpha <= 1.1/3; and it is not needlessly small.
    assert 0.0 < alpha <= 1.1 / 3 + 1e-12
    assert alpha >= 0.99 * 1.1 / 3
    dist, _, _ = cl.min_distance(x + alpha * dx)
    assert dist >= 0.1 * D * (1 - 1e-9)
    # A step that moves away is not limited.
    assert cl.max_step(x, -dx, m.edge_rest_length) == 1.0


def test_a_step_that_moves_two_pieces_alike_is_not_cut() -> None:
    # The bound counts the two edges' relative motion: the crossing carried 3 D along and
    # 2 D down as a whole keeps every distance, so nothing cuts it; rod 1 pushed 3 D down
    # through rod 0 while both are carried 3 D along is cut where the push alone is, to
    # (1.2 - 0.1) / 3 (a bound on the sum of the two edges' motions cut these to
    # 1.1 / (2 sqrt(13)) = 0.15 and 1.1 / (3 + 3 sqrt(2)) = 0.15).
    m = two_rods(90.0, 1.2 * D, n=21, length=6 * D)
    cl = ContactLayer(m, LAW, hard_fraction=0.1)
    x = m.vertex_initial_position
    carried = np.tile([3.0 * D, 0.0, -2.0 * D], (x.shape[0], 1))
    assert cl.max_step(x, carried, m.edge_rest_length) == 1.0
    push = np.tile([3.0 * D, 0.0, 0.0], (x.shape[0], 1))
    push[m.rods[1].vertex_slice, 2] = -3.0 * D
    assert cl.max_step(x, push, m.edge_rest_length) == pytest.approx(1.1 / 3, rel=1e-9)


def test_random_steps_within_the_bound_never_pass_through() -> None:
    # Random steps of a tangle of two crossing rods (each vertex moved by up to 2 D, with
    # a shared part): along every step cut to its bound the two rods stay at least the
    # hard limit apart (checked at 201 points of the way, the independent proximity check).
    from tightknot.rods.proximity import ProximityCheck

    m = two_rods(60.0, 1.1 * D, n=21, length=6 * D)
    cl = ContactLayer(m, LAW, hard_fraction=0.1)
    check = ProximityCheck(m, hard_fraction=0.1 * (1 - 1e-9), local_fraction=0.25)
    rest = m.edge_rest_length
    x = m.vertex_initial_position
    rng = np.random.default_rng(7)
    cut = 0
    for _ in range(20):
        dx = 2.0 * D * (rng.uniform(-1, 1, x.shape) + rng.uniform(-1, 1, 3))
        alpha = cl.max_step(x, dx, rest)
        cut += alpha < 1.0
        for u in np.linspace(0.0, alpha, 201):
            assert not check.check(x + u * dx, rest).violated
    assert cut >= 10  # the steps do reach the bound


def test_a_step_too_long_for_the_broad_phase_is_cut_and_stays_safe(monkeypatch) -> None:
    # Rod 1 crosses a long rod 0 1.2 D above it; a step moves it 300 D along rod 0 and 300 D
    # down, sweeping its bounds over all of rod 0. With the broad phase's limit lowered
    # below that sweep's candidates (and above those of a 20 D sweep), the bound first cuts
    # the step to STEP_REACH diameters; without the cut the query overflowed and raised (a
    # floppy start's first Newton steps on a rod of 1e4 D0 stopped the run so, exit 2).
    # The fraction is then that of the cut step: at most the reach, and safe.
    from tightknot.contact import broad_phase, step_bound
    from tightknot.contact.broad_phase import ContactCapacityError

    b = RodBuilder(twist=False)
    s0 = np.linspace(-20 * D, 180 * D, 401)  # edges of 0.5 D
    b.add_rod(np.c_[s0, 0 * s0, 0 * s0], D, Material(E, 0.5, 1160.0))
    s1 = np.linspace(-3 * D, 3 * D, 13)
    b.add_rod(np.c_[0 * s1, s1, 0 * s1 + 1.2 * D], D, Material(E, 0.5, 1160.0))
    m = b.finalize()
    x = m.vertex_initial_position
    dx = np.zeros_like(x)
    dx[m.rods[1].vertex_slice] = [300.0 * D, 0.0, -300.0 * D]

    def count(step: np.ndarray) -> int:
        cl = ContactLayer(m, LAW, hard_fraction=0.1)
        bp = cl.broad_phase
        return bp.candidates(bp.x_in.put(x), bp.dx_in.put(step), cl.step_bound.half_hard,
                             *bp.arcs(m.edge_rest_length), window=0.0).shape[0]

    reach = step_bound.STEP_REACH / (300.0 * math.sqrt(2.0))
    far, near = count(dx), count(reach * dx)
    assert far > 4 * near  # the sweep over rod 0 is what overflows (722 against 60 pairs)
    monkeypatch.setattr(broad_phase, "MAX_CANDIDATES", (far + near) // 2)
    cl = ContactLayer(m, LAW, hard_fraction=0.1, initial_capacity=1)
    alpha = cl.max_step(x, dx, m.edge_rest_length)
    assert 0.0 < alpha <= reach * (1 + 1e-12)
    monkeypatch.setattr(broad_phase, "MAX_CANDIDATES", 10**9)  # the check's own query
    dist, _, _ = cl.min_distance(x + alpha * dx)
    assert dist >= 0.1 * D * (1 - 1e-9)
    # A step within the reach that still overflows is a dense contact set: an error.
    monkeypatch.setattr(broad_phase, "MAX_CANDIDATES", 1)
    fresh = ContactLayer(m, LAW, hard_fraction=0.1, initial_capacity=1)
    with pytest.raises(ContactCapacityError):
        fresh.max_step(x, reach * dx, m.edge_rest_length)


def test_start_that_intersects_itself_is_refused_with_arc_lengths() -> None:
    m = two_rods(90.0, 0.05 * D, n=21, length=6 * D)
    cl = ContactLayer(m, LAW, hard_fraction=0.1)
    with pytest.raises(SelfIntersectionError, match=r"arc lengths .* m apart, below"):
        cl.check_no_intersection(m.vertex_initial_position)


def test_candidate_buffer_grows_instead_of_dropping() -> None:
    # Start with a capacity of 1: the buffer must grow and give the same energy.
    m = two_rods(10.0, 0.9 * D, n=41, length=10 * D)
    small = ContactLayer(m, LAW, initial_capacity=1)
    big = ContactLayer(m, LAW, initial_capacity=100000)
    e1, _, _ = small.evaluate(m.vertex_initial_position, m.edge_rest_length, False, False)
    e2, _, _ = big.evaluate(m.vertex_initial_position, m.edge_rest_length, False, False)
    assert e1 == e2 and e1 > 0


def test_law_parameters_are_validated() -> None:
    with pytest.raises(ValueError, match="p_line"):
        RadialComplianceLaw(k_line=1.0, p_line=0.5, k_point=1.0, p_point=1.5)
    with pytest.raises(ValueError, match="k_point"):
        RadialComplianceLaw(k_line=1.0, p_line=1.2, k_point=-1.0, p_point=1.5)
    with pytest.raises(ValueError, match="gauss_points"):
        ContactLayer(two_rods(0.0, 2 * D, n=5), LAW, gauss_points=5)


def test_report_follows_the_fits_on_one_and_two_sided_squeeze() -> None:
    from tightknot.contact.report import contact_report

    # One-sided: two parallel rods at pair overlap 0.1 D; each side has w = 0.05 D.
    m = two_rods(0.0, distance_for_overlap(0.1))
    rep = contact_report(ContactLayer(m, LAW), m.vertex_initial_position)
    i = m.rods[1].vertex_start + 40
    w = 0.05 * D
    # The closest points are exact on straight strands: overlap to round-off.
    assert rep.overlap[i] == pytest.approx(2 * w, rel=1e-9)
    assert rep.overlap_opposite[i] == 0.0
    assert rep.contact_width_fraction[i] == pytest.approx(LAW.c_lc * (w / D) ** LAW.p_lc)
    assert rep.half_width[i] == pytest.approx(LAW.k_width * D * (w / D) ** LAW.p_width)
    # A one-sided contact squeezes the area as half a two-sided one (report docstring).
    assert rep.area_ratio[i] == pytest.approx(1 - LAW.k_area * (w / 2 / D) ** LAW.p_area)
    assert rep.pairs.shape[1] == 3 and rep.pairs.shape[0] > 0

    # Two-sided: a rod between two others, both at overlap 0.1 D: both sides count.
    s = np.linspace(-10 * D, 10 * D, 81)
    d = distance_for_overlap(0.1)
    b = RodBuilder(twist=False)
    for z in (-d, 0.0, d):
        b.add_rod(np.c_[s, 0 * s, 0 * s + z], D, Material(E, 0.5, 1160.0))
    m3 = b.finalize()
    rep3 = contact_report(ContactLayer(m3, LAW), m3.vertex_initial_position)
    j = m3.rods[1].vertex_start + 40
    assert rep3.overlap_opposite[j] == pytest.approx(2 * w, rel=1e-9)
    assert rep3.contact_width_fraction[j] == pytest.approx(
        2 * LAW.c_lc * (w / D) ** LAW.p_lc)
    assert rep3.area_ratio[j] == pytest.approx(1 - LAW.k_area * (w / D) ** LAW.p_area)


def test_report_of_a_rigid_tube_and_of_free_rods() -> None:
    from tightknot.contact.report import contact_report

    m = two_rods(0.0, distance_for_overlap(0.1))
    rep = contact_report(ContactLayer(m, LAW.rigid_tube()), m.vertex_initial_position)
    i = m.rods[1].vertex_start + 40
    assert rep.overlap[i] > 0 and rep.contact_width_fraction[i] == 0.0
    assert rep.area_ratio[i] == pytest.approx(1.0)
    far = two_rods(0.0, 2.0 * D)
    rep2 = contact_report(ContactLayer(far, LAW), far.vertex_initial_position)
    assert not rep2.overlap.any() and np.allclose(rep2.area_ratio, 1.0)


def test_a_coarse_straight_rod_reports_no_contact_with_its_neighbours() -> None:
    # Edges of 0.393 D (the 1 m rod at 300 vertices): edges three apart hold points farther
    # apart along the rod than the window (pi D / 2) though their nearest ends are only
    # 0.78 D apart; their whole segments' distance would read as an overlap. Only the
    # points beyond the window count, and a straight rod touches nothing.
    from tightknot.contact.report import contact_report

    n = 61
    x = np.c_[np.linspace(0.0, 60 * 0.393 * D, n), np.zeros(n), np.zeros(n)]
    b = RodBuilder(twist=False)
    b.add_rod(x, D, Material(1e6, 0.5, 1000.0))
    m = b.finalize()
    layer = ContactLayer(m)
    assert len(layer.nonlocal_pairs(x, m.edge_rest_length)) > 0  # the straddling pairs
    rep = contact_report(layer, x, m.edge_rest_length)
    assert np.all(rep.contact_width_fraction == 0.0) and np.all(rep.overlap == 0.0)


def test_the_step_bound_guards_a_pair_inside_the_exclusion_window() -> None:
    # A hairpin whose legs are 1.2 D apart along the rod (inside the pi/2 D window, where
    # the energy takes no notice of them) and 0.3 D apart in space; a step moves one leg
    # through the other. The step bound cuts it so that the legs stay at least their floor
    # (a quarter of the tightest legal bend's chord, here the hard limit) apart.
    from tightknot.contact.step_bound import LOCAL_FRACTION
    from tightknot.rods.proximity import ProximityCheck

    h = 0.1 * D
    leg = np.arange(7) * h
    x = np.vstack([np.c_[leg, np.zeros(7), np.zeros(7)],
                   np.c_[leg[::-1][1:], np.full(6, 0.3 * D), np.zeros(6)]])
    b = RodBuilder(twist=False)
    b.add_rod(x, D, Material(1e6, 0.5, 1000.0))
    m = b.finalize()
    layer = ContactLayer(m)
    rest = m.edge_rest_length
    dx = np.zeros_like(x)
    dx[7:, 1] = -0.6 * D  # the second leg through the first
    alpha = layer.max_step(x, dx, rest)
    assert 0.0 < alpha < 0.5
    check = ProximityCheck(m, hard_fraction=0.05, local_fraction=LOCAL_FRACTION)
    for u in np.linspace(0.0, alpha, 11):
        assert not check.check(x + u * dx, rest).violated


def test_mirror_images_are_no_candidates_and_cost_nothing_else() -> None:
    # Three rods through one region: 0 and 1 declared one body's mirror images (a FEM
    # stack's), 2 crossing both. Their pairs leave the candidates, which the energy, the
    # step bound and the checks all read; rod 2's pairs with either stay, as before.
    def model(mirror):
        s = np.linspace(-3 * D, 3 * D, 13)
        b = RodBuilder(twist=False)
        b.add_rod(np.c_[s, 0 * s, 0 * s], D, Material(E, 0.5, 1160.0))
        b.add_rod(np.c_[0 * s, s, 0 * s + 0.5 * D], D, Material(E, 0.5, 1160.0))
        b.add_rod(np.c_[0 * s + 0.2 * D, 0 * s - 0.3 * D, s], D, Material(E, 0.5, 1160.0))
        return b.finalize(mirror_rod_pairs=mirror)

    def pairs(m):
        cl = ContactLayer(m, LAW)
        bp = cl.broad_phase
        got = bp.candidates(bp.x_in.put(m.vertex_initial_position), bp.zero_dx,
                            bp.interaction_margin, *bp.arcs(m.edge_rest_length)).numpy()
        return {tuple(sorted(int(m.edge_rod[e]) for e in p)) for p in got}, cl

    plain, _ = pairs(model(()))
    mirrored, cl = pairs(model(((0, 1),)))
    assert (0, 1) in plain and {(0, 2), (1, 2)} <= plain
    assert mirrored == plain - {(0, 1)}
    # rods 0 and 1 overlap by half a diameter: no energy between them
    m = model(((0, 1),))
    x = m.vertex_initial_position.copy()
    x[m.rods[2].vertex_slice] += [10 * D, 0.0, 0.0]  # rod 2 away
    assert cl.evaluate(x, m.edge_rest_length, False, False)[0] == 0.0
    # and the step bound lets rod 1 move through rod 0
    dx = np.zeros_like(x)
    dx[m.rods[1].vertex_slice] = [0.0, 0.0, -D]
    assert cl.max_step(x, dx, m.edge_rest_length) == 1.0
