"""Cross-check FEM versus rod model on the coarse meshes: it runs, the report is complete
and honest, and the targets that the rod model meets stay met.

The comparison itself runs on the medium mesh (``DEFAULT_MESH``, the calibration's); these
tests use the coarse one to stay fast. Measured on the coarse meshes with the default level
(each rod's section thinned by the rod's mean stretch; docs/fem_crosscheck.md): indent force
-4.0 % to +4.4 % from an approach of 0.027 D0 on and +2.9 % at 0.003 D0, +17.2 % at 0.012 D0
(where the coarse mesh's patch is below two elements and the coarse FEM is 19 % below the
medium one; the medium comparison there is -6.4 %), indent area within 2.2 points; wrap
curvature of the nominal axis +0.7 % to +7.3 % (met), area within 2.9 points (met), mid line
load -22 % to -32 % (missed). The misses are recorded, not asserted away."""

import json
import math

import pytest

pytest.importorskip("felupe")

from tightknot.fem.crosscheck import (  # noqa: E402
    APPROACH_LIMIT,
    DEFAULT_MESH,
    TARGETS,
    crosscheck,
)


@pytest.fixture(scope="module")
def report(indent_coarse, wrap_coarse, once_per_run):
    return once_per_run("crosscheck_report", lambda: crosscheck(
        "coarse", fem_results={"indent": indent_coarse, "wrap": wrap_coarse}, soft=False))


def test_default_mesh_is_the_calibration_mesh():
    from tightknot.fem.calibration import LAW_PATH

    assert DEFAULT_MESH == json.loads(LAW_PATH.read_text())["provenance"]["meshes"]["level"]


def test_report_keys_and_json(report):
    data = json.loads(json.dumps(report, allow_nan=False))
    for key in ("scenes", "fem_over_rod_time_ratio", "passed", "targets", "fem_wall_time_s",
                "rod_wall_time_s", "smoothed_contact_level"):
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
        assert abs(lv["area_points"]) <= TARGETS["area_points"]  # measured <= 0.022
        assert lv["rod_converged"]
    # the calibrated point law and its kernel agree with the FEM at the smallest approach
    # (measured +2.9 %) and from 0.027 D0 on (measured -4.0 % to +4.4 %); at 0.012 D0 the
    # coarse mesh itself is 19 % off the medium one (module docstring), so that level is
    # judged on the medium mesh only
    for lv in [levels[0], *levels[2:]]:
        assert abs(lv["force_rel"]) <= TARGETS["force_rel"]


def test_wrap_statics_and_met_targets(report):
    wrap = report["scenes"]["wrap"]
    for row in wrap["total_force_statics"]:
        assert row["fem_over_2T_sin_theta"] == pytest.approx(1.0, rel=1e-6)
    for lv in wrap["comparison"]["levels"]:
        for key in ("force_rel", "area_points", "curvature_rel"):
            assert math.isfinite(lv[key])


def test_indent_diagnostics_keep_the_crossing_tension_near_the_fem(report):
    rows = report["diagnostics"]["indent_axial"]["levels"]
    assert len(rows) == 9
    for row in rows:
        assert row["rod_nu0_converged"]
        if row["approach_over_d0"] < 0.025:
            continue  # patch radius below two elements of the coarse mesh
        # thinned by the rod's mean stretch, the contact puts an axial force into the rod at
        # the crossing of the FEM's order (measured 0.77 to 2.4 times it, largest at the
        # lightest levels); thinned by each edge's own stretch it was 3.4 to 29 times, with
        # the overlap 0.87 to 0.91 of w. A return of the local thinning fails these.
        assert row["rod_axial_force_mid_over_e_d0sq"] < 3.0 * row[
            "fem_axial_force_mid_over_e_d0sq"]
        assert row["rod_overlap_over_w"] > 0.95  # measured 0.97 to 0.99
        # all of the axial force comes from the radius's thinning with stretch: with nu = 0
        # it vanishes (measured |N| <= 3e-5 E D0^2 against 3e-4 to 0.011 with nu = 1/2)
        assert abs(row["rod_nu0_axial_force_mid_over_e_d0sq"]) < 0.05 * row[
            "rod_axial_force_mid_over_e_d0sq"]
        # the force is within the target either way (measured -4.0 to +4.4 %, with nu = 0
        # -2.5 to +6.3 %)
        assert abs(row["force_rel"]) <= TARGETS["force_rel"]
        assert abs(row["force_rel_rod_nu0"]) <= TARGETS["force_rel"]


