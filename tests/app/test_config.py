"""The tie config loader: defaults resolved, every key checked with a message naming it."""

import json

import numpy as np
import pytest

from tightknot.app.config import (
    COLOR_FIELDS,
    TieConfig,
    config_from_dict,
    config_keys,
    load_config,
)
from tightknot.knots.scenes import default_nodes


def test_defaults_are_resolved() -> None:
    c = config_from_dict({"knot": "closed"})
    # The vertex count follows the rest length: one vertex per DEFAULT_EDGE_D0 D0.
    assert c.nodes == default_nodes(16.37, True) and c.l0_over_d0 == 16.37 and c.length is None
    o = config_from_dict({"knot": "open", "force": 5})
    assert o.nodes == default_nodes(0.185 / 8.5e-3, False) and o.length == 0.185 and o.force == 5.0
    assert isinstance(o.force, float)  # an int in the file is a number of newtons


def test_round_trip_through_json_and_toml(tmp_path) -> None:
    c = config_from_dict({"knot": "open", "target_lambda": 10.1, "length": 0.125,
                          "nodes": 100, "color_by": "contact_width"})
    assert c.color_by == "contact_width_fraction"  # the alias is stored by its full name
    p = tmp_path / "config.json"
    p.write_text(json.dumps(c.to_dict()))
    assert load_config(p) == c
    t = tmp_path / "config.toml"
    t.write_text('knot = "open"\ntarget_lambda = 10.1\nlength = 0.125\nnodes = 100\n'
                 'color_by = "contact_width_fraction"\n')
    assert load_config(t) == c
    assert set(c.to_dict()) == set(config_keys())


@pytest.mark.parametrize(("data", "words"), [
    ({"knot": "closed", "nodez": 60}, ["unknown key", "'nodez'", "nodes"]),
    ({"knot": "closed", "nodes": 60.0}, ["nodes", "integer"]),
    ({"knot": "closed", "nodes": True}, ["nodes", "integer"]),
    ({"knot": "closed", "nodes": 5}, ["nodes", "out of range", "[24, 200000]"]),
    ({"knot": "closed", "poisson": 0.7}, ["poisson", "(-1, 0.5]"]),
    ({"knot": "closed", "diameter": "8.5mm"}, ["diameter", "number", "m"]),
    ({"knot": "closed", "residual_tol": 0.0}, ["residual_tol", "(0, 1)"]),
    ({"knot": "closed", "youngs_modulus": float("nan")}, ["youngs_modulus", "out of range"]),
    ({"knot": "closed", "color_by": "curvature"}, ["color_by", "kappa_D0", "contact_width"]),
    ({"knot": "closed", "force": 5.0}, ["force", "open knots only"]),
    ({"knot": "open"}, ["exactly one of", "none"]),
    ({"knot": "open", "force": 5.0, "target_lambda": 10.1}, ["exactly one of", "force"]),
    ({"knot": "open", "force": -5.0}, ["force", "(0, 1e+06]", "N"]),
    ({"knot": "trefoil"}, ["knot", "closed, open"]),
    ({"nodes": 60}, ["knot", "missing"]),
    ({"knot": "closed", "diameter": None}, ["diameter", "null"]),
])
def test_bad_values_name_the_key_and_range(data: dict, words: list[str]) -> None:
    with pytest.raises(ValueError) as err:
        config_from_dict(data)
    for w in words:
        assert w in str(err.value), (w, str(err.value))


def test_bad_files(tmp_path) -> None:
    with pytest.raises(ValueError, match="cannot read"):
        load_config(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text('{"knot": "closed",\n "nodes": }')
    with pytest.raises(ValueError, match="not valid JSON .line 2"):
        load_config(bad)
    listed = tmp_path / "list.json"
    listed.write_text("[1, 2]")
    with pytest.raises(ValueError, match="mapping"):
        load_config(listed)
    binary = tmp_path / "binary.json"
    binary.write_bytes(b"\xff\xfe{\x00")
    with pytest.raises(ValueError, match=r"binary.json: not a UTF-8 text file"):
        load_config(binary)
    typo = tmp_path / "typo.toml"
    typo.write_text('knot = "closed"\nnode = 60\n')
    with pytest.raises(ValueError, match=r"typo.toml: unknown key\(s\) 'node'"):
        load_config(typo)


def test_every_color_field_is_computed() -> None:
    # The fields are defined once (the logger's); the run must compute each of them.
    from tightknot.contact.report import contact_report
    from tightknot.knots.scenes import closed_trefoil
    from tightknot.study.run import rod_field

    scene = closed_trefoil(nodes=60)
    x = scene.state.x
    rep = contact_report(scene.contact, x, scene.model.edge_rest_length)
    for name in COLOR_FIELDS:
        values, at = rod_field(name, scene, x, scene.model.edge_rest_length, rep)
        n = scene.model.vertex_count if at == "vertex" else scene.model.edge_count
        assert values.shape == (n,) and np.isfinite(values).all(), name


def test_tie_options() -> None:
    closed = config_from_dict({"knot": "closed", "relax_iterations": 7})
    assert closed.tie_options() == {"tighten_steps": 40, "residual_tol": 1e-6,
                                    "relax_iterations": 7, "section_path": "auto"}
    pulled = config_from_dict({"knot": "open", "end_distance": 0.1})
    assert pulled.tie_options()["end_distance"] == 0.1
    assert pulled.tie_options()["pull_force"] is None
    lam = config_from_dict({"knot": "open", "target_lambda": 12.0})
    assert lam.tie_options() == {"target_lambda": 12.0, "tolerance": 0.1, "residual_tol": 1e-6,
                                 "section_path": "auto"}
    assert isinstance(lam, TieConfig) and lam.scene_name == "open_trefoil"
