"""The deepest contacts by kind (contact.checks.deepest_approaches): the crossing and the
parallel pairs' largest per-side approach, which the summary compares with the ranges the
point law and the line law (with its core) were calibrated to."""

import numpy as np
import pytest

from tightknot.contact.checks import deepest_approaches
from tightknot.contact.layer import ContactLayer
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material

D0 = 8.5e-3


def _two_rods(second_start, second_end, n: int = 36):
    b = RodBuilder(twist=False)
    mat = Material(1.25e6, 0.5, 1160.0)
    b.add_rod(np.linspace([0, 0, -1.5 * D0], [0, 0, 1.5 * D0], n + 1), D0, mat)
    b.add_rod(np.linspace(second_start, second_end, n + 1), D0, mat)
    return b.finalize()


def test_a_crossing_is_told_from_a_parallel_contact():
    gap = 0.8  # centerlines 0.8 D0 apart: a pair overlap of 0.2 D0, w = 0.1 D0 per side
    cross = _two_rods([-1.5 * D0, gap * D0, 0], [1.5 * D0, gap * D0, 0])
    w_line, w_cross = deepest_approaches(ContactLayer(cross), cross.vertex_initial_position,
                                         cross.edge_rest_length)
    assert w_line == 0.0
    # the layer's overlap is the law's (less its onset band of 1e-4 R)
    assert w_cross == pytest.approx(0.1 * D0, rel=2e-3)
    par = _two_rods([0, gap * D0, -1.5 * D0], [0, gap * D0, 1.5 * D0])
    w_line, w_cross = deepest_approaches(ContactLayer(par), par.vertex_initial_position,
                                         par.edge_rest_length)
    assert w_cross == 0.0
    assert w_line == pytest.approx(0.1 * D0, rel=2e-3)


def test_apart_rods_have_no_approach():
    m = _two_rods([-1.5 * D0, 1.2 * D0, 0], [1.5 * D0, 1.2 * D0, 0])
    assert deepest_approaches(ContactLayer(m), m.vertex_initial_position,
                              m.edge_rest_length) == (0.0, 0.0)