def test_footprint_and_kernel_variant_diagnostics(report):
    fp = report["diagnostics"]["indent_footprint"]["levels"]
    assert len(fp) == 9
    for row in fp:
        assert math.isfinite(row["rod_equivalent_semi_axis_over_d0"])
        assert row["rod_equivalent_semi_axis_over_d0"] > 0
    variants = report["diagnostics"]["wrap_kernel_variants"]["variants"]
    assert [(v["kernel"], v["footprint"]) for v in variants] == [
        ("warp_without_core", None), ("point", 1.0), ("point", 2.0), ("line", 1.0)]
    shipped = variants[0]["levels"]  # the rod model's own kernel, without the core as they
    for lv, vv in zip(shipped, variants[1]["levels"], strict=True):
        # the re-implemented kernel gives the rod model's own comparison (0.5 points: the
        # two differ in the obstacle's quadrature, measured 0.3 %)
        assert vv["force_rel"] == pytest.approx(lv["force_rel"], abs=0.005)
        assert vv["curvature_rel"] == pytest.approx(lv["curvature_rel"], abs=0.005)
    for v in variants:
        assert all(lv["converged"] for lv in v["levels"])


def test_smoothed_level_keeps_the_crossing_tension_near_the_fem(report):
    sm = report["smoothed_contact_level"]
    assert sm["radius_window_d0"] == 1.0
    assert sm["passed"] == (all(s["comparison"]["passed"] for s in sm["scenes"].values())
                            and sm["fem_over_rod_time_ratio"] >= 1000.0)
    smooth = sm["scenes"]["indent"]["comparison"]["levels"]
    for s, ax in zip(smooth, sm["indent_axial"], strict=True):
        if s["approach_over_d0"] < 0.025:
            continue  # patch radius below two elements of the coarse mesh
        # the window spreads the thinning over +-1 D0: the force is within the target
        # (measured -5.0 % to +3.8 %) ...
        assert abs(s["force_rel"]) <= TARGETS["force_rel"]
        # ... and the axial force at the crossing stays above the default level's (the
        # window's mean over 2 D0 of the crossing is stretched more than the whole rod:
        # measured 1.4 to 1.45 times it)
        assert ax["rod_axial_force_mid_over_e_d0sq"] > ax[
            "default_level_rod_axial_force_mid_over_e_d0sq"]
    # at the deepest level the axial force is the FEM's (measured 1.09 times it; 3.4 times
    # with the edge's own stretch); 1.5: twice the coarse mesh's error on forces
    last = sm["indent_axial"][-1]
    assert last["rod_axial_force_mid_over_e_d0sq"] < 1.5 * last["fem_axial_force_mid_over_e_d0sq"]
    for lv in sm["scenes"]["wrap"]["comparison"]["levels"]:
        assert abs(lv["curvature_rel"]) <= TARGETS["curvature_rel"]  # measured <= 7.9 %
        assert abs(lv["area_points"]) <= TARGETS["area_points"]  # measured <= 1.4 points


def test_wrap_nominal_axis_is_the_rod_centerline(report):
    wrap = report["scenes"]["wrap"]
    levels = wrap["comparison"]["levels"]
    assert len(levels) == 5  # T = 0.25 (k/6)^2 E D0^2, centroid approach <= 0.25: k = 1..5
    for lv, cen in zip(levels, wrap["centroid_axis"], strict=True):
        # the nominal axis's approach matches the rod's centerline (measured within
        # 0.02 D0); the centroid's lags by up to 0.066 D0
        assert abs(cen["fem_approach_nominal_over_d0"] - lv["rod_approach_over_d0"]) < 0.025
        # its curvature too (measured +0.7 % to +7.3 %: the target, which is met)
        assert abs(lv["curvature_rel"]) <= TARGETS["curvature_rel"]
        assert abs(lv["area_points"]) <= TARGETS["area_points"]  # measured <= 2.9 points
    # the centroid line bends far more at low tension (measured kappa D0 0.505 vs 0.184)
    assert wrap["centroid_axis"][0]["fem_kappa_d0_centroid"] > 2.0 * levels[0]["fem_kappa_d0"]


@pytest.mark.slow
def test_cli_crosscheck_writes_json(tmp_path):
    import argparse

    from tightknot.fem.commands import register

    parser = argparse.ArgumentParser(prog="tightknot")
    register(parser.add_subparsers(dest="command"))
    out = tmp_path / "cc.json"
    # coarse: the default (medium) takes about 8 minutes on 2 cores
    args = parser.parse_args(["fem", "crosscheck", "--mesh", "coarse", "--json", str(out)])
    code = args.handler(args)
    data = json.loads(out.read_text())
    assert code == (0 if data["passed"] else 1)
    assert data["mesh"] == "coarse"
    assert data["fem_over_rod_time_ratio"] > 1.0


