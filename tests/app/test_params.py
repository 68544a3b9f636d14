"""The run parameters are declared once (tightknot.study.params, tightknot.loading.options):
the tie config's keys, the tie flags, the sweep's case parameters and flags, their defaults,
ranges and help all follow the declaration, so none of them can drift from another."""

from __future__ import annotations

import argparse
import inspect
import math

import pytest

from tightknot.app.cli import build_parser, tie_config
from tightknot.app.config import config_from_dict, config_keys
from tightknot.knots.scenes import default_nodes
from tightknot.loading.options import LoadPath, Range, flags, parameters
from tightknot.study.params import (
    CONTACT_LEVELS,
    KNOT_DEFAULTS,
    KNOT_TYPES,
    KNOTS,
    RUN_PARAMS,
    Scene,
    resolve_nodes,
)
from tightknot.sweep.cases import CASE_KEYS, LEVELS, NOT_CASE_KEYS, canonical, defaults

#: Options of the two commands that are not run parameters.
TIE_OTHER = {"help", "config", "out", "json", "figures", "rrd", "quiet", "overwrite",
             "knot_flag"}
SWEEP_OTHER = {"help", "out", "executor", "workers", "scheduler", "batch", "retry_failed",
               "json", "quiet"}


def _subparser(name: str) -> argparse.ArgumentParser:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[name]


