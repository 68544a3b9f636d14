"""The wrap's kernel variants (tightknot.fem.wrap_variants): the NumPy re-implementation of
the shipped point kernel against an analytic obstacle agrees with the Warp kernel, and the
footprint scaling keeps the energy of a straight crossing, as its docstring claims."""

import math

import numpy as np
import pytest

from tightknot.contact.law import RadialComplianceLaw
from tightknot.fem.material import ROD_DIAMETER as D0
from tightknot.fem.material import YOUNGS_MODULUS as E
from tightknot.fem.rod_model import rigid_counterbody_law, rod_wrap
from tightknot.fem.wrap_variants import ObstacleLineContact, rod_wrap_variant

LEVELS = [0.25 * (k / 6) ** 2 * E * D0**2 for k in (1, 3, 5)]


def test_point_variant_reproduces_the_warp_kernel():
    # Both without the hard core and with each edge's own thinning (the re-implementation's).
    warp = rod_wrap(LEVELS, law=RadialComplianceLaw.from_json().without_core(),
                    thinning="edge")["steps"]
    numpy_ = rod_wrap_variant(LEVELS, kernel="point", footprint=1.0)["steps"]
    for w, n in zip(warp, numpy_, strict=True):
        assert n["converged"] and w["converged"]
        # 0.5 %: the two differ in the obstacle's integral only (48 edges with 2 Gauss
        # points in the kernel, exact here) and in the onset band (1e-4 R); measured 0.3 %
        assert n["force_per_length_mid"] == pytest.approx(w["force_per_length_mid"], rel=5e-3)
        assert n["kappa_d0_mid"] == pytest.approx(w["kappa_d0_mid"], rel=5e-3)
        # statics: the total contact force is 2 T sin(theta) (dead end loads)
        assert n["contact_force_total_over_2t_sin_theta"] == pytest.approx(1.0, rel=1e-6)


class _StraightRod:
    """The minimum of a model that ObstacleLineContact reads: one straight rod."""

    def __init__(self, n: int, length: float) -> None:
        self.rods = [type("R", (), {"edge_count": n})()]
        self.edge_rest_length = np.full(n, length / n)
        self.edge_radius = np.full(n, 0.5 * D0)
        self.vertex_count = n + 1
        self.vertex_dof = np.arange(n + 1) * 3


@pytest.mark.parametrize("kernel", ["point", "line"])
def test_footprint_keeps_the_energy_of_a_straight_crossing(kernel):
    # a straight rod along e_z crossing the obstacle (along e_x) at 90 degrees, overlap
    # 0.1 D0: the scaled kernel's energy is a change of variables of the unscaled one
    law = rigid_counterbody_law(RadialComplianceLaw.from_json())
    n, length = 2000, 2.0 * D0
    model = _StraightRod(n, length)
    x = np.zeros((n + 1, 3))
    x[:, 2] = np.linspace(-0.5 * length, 0.5 * length, n + 1)
    y_axis = 0.9 * D0
    e = {}
    for alpha in (1.0, 2.0):
        term = ObstacleLineContact(model, law, y_axis, kernel, alpha)
        e[alpha] = term.evaluate(x, model.edge_rest_length, False, False)[0]
    assert e[1.0] > 0
    # 1e-4: the Gauss quadrature over chords of D0/1000 against a zone 0.22 to 0.44 D0 long
    assert e[2.0] == pytest.approx(e[1.0], rel=1e-4)


def test_variant_gradient_matches_energy_differences():
    law = rigid_counterbody_law(RadialComplianceLaw.from_json())
    n = 40
    model = _StraightRod(n, 2.0 * D0)
    rng = np.random.default_rng(3)
    x = np.zeros((n + 1, 3))
    s = np.linspace(-1.0, 1.0, n + 1)
    x[:, 1] = 0.12 * D0 * (1 - s**2) + 1e-3 * D0 * rng.standard_normal(n + 1)
    x[:, 2] = s * D0
    term = ObstacleLineContact(model, law, 0.95 * D0, "point", 2.0)
    _, g, (rows, cols, vals) = term.evaluate(x, model.edge_rest_length, True, True)
    assert math.isfinite(g.sum()) and np.abs(g).max() > 0
    # directional derivative of the energy against the gradient; 1e-5: central differences
    # of step 1e-7 D0 on energies (relative truncation ~1e-12, round-off ~1e-9)
    d = rng.standard_normal(x.shape)
    d[:, 0] = 0.0
    h = 1e-7 * D0
    ep = term.evaluate(x + h * d, model.edge_rest_length, False, False)[0]
    em = term.evaluate(x - h * d, model.edge_rest_length, False, False)[0]
    assert (ep - em) / (2 * h) == pytest.approx(float((g * d).sum()), rel=1e-5)
    # and the Hessian is symmetric with the gradient's derivative along d (1e-4: finite
    # differences of finite differences)
    import scipy.sparse as sp

    hm = sp.coo_matrix((vals, (rows, cols)), shape=(3 * (n + 1),) * 2).tocsr()
    assert abs(hm - hm.T).max() <= 1e-9 * abs(hm).max()
    gp = term.evaluate(x + h * d, model.edge_rest_length, True, False)[1]
    gm = term.evaluate(x - h * d, model.edge_rest_length, True, False)[1]
    hd = (hm @ d.ravel()).reshape(-1, 3)
    np.testing.assert_allclose((gp - gm)[:, 1:] / (2 * h), hd[:, 1:],
                               atol=1e-4 * np.abs(hd).max())


@pytest.mark.parametrize("kw,msg", [({"kernel": "spring"}, "kernel must be one of"),
                                    ({"footprint": 0.5}, "footprint must be in"),
                                    ({"footprint": float("nan")}, "footprint must be in")])
def test_bad_variant_is_refused(kw, msg):
    law = RadialComplianceLaw.from_json()
    with pytest.raises(ValueError, match=msg):
        ObstacleLineContact(_StraightRod(4, D0), law, D0, **kw)