def test_level_truth_reads_each_level_off_the_report(report):
    # bench tradeoff --fem: the table is the report's own comparisons, level by level
    from tightknot.benchmarks.level_truth import format_table, level_truth

    table = level_truth(report)
    rows = {r["level"]: r for r in table["rows"]}
    ind = [lv["force_rel"] for lv in report["scenes"]["indent"]["comparison"]["levels"]]
    assert rows["compliant"]["indent_force_rel"] == [min(ind), max(ind)]
    sm = report["smoothed_contact_level"]["scenes"]["wrap"]["comparison"]["levels"]
    assert rows["smoothed"]["wrap_line_load_rel"] == [min(lv["force_rel"] for lv in sm),
                                                     max(lv["force_rel"] for lv in sm)]
    assert rows["rigid"]["fem_errors"] is None and "compliance" in rows["rigid"]["reason"]
    assert "| compliant |" in format_table(table)
    with pytest.raises(ValueError, match="cross-check report"):
        level_truth({"rows": []})


def test_the_sectioned_level_reuses_the_fem_and_joins_the_table(report):
    # crosscheck --contact sectioned --fem-json: the FEM results a report keeps are reused
    # (no FEM run: the sectioned rod models only), and bench tradeoff --fem-sectioned adds
    # the level's row with its contact width's miss
    from tightknot.benchmarks.level_truth import format_table, level_truth
    from tightknot.fem.crosscheck import crosscheck

    sec = crosscheck(mesh="coarse", fem_results=report["fem_results"], contact="sectioned",
                     soft=False)
    assert sec["contact"] == "sectioned" and sec["section_modes"] == 8
    assert sec["fem_wall_time_s"] == report["fem_wall_time_s"]  # the same FEM runs
    assert all(lv["rod_converged"] for s in sec["scenes"].values()
               for lv in s["comparison"]["levels"])
    # indent and wrap along their contact (issue 18: L_c within 0.1 and A/A0 within 5
    # points along the contact): both sides' profiles at every level, judged; on the
    # coarse mesh the sectioned level meets both in the wrap (2026-12-08: within 0.051 and
    # 2.9 points; the indent's L_c is missed by up to 0.139, reported, not asserted); the
    # compliant level has no profile to compare
    for name in ("indent", "wrap"):
        comp = sec["scenes"][name]["comparison"]
        for lv in comp["levels"]:
            prof = lv["profile_a"]
            assert prof["rows"][0]["s_over_d0"] == 0.0 and prof["layers"] >= 1
            assert lv["met"]["width_profile_a"] == (prof["width_fraction_max"]
                                                    <= TARGETS["width_fraction"])
            assert lv["met"]["area_profile_a"] == (prof["area_points_max"]
                                                   <= TARGETS["area_points"])
        assert comp["worst"]["width_profile"] == max(
            lv["profile_a"]["width_fraction_max"] for lv in comp["levels"])
        assert not any("profile_a" in lv
                       for lv in report["scenes"][name]["comparison"]["levels"])
    wrap = sec["scenes"]["wrap"]["comparison"]
    assert all(lv["met"]["width_profile_a"] and lv["met"]["area_profile_a"]
               for lv in wrap["levels"])
    rows = {r["level"]: r for r in level_truth(report, None, sec)["rows"]}
    wc = [lv["width_fraction"] for s in sec["scenes"].values()
          for lv in s["comparison"]["levels"] if lv["width_fraction"] is not None]
    assert rows["sectioned"]["width_fraction_max"] == max(abs(w) for w in wc)
    assert rows["sectioned"]["width_profile_max"] == max(
        sec["scenes"][n]["comparison"]["worst"]["width_profile"] for n in ("indent", "wrap"))
    assert rows["compliant"]["width_profile_max"] is None  # no profile at that level
    text = format_table(level_truth(report, None, sec))
    line = next(t for t in text.splitlines() if t.startswith("| sectioned |"))
    assert "along the contact)" in line
    with pytest.raises(ValueError, match="sectioned level"):
        level_truth(report, None, report)
    # several sectioned reports, a row each (with and without the bend shift), and the
    # two-soft-rod scenes' rows where a report carries them
    soft = {"levels": {"sectioned": {"scenes": {
        "clasp": {"comparison": {"levels": [{"force_rel": 0.1}, {"force_rel": -0.2}],
                                 "worst": {"width_profile": 0.137}},
                  "fem_over_rod_time_ratio": 500.0}}}}}
    shifted = {**sec, "section_bend_shift": True, "soft_scenes": soft}
    table = level_truth(report, None, [sec, shifted])
    both = [r for r in table["rows"] if r["level"] == "sectioned"]
    assert [r["section_bend_shift"] for r in both] == [False, True]
    assert both[0]["soft"] is None
    assert both[1]["soft"] == {"clasp_force_rel": [-0.2, 0.1],
                               "clasp_fem_over_rod_time_ratio": 500.0,
                               "clasp_width_profile_max": 0.137}
    text = format_table(table)
    assert "| sectioned + bend shift |" in text and "-20.0 .. +10.0 %" in text
    # the nip's L_c along the contact where the report compares it, n/a where not
    shift_line = next(t for t in text.splitlines() if t.startswith("| sectioned + bend"))
    assert "| 0.14 |" in shift_line
    assert all(t.count("|") == shift_line.count("|") for t in text.splitlines()
               if t.startswith("| "))
    assert "soft wrap and the clasp at compliant, smoothed, sectioned" in table["not_covered"]
    # reports at two rod resolutions name them in their rows (one alone does not)
    finer = {**sec, "rod_edges_per_d0": 24}
    text = format_table(level_truth(report, None, [sec, finer]))
    assert "| sectioned, 24 edges per D0 |" in text
    assert f"| sectioned, {sec['rod_edges_per_d0']} edges per D0 |" in text