def _options(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {a.dest: a for a in parser._actions if a.option_strings}


def _flat(text: str) -> str:
    # argparse wraps help at spaces and hyphens: compare without any whitespace.
    return "".join(text.split())


def test_every_run_parameter_is_a_config_key_and_a_tie_flag() -> None:
    assert config_keys() == tuple(RUN_PARAMS)
    tie = _subparser("tie")
    opts = _options(tie)
    assert set(opts) == (set(RUN_PARAMS) - {"knot"}) | TIE_OTHER
    for name, p in RUN_PARAMS.items():
        if name == "knot":
            (knot,) = [a for a in tie._actions if a.dest == "knot"]
            assert not knot.option_strings and list(knot.choices) == list(p.valid)
            continue
        action = opts[name]
        assert action.option_strings == list(flags(p)) and action.default is None, name
        if isinstance(p.valid, tuple) and p.kind is str:
            assert list(action.choices) == list(p.valid) + list(p.aliases), name


def test_every_case_parameter_is_a_run_parameter_and_a_sweep_flag() -> None:
    keys = set(CASE_KEYS["closed"]) | set(CASE_KEYS["open"])
    assert keys <= set(RUN_PARAMS)
    # Each run parameter is a case parameter, a level's load, or left out with a reason.
    assert keys | set(NOT_CASE_KEYS) == set(RUN_PARAMS) - {"knot"}
    assert not keys & set(NOT_CASE_KEYS)
    assert set(LEVELS.values()) <= set(RUN_PARAMS)
    # A knot's case holds the parameters of that knot (Param.only) and of both.
    for knot in KNOTS:
        for k in CASE_KEYS[knot]:
            assert RUN_PARAMS[k].only in (None, knot), (knot, k)
    opts = _options(_subparser("sweep"))
    assert set(opts) == keys | set(LEVELS) | {"device"} | SWEEP_OTHER
    for name in parameters(Scene):
        if name != "knot":
            assert opts[name].nargs == "+", name  # every scene parameter is a sweep axis


@pytest.mark.parametrize("command", ["tie", "sweep"])
def test_help_shows_each_parameter_with_its_unit_range_and_default(command: str) -> None:
    text = _flat(_subparser(command).format_help())
    names = (set(RUN_PARAMS) - {"knot"} if command == "tie" else
             set(CASE_KEYS["closed"]) | set(CASE_KEYS["open"]) | {"device"})
    for name in names:
        p = RUN_PARAMS[name]
        assert _flat(p.help_text()) in text, name
        if p.default_str():
            assert _flat(f"(default {p.default_str()})") in text, name
    for load in LEVELS.values():
        p = RUN_PARAMS[load]
        assert _flat(f"[{p.unit}] in {p.valid.text()}" if p.unit else p.valid.text()) in text


@pytest.mark.parametrize(("knot", "knot_type"), [(k, t) for k in KNOTS for t in KNOT_TYPES])
def test_config_and_sweep_resolve_the_same_defaults(knot: str, knot_type: str) -> None:
    load = {"open": {"force": 2.0}, "closed": {}}[knot]
    cfg = config_from_dict({"knot": knot, "knot_type": knot_type, **load}).to_dict()
    case = defaults(knot, knot_type)
    assert {k: cfg[k] for k in case} == case
    for k, v in case.items():
        if k == "nodes":  # from the rest length
            assert v == resolve_nodes({"knot": knot, **case}), k
            continue
        assert v == KNOT_DEFAULTS[(knot, knot_type)].get(k, RUN_PARAMS[k].default) or \
            k == "knot_type", k


def _outside(p) -> object:
    """A value the declaration refuses."""
    if isinstance(p.valid, Range):
        low = p.kind(p.valid.low)
        return low if p.valid.low_open else low - 1  # the excluded end, or one below
    if isinstance(p.valid, tuple):
        return "no such value"
    return "on"  # a string where a bool is due


@pytest.mark.parametrize("name", sorted(set(CASE_KEYS["closed"]) | set(CASE_KEYS["open"])))
def test_config_and_sweep_refuse_the_same_values(name: str) -> None:
    p = RUN_PARAMS[name]
    knot = p.only or "closed"
    bad = _outside(p)
    base = {"knot": knot}
    levels = {"pull_force": [2.0]} if knot == "open" else {}
    with pytest.raises(ValueError) as in_config:
        config_from_dict({**base, **({"force": 2.0} if knot == "open" else {}), name: bad})
    with pytest.raises(ValueError) as in_case:
        canonical({**base, **levels, name: bad})
    assert str(in_config.value) == str(in_case.value)
    assert str(in_config.value).startswith(f"{name}: ")


def test_the_scene_defaults_are_the_scenes_own() -> None:
    # The scene functions keep their own defaults (the knots layer sits below this one):
    # the declaration must agree with them.
    from tightknot.knots import scenes

    assert RUN_PARAMS["diameter"].default == scenes.STUDY_DIAMETER
    m = scenes.STUDY_MATERIAL
    assert (RUN_PARAMS["youngs_modulus"].default, RUN_PARAMS["poisson"].default,
            RUN_PARAMS["density"].default) == (m.youngs_modulus, m.poisson_ratio, m.density)
    assert CONTACT_LEVELS == tuple(c for c in scenes.CONTACT_LEVELS if c != "off")
    names = {"3_1": "trefoil", "4_1": "figure_eight"}
    for (knot, knot_type), table in KNOT_DEFAULTS.items():
        if knot_type in names:
            sig = inspect.signature(getattr(scenes, f"{knot}_{names[knot_type]}")).parameters
            length = sig["l0_over_d0" if knot == "closed" else "rest_length"].default
        else:
            sig = inspect.signature(getattr(scenes, f"{knot}_knot")).parameters
            length = (scenes.default_l0_over_d0 if knot == "closed"
                      else scenes.default_open_length)(knot_type)
        assert table["l0_over_d0" if knot == "closed" else "length"] == length
        assert table["twist"] == sig["twist"].default
        assert sig["nodes"].default is None  # both resolve it from the rest length
        assert sig["contact"].default == RUN_PARAMS["contact"].default


def test_the_load_functions_take_the_load_paths_defaults() -> None:
    from tightknot.loading.batch import tie_batch
    from tightknot.loading.pull import tie_to_lambda
    from tightknot.loading.tie import tie

    for fn in (tie, tie_batch):
        for name, p in inspect.signature(fn).parameters.items():
            if name in parameters(LoadPath):
                assert p.default == getattr(LoadPath, name), (fn.__name__, name)
    sig = inspect.signature(tie_to_lambda).parameters
    assert sig["tolerance"].default == LoadPath.lambda_tolerance
    assert sig["residual_tol"].default == LoadPath.residual_tol


def test_tie_flags_reach_the_config_and_the_scene() -> None:
    from tightknot.study.params import build_scene

    args = build_parser().parse_args(["tie", "closed", "--knot-type", "4_1", "--twist", "off",
                                      "--nodes", "120"])
    cfg = tie_config(args)
    assert (cfg.knot_type, cfg.twist, cfg.nodes) == ("4_1", False, 120)
    assert math.isclose(cfg.l0_over_d0, KNOT_DEFAULTS[("closed", "4_1")]["l0_over_d0"])
    scene = build_scene(cfg.to_dict())  # builds, never solves
    assert scene.name == cfg.scene_name == "closed_figure_eight"
    assert scene.knot_type == "4_1" and not scene.model.twist


def test_a_config_file_for_another_knot_keeps_only_what_carries_over(tmp_path) -> None:
    import json

    path = tmp_path / "config.json"
    closed = config_from_dict({"knot": "closed", "nodes": 100, "l0_over_d0": 18.0,
                               "youngs_modulus": 2e6})
    path.write_text(json.dumps(closed.to_dict()))
    parse = build_parser().parse_args
    opened = tie_config(parse(["tie", "open", "--config", str(path), "--force", "2"]))
    # The knot's own values go back to the open knot's defaults; the rest carries over.
    assert (opened.nodes, opened.twist, opened.length, opened.l0_over_d0) == \
        (default_nodes(0.185 / 8.5e-3, False), False, 0.185, None)
    assert opened.youngs_modulus == 2e6 and opened.force == 2.0
    # Another knot type of the same knot: its length changes, and the vertex count that
    # follows the length.
    eight = tie_config(parse(["tie", "--config", str(path), "--knot-type", "4_1"]))
    assert (eight.nodes, eight.l0_over_d0, eight.youngs_modulus) == (
        default_nodes(22.1, True), 22.1, 2e6)
