"""Cross-check FEM versus rod model on the coarse meshes: it runs, the report is complete
and honest, and the targets that the rod model meets stay met.

Measured on the coarse meshes (see the report of issue 4): indent force -0.3 % to -29 %
(met up to an approach of 0.048 D0 only), indent area within 1.1 points (met); wrap line
load -17 % to +435 %, curvature -19 % to +70 %, area within 5 points up to an approach of
0.12 D0. The misses are recorded, not asserted away.
"""

import json
import math

import pytest

pytest.importorskip("felupe")

from tightknot.fem.crosscheck import APPROACH_LIMIT, TARGETS, crosscheck  # noqa: E402


@pytest.fixture(scope="module")
def report(indent_coarse, wrap_coarse):
    return crosscheck("coarse", fem_results={"indent": indent_coarse, "wrap": wrap_coarse})


def test_report_keys_and_json(report):
    data = json.loads(json.dumps(report, allow_nan=False))
    for key in ("scenes", "fem_over_rod_time_ratio", "passed", "targets", "fem_wall_time_s",
                "rod_wall_time_s"):
        assert key in data
    assert set(data["scenes"]) == {"indent", "wrap"}
    for scene in data["scenes"].values():
        levels = scene["comparison"]["levels"]
        assert levels, "no load level compared"
        assert all(lv["approach_over_d0"] <= APPROACH_LIMIT + 1e-9 for lv in levels)
        for lv in levels:
            for key in ("force_rel", "area_points", "pressure_rel"):
                assert math.isfinite(lv[key])


def test_passed_is_every_target(report):
    met = all(all(lv["met"].values()) for s in report["scenes"].values()
              for lv in s["comparison"]["levels"])
    assert report["passed"] == (met and report["fem_over_rod_time_ratio"] >= 1000.0)
    for scene in report["scenes"].values():
        for lv in scene["comparison"]["levels"]:
            assert lv["met"]["force"] == (abs(lv["force_rel"]) <= TARGETS["force_rel"])


def test_time_ratio_is_measured(report):
    # both sides timed in this run: FEM tens of seconds, rod model about a second
    assert report["rod_wall_time_s"] > 0.0 and report["fem_wall_time_s"] > 0.0
    assert report["fem_over_rod_time_ratio"] == pytest.approx(
        report["fem_wall_time_s"] / report["rod_wall_time_s"])
    assert report["fem_over_rod_time_ratio"] > 1.0


def test_indent_targets_that_are_met(report):
    levels = report["scenes"]["indent"]["comparison"]["levels"]
    assert len(levels) == 9  # w = 0.15 (k/10)^2 D0 with 2 w <= 0.25 D0: k = 1..9
    for lv in levels:
        assert abs(lv["area_points"]) <= TARGETS["area_points"]  # measured <= 0.011
        assert lv["rod_converged"]
    # small loads: the calibrated point law and its kernel agree with the FEM
    for lv in levels[:2]:
        assert abs(lv["force_rel"]) <= TARGETS["force_rel"]  # measured -0.3 %, +4.4 %


def test_wrap_statics_and_met_targets(report):
    wrap = report["scenes"]["wrap"]
    for row in wrap["total_force_statics"]:
        assert row["fem_over_2T_sin_theta"] == pytest.approx(1.0, rel=1e-6)
    levels = wrap["comparison"]["levels"]
    for lv in levels:
        for key in ("force_rel", "area_points", "curvature_rel"):
            assert math.isfinite(lv[key])
        if lv["approach_over_d0"] <= 0.12:
            assert abs(lv["area_points"]) <= TARGETS["area_points"]  # measured <= 3.6 pts


@pytest.mark.slow
def test_cli_crosscheck_writes_json(tmp_path):
    import argparse

    from tightknot.fem.commands import register

    parser = argparse.ArgumentParser(prog="tightknot")
    register(parser.add_subparsers(dest="command"))
    out = tmp_path / "cc.json"
    args = parser.parse_args(["fem", "crosscheck", "--json", str(out)])
    code = args.handler(args)
    data = json.loads(out.read_text())
    assert code == (0 if data["passed"] else 1)
    assert data["fem_over_rod_time_ratio"] > 1.0
