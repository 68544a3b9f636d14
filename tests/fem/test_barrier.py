"""Barrier contact (ipctk): its pressure law, exact derivatives, CCD step cap, and the
Newton solver on two blocks pressed together."""

import numpy as np
import pytest

pytest.importorskip("felupe")
pytest.importorskip("ipctk")

import felupe as fem  # noqa: E402

from tightknot.fem.barrier import BarrierContact, quads_to_triangles  # noqa: E402
from tightknot.fem.barrier_solver import BarrierProblem  # noqa: E402
from tightknot.fem.material import nearly_incompressible_solid  # noqa: E402
from tightknot.fem.scenes._pair import stack  # noqa: E402

D0 = 8.5e-3
E = 1.25e6
KAPPA = 0.01 * E
DHAT = 3e-4


def _two_blocks_2d(gap, n=5):
    """Two unit-D0 squares, one above the other with a gap [m]; returns the field and the
    facing edges (top of the lower block, bottom of the upper one)."""
    lower = fem.Rectangle(a=(0.0, -D0), b=(D0, 0.0), n=n)
    upper = fem.Rectangle(a=(0.0, gap), b=(D0, gap + D0), n=n)
    mesh, (ia, ib) = stack([lower, upper])
    region = fem.RegionQuad(mesh)
    field = fem.FieldContainer([fem.FieldPlaneStrain(region, dim=2)])
    p = mesh.points

    def chain(idx, y):
        nodes = idx[np.isclose(p[idx, 1], y)]
        nodes = nodes[np.argsort(p[nodes, 0])]
        return np.column_stack([nodes[:-1], nodes[1:]])

    faces = np.vstack([chain(ia, 0.0), chain(ib, gap)])
    return mesh, field, faces, ia, ib


@pytest.mark.parametrize("gap_over_dhat", [0.01, 0.05])
def test_pressure_law_of_flat_contact(gap_over_dhat):
    # two parallel flat faces at gap d: the physical barrier's energy per area is
    # kappa b(d^2, dhat^2) / dhat^3 (Li et al. 2020 eq. 6 on squared distances), so the
    # pressure is p = -kappa 2 d b'(d^2) / dhat^3 exactly, and 2 kappa dhat / d for d << dhat
    # (+0.5 % at d = 0.01 dhat, +2.5 % at 0.05 dhat: the 20 % bound only says "this law")
    gap = gap_over_dhat * DHAT * D0
    _, field, faces, ia, ib = _two_blocks_2d(gap)
    contact = BarrierContact(field, faces, length_scale=D0, stiffness=KAPPA)
    force = contact.nodal_forces()
    f_up = force[ib, 1].sum()
    assert f_up > 0.0
    assert force[ia, 1].sum() == pytest.approx(-f_up, rel=1e-12)  # action = reaction
    s, sh = gap_over_dhat**2, 1.0  # squared distances over dhat^2
    db_ds = -2.0 * (s - sh) * np.log(s / sh) - (s - sh) ** 2 / s
    exact = -KAPPA * 2.0 * gap_over_dhat * db_ds  # in dhat units: d = x dhat
    # area weighting integrates the pressure over the face: the force per unit depth is
    # p times the face length D0 (the chain ends carry half weights, as a Riemann sum does)
    assert f_up / D0 == pytest.approx(exact, rel=1e-6)
    assert exact == pytest.approx(2.0 * KAPPA / gap_over_dhat, rel=0.2)


def test_derivatives_match_finite_differences():
    # 3D: two cubes with facing triangulated faces inside the barrier's range; energy,
    # gradient and Hessian (unprojected) agree with central differences to round-off
    gap = 0.2 * DHAT * D0
    lower = fem.Cube(a=(0.0, 0.0, -D0), b=(D0, D0, 0.0), n=3)
    upper = fem.Cube(a=(0.1 * D0, 0.2 * D0, gap), b=(1.1 * D0, 1.2 * D0, gap + D0), n=3)
    mesh, (ia, ib) = stack([lower, upper])
    field = fem.FieldContainer([fem.Field(fem.RegionHexahedron(mesh), dim=3)])
    quads = mesh.cells[:, [4, 5, 6, 7]]  # top faces (VTK order) of the lower cubes
    top = quads[np.all(np.isclose(mesh.points[quads, 2], 0.0), axis=1)]
    bottom = mesh.cells[:, [0, 1, 2, 3]]
    bottom = bottom[np.all(np.isclose(mesh.points[bottom, 2], gap), axis=1)]
    contact = BarrierContact(field, quads_to_triangles(np.vstack([top, bottom])),
                             length_scale=D0, stiffness=KAPPA)
    rng = np.random.default_rng(1)
    u0 = 1e-3 * gap * rng.standard_normal(field[0].values.shape)
    du = 1e-3 * gap * rng.standard_normal(u0.shape)
    g = contact.gradient(u0)
    hess = contact.hessian(u0, project=False)
    assert np.abs(g).max() > 0.0
    h = 1e-3
    de = (contact.energy(u0 + h * du) - contact.energy(u0 - h * du)) / (2 * h)
    assert de == pytest.approx(g @ du.ravel(), rel=1e-6)
    dg = (contact.gradient(u0 + h * du) - contact.gradient(u0 - h * du)) / (2 * h)
    assert np.linalg.norm(dg - hess @ du.ravel()) < 1e-5 * np.linalg.norm(dg)
    # the projected Hessian is positive semi-definite
    proj = contact.hessian(u0, project=True).toarray()
    assert np.linalg.eigvalsh(0.5 * (proj + proj.T)).min() > -1e-8 * np.abs(proj).max()


