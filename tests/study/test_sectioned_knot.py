"""A knot tied at the sectioned contact level end to end: the closed trefoil (60 vertices)
converges, keeps its type, and its summary reads width, pressure and area off the sections;
the level's bad input."""

import numpy as np
import pytest

from tightknot.contact.law import RadialComplianceLaw
from tightknot.contact.sectioned import SectionedLayer, SectionSettings
from tightknot.knots.scenes import closed_trefoil
from tightknot.loading.batch import tie_batch
from tightknot.study.run import run_knot


@pytest.fixture(scope="module")
def sectioned_run():
    scene = closed_trefoil(16.37, nodes=60, contact=SectionSettings())
    return scene, run_knot(scene, tighten_steps=20)


def test_the_closed_trefoil_ties_at_the_sectioned_level(sectioned_run) -> None:
    scene, run = sectioned_run
    s = run.summary
    assert isinstance(scene.contact, SectionedLayer)
    assert s["converged"], s["failure"]
    assert s["knot_type"] == "3_1"
    # the sections carry the contact: some of their perimeter touches (measured 0.14 at
    # 60 and 100 vertices), none wholly
    assert 0.02 < s["max_contact_width_fraction"] < 1.0
    assert 0.0 < s["max_pressure_over_E"] < 2.0
    # the modes keep the area: A/A0 is the stretch's, lambda^-1 at nu = 1/2
    x = run.result.system.state.x
    ev = scene.model.edge_vertex
    lam = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1) / run.result.system.rest
    assert s["min_area_ratio"] == pytest.approx(1.0 / lam.max(), rel=0.02)
    # the range check speaks of the sections' calibration
    cal = scene.contact.calibration
    assert s["calibrated_w_over_D0"] == cal.calibrated_w_hat
    assert s["crossing_calibrated_w_over_D0"] == cal.crossing_w_hat
    assert run.result.system.state.extra.size == scene.contact.dof_count > 0


def test_a_sectioned_level_takes_no_radial_compliance_law() -> None:
    with pytest.raises(ValueError, match="sectioned.*no radial-compliance law"):
        closed_trefoil(16.37, nodes=60, contact="sectioned",
                       law=RadialComplianceLaw.from_json())


def test_the_batch_refuses_the_sectioned_level() -> None:
    scenes = [closed_trefoil(16.37, nodes=60, contact="sectioned") for _ in range(2)]
    with pytest.raises(ValueError, match="sectioned"):
        tie_batch(scenes)
