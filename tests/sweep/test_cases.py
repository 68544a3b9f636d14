"""Sweep cases: canonical parameters, stable ids, grids, and clear errors on bad input."""

import json

import pytest

from tightknot.sweep.cases import Case, canonical, case_id, grid


def test_the_id_depends_on_the_physics_not_on_spelling_or_order() -> None:
    a = Case.of({"knot": "open", "target_lambda": [13, 15, 14], "nodes": 150})
    # Same case: defaults written out, ints as floats, levels in another order.
    b = Case.of({"nodes": 150.0, "knot": "open", "length": 0.185, "contact": "compliant",
                 "target_lambda": [15.0, 14.0, 13.0]})
    assert a.id == b.id
    assert a.params == b.params
    # Levels are stored loosest first: Lambda_OC decreasing, forces increasing.
    assert a.params["target_lambda"] == [15.0, 14.0, 13.0]
    assert Case.of({"knot": "open", "pull_force": [3, 1, 2]}).params["pull_force"] == [1, 2, 3]
    # Any change of a parameter gives another id.
    assert Case.of({"knot": "open", "target_lambda": [13, 15, 14], "nodes": 151}).id != a.id
    assert Case.of({"knot": "open", "target_lambda": [13, 15], "nodes": 150}).id != a.id
    # The canonical form is a fixed point, JSON round-trips, and the id is 16 hex digits.
    assert canonical(a.params) == a.params
    assert json.loads(json.dumps(a.params)) == a.params
    assert case_id(json.loads(json.dumps(a.params))) == a.id
    assert len(a.id) == 16 and int(a.id, 16) >= 0


def test_grid_is_the_product_of_the_axes_without_duplicates() -> None:
    cases = grid({"knot": "closed", "nodes": 60}, l0_over_d0=[16.37, 18, 20],
                 contact=["compliant", "rigid"])
    assert len(cases) == 6
    assert len({c.id for c in cases}) == 6
    assert [c.params["l0_over_d0"] for c in cases[:2]] == [16.37, 16.37]
    # 18 and 18.0 are one case.
    assert len(grid({"knot": "closed"}, l0_over_d0=[18, 18.0])) == 1
    assert "l0_over_d0=18" in cases[2].label()
    # Every parameter is named, defaults included (issue 20: "nodes=100 pull_force=3
    # levels" did not say which rod).
    open_case = grid({"knot": "open", "pull_force": [3.0, 2.0]}, nodes=[100])[0]
    label = open_case.label()
    for key in open_case.params:
        if key != "knot":
            assert f"{key}=" in label, key
    assert "length=0.185" in label and "pull_force=[2, 3]" in label


@pytest.mark.parametrize(("params", "words"), [
    ({"knot": "loop"}, "knot: 'loop' is not one of: closed, open"),
    ({"knot": "closed", "nodes": 10}, "nodes: 10 is out of range; valid: [24, 200000]"),
    ({"knot": "open", "nodes": 30, "pull_force": [1.0]},
     "nodes: 30 is out of range for open knots; valid: [40,"),
    ({"knot": "closed", "nodes": 40.5}, "nodes: expected an integer"),
    ({"knot": "closed", "l0_over_d0": 5}, "l0_over_d0: 5.0 is out of range; valid: [10, 10000]"),
    ({"knot": "closed", "poisson": 0.7}, "poisson: 0.7 is out of range; valid: (-1, 0.5]"),
    ({"knot": "closed", "youngs_modulus": float("nan")}, "youngs_modulus: nan is out of range"),
    ({"knot": "closed", "youngs_modulus": -1.0}, "valid: (0, 1e+12] Pa (Young's modulus E)"),
    ({"knot": "closed", "contact": "sticky"}, "contact: 'sticky' is not one of: compliant"),
    ({"knot": "closed", "pull_force": [1.0]}, "unknown parameter(s) ['pull_force']"),
    ({"knot": "open"}, "exactly one level list"),
    ({"knot": "open", "pull_force": [1.0], "target_lambda": [14]}, "exactly one level list"),
    ({"knot": "open", "pull_force": []}, "non-empty list"),
    ({"knot": "open", "pull_force": [1.0, -2.0]}, "pull_force[1]: -2.0 is out of range; "
                                                    "valid: (0, 1e+06] N"),
    ({"knot": "open", "target_lambda": [14, 14.0]}, "lists a level twice"),
    ({"knot": "open", "length": 0.05, "pull_force": [1.0]}, "length must be >= 10 D0"),
    ({"knot": "open", "twist": "yes", "pull_force": [1.0]}, "twist: expected true or false"),
])
def test_bad_parameters_are_refused_with_their_name_and_range(params: dict,
                                                              words: str) -> None:
    with pytest.raises(ValueError) as err:
        Case.of(params)
    assert words in str(err.value)


def test_a_grid_axis_cannot_repeat_a_fixed_parameter() -> None:
    with pytest.raises(ValueError, match="both as a fixed parameter and as a sweep axis"):
        grid({"knot": "closed", "nodes": 60}, nodes=[60, 80])
    with pytest.raises(ValueError, match="non-empty list"):
        grid({"knot": "closed"}, nodes=[])


def test_knot_types_have_their_own_default_lengths() -> None:
    assert Case.of({"knot": "closed"}).params["l0_over_d0"] == 16.37
    assert Case.of({"knot": "closed", "knot_type": "4_1"}).params["l0_over_d0"] == 22.1
    assert Case.of({"knot": "open", "knot_type": "4_1", "pull_force": [2]}).params["length"] \
        == 0.30
    from tightknot.knots.scenes import default_l0_over_d0

    assert Case.of({"knot": "closed", "knot_type": "5_1"}).params["l0_over_d0"] == \
        default_l0_over_d0("5_1")
    with pytest.raises(ValueError, match="knot_type: '9_1' is not one of"):
        Case.of({"knot": "closed", "knot_type": "9_1"})


def test_a_case_builds_the_scene_it_names() -> None:
    # Scenes build without solving (fast): the case's parameters reach the scene.
    from tightknot.sweep.execute import build_scene

    scene = build_scene(Case.of({"knot": "closed", "knot_type": "4_1", "nodes": 120,
                                 "contact": "rigid", "poisson": 0.3,
                                 "youngs_modulus": 2e6}).params)
    assert scene.knot_type == "4_1" and scene.closed
    assert scene.model.vertex_count == 120
    assert scene.contact.law.rigid
    assert scene.model.rods[0].material.poisson_ratio == 0.3
    assert scene.model.rods[0].material.youngs_modulus == 2e6
    assert abs(scene.rest_length / scene.diameter - 22.1) < 1e-12
    scene = build_scene(Case.of({"knot": "open", "nodes": 100, "length": 0.16,
                                 "pull_force": [3.0]}).params)
    assert scene.knot_type == "3_1" and not scene.closed and not scene.contact.law.rigid
    assert scene.rest_length == 0.16 and not scene.model.twist