def test_ccd_caps_a_step_through_the_other_body():
    gap = 2.0 * DHAT * D0
    _, field, faces, ia, ib = _two_blocks_2d(gap)
    contact = BarrierContact(field, faces, length_scale=D0, stiffness=KAPPA)
    step = np.zeros(field[0].values.shape)
    step[ib, 1] = -3.0 * gap  # would pass the upper block through the lower one
    alpha = contact.max_step(field[0].values, step)
    assert 0.0 < alpha < 1.0 / 3.0  # stops before touching (conservative rescaling 0.8)
    step[ib, 1] = -0.5 * gap
    assert contact.max_step(field[0].values, step) == 1.0


def test_solver_presses_two_blocks_uniformly():
    # two blocks squeezed between a fixed base and a moving top, frictionless sides
    # (symmetry): a uniform uniaxial plane-strain state, force per depth known in closed
    # form only up to large strain; what must hold is equilibrium (the force through the
    # contact equals the reaction at the top) and no interpenetration
    gap = DHAT * D0
    mesh, field, faces, ia, ib = _two_blocks_2d(gap, n=3)
    solid = nearly_incompressible_solid(field, mu=E / 3.0, bulk=5000.0 * E / 3.0)
    contact = BarrierContact(field, faces, length_scale=D0, stiffness=KAPPA)
    p = mesh.points
    fixed = np.zeros((mesh.npoints, 2), bool)
    fixed[np.isclose(p[:, 0], 0.0), 0] = True
    bottom = np.isclose(p[:, 1], -D0)
    top = np.isclose(p[:, 1], gap + D0)
    fixed[bottom | top, 1] = True

    def prescribed(t):
        u = np.zeros((mesh.npoints, 2))
        u[top, 1] = -(gap + t)
        return u.ravel()

    problem = BarrierProblem(field, solid, contact, fixed.ravel(), prescribed,
                             force_scale=E * D0, load=-gap)
    rows = problem.run(np.array([0.01 * D0, 0.02 * D0]),
                       lambda t: {"f": float(contact.nodal_forces()[ib, 1].sum()),
                                  "gap": contact.minimum_distance_over_scale()})
    r, _ = problem.assemble(project=False)
    # the top support's force on the upper block is r there; it balances the contact
    reaction = -float(r.reshape(-1, 2)[top, 1].sum())
    assert rows[-1]["f"] == pytest.approx(reaction, rel=1e-6)
    assert 0.0 < rows[-1]["gap"] < DHAT
    # each block shortens by ~t/2 at small strain: the plane-strain modulus of an
    # incompressible solid with a free side is 4 mu = 4E/3, so f ~ (4E/3) (t/2 / D0) D0;
    # the barrier's gap (0.7 dhat at these pressures, 2 % of t = 0.01 D0) and the strain
    # (1 %) lower it by a few per cent: 5 %
    for t, row in zip([0.01, 0.02], rows, strict=True):
        assert row["f"] == pytest.approx(4.0 / 3.0 * E * t / 2.0 * D0, rel=0.05)


def test_contact_library_failure_is_a_failed_solve():
    # ipctk raises RuntimeError (a PSD projection on crossed surfaces) or MemoryError (a
    # CCD on a runaway step); the CLI must see a failed solve (one line, exit 1)
    from types import SimpleNamespace

    from tightknot.fem.barrier_solver import BarrierNewtonFailure, BarrierProblem

    problem = SimpleNamespace(load=0.25)
    for err in (RuntimeError("unable to project matrix"), MemoryError("std::bad_alloc")):
        with pytest.raises(BarrierNewtonFailure, match="contact library failed at load 0.25"):
            with BarrierProblem.failures_as_newton(problem):
                raise err