def test_each_compared_level_has_the_fem_spread_beside_it() -> None:
    """Given the coarser mesh's run at the same levels, every compared row reports the
    FEM's own force and area differences (ground rule 4), and the comparison its largest;
    without one, None (the coarse mesh has no coarser)."""
    from tightknot.fem.crosscheck import _compare

    def step(force, approach, area):
        return {"approach_over_d0": approach, "force": force, "area_ratio_mid": area,
                "peak_pressure_over_e": 0.1}

    fem = [step(1.0, 0.1, 0.99), step(2.0, 0.2, 0.97), step(3.0, 0.3, 0.95)]
    coarse = [step(1.1, 0.1, 0.98), step(1.9, 0.2, 0.975), step(3.0, 0.3, 0.9)]
    rod = [dict(step(1.05, 0.1, 0.985), converged=True),
           dict(step(2.0, 0.2, 0.97), converged=True),
           dict(step(3.0, 0.3, 0.95), converged=True)]
    out = _compare(fem, rod, ("force", "force"), None, spread_steps=coarse)
    assert len(out["levels"]) == 2  # the third lies past the approach limit
    first, second = out["levels"]
    assert first["fem_spread_rel"]["force"] == pytest.approx(1.0 / 1.1 - 1.0)
    assert first["fem_spread_rel"]["area_points"] == pytest.approx(0.01)
    assert second["fem_spread_rel"]["force"] == pytest.approx(2.0 / 1.9 - 1.0)
    assert out["fem_force_spread_max"] == pytest.approx(abs(1.0 / 1.1 - 1.0))
    # a coarser run at other load levels gives no spread
    moved = [dict(c, w_over_d0=0.5) for c in coarse]
    fem_w = [dict(f, w_over_d0=0.25) for f in fem]
    assert all(r["fem_spread_rel"] is None for r in
               _compare(fem_w, rod, ("force", "force"), None, spread_steps=moved)["levels"])
    plain = _compare(fem, rod, ("force", "force"), None)
    assert all(r["fem_spread_rel"] is None for r in plain["levels"])
    assert plain["fem_force_spread_max"] is None


def test_a_finer_run_adds_the_third_mesh_beside_each_level() -> None:
    """Given the next finer mesh's run (never run by the cross-check itself), each
    compared level also reports the compared mesh's difference from it and the rod
    model's force error against it; levels the finer run does not hold get neither, and
    ``passed`` does not read them."""
    from tightknot.fem.crosscheck import _compare

    def step(force, approach, area, w):
        return {"approach_over_d0": approach, "force": force, "area_ratio_mid": area,
                "peak_pressure_over_e": 0.1, "w_over_d0": w}

    fem = [step(1.0, 0.1, 0.99, 0.05), step(2.0, 0.2, 0.97, 0.1)]
    rod = [dict(step(1.05, 0.1, 0.985, 0.05), converged=True),
           dict(step(2.0, 0.2, 0.97, 0.1), converged=True)]
    fine = [step(1.2, 0.1, 0.985, 0.05)]  # the first level only
    out = _compare(fem, rod, ("force", "force"), None, finer_steps=fine)
    first, second = out["levels"]
    assert first["fem_spread_finer_rel"]["force"] == pytest.approx(1.0 / 1.2 - 1.0)
    assert first["fem_spread_finer_rel"]["area_points"] == pytest.approx(0.005)
    assert first["force_rel_finer"] == pytest.approx(1.05 / 1.2 - 1.0)
    assert "force_rel_finer" not in second and "fem_spread_finer_rel" not in second
    assert out["fem_force_spread_finer_max"] == pytest.approx(abs(1.0 / 1.2 - 1.0))
    assert out["force_rel_finer_worst"] == pytest.approx(abs(1.05 / 1.2 - 1.0))
    assert out["passed"] == _compare(fem, rod, ("force", "force"), None)["passed"]
    assert "fem_force_spread_finer_max" not in _compare(fem, rod, ("force", "force"), None)
