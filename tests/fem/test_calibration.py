"""The shipped contact law: well-formed, and reproduced by a re-calibration on the
coarsest meshes within the measured mesh error."""

import json

import numpy as np
import pytest

from tightknot.fem.calibration import LAW_PATH, hertz_defaults, power_fit

LAWS = {  # law name -> (k key, p key)
    "line": ("k_line", "p_line"),
    "width": ("k_width", "p_width"),
    "contact_fraction": ("c_lc", "p_lc"),
    "pmax_line": ("k_pmax_line", "p_pmax_line"),
    "point": ("k_point", "p_point"),
    "patch_axial": ("k_patch_axial", "p_patch_axial"),
    "patch_transverse": ("k_patch_transverse", "p_patch_transverse"),
    "pmax_point": ("k_pmax_point", "p_pmax_point"),
    "area": ("k_area", "p_area"),
}

# Coarse-versus-medium difference of each fitted law, max over w/D0 in [0.02, 0.15],
# measured when the law was shipped: line 1.8 %, width 3.9 %, contact fraction 4.0 %,
# line peak pressure 2.8 %, point force 7.3 %, patch axial 2.6 %, patch transverse 3.9 %,
# point peak pressure 9.7 %, area deficit 1.6 %. Most of it is the unresolved smallest
# steps (w/D0 < 0.01, patch below two elements) pulling the log-log fit; the values at
# w/D0 = 0.15 agree within 1.3 % (indent force) and 0.2 % (squeeze force). Tolerance:
# the measured difference plus a third, so a change of the physics or of a definition
# (tens of %) fails while the known discretisation error passes.
COARSE_TOLERANCE = {
    "line": 0.025, "width": 0.052, "contact_fraction": 0.053, "pmax_line": 0.038,
    "point": 0.098, "patch_axial": 0.035, "patch_transverse": 0.052, "pmax_point": 0.13,
    "area": 0.022,
}


@pytest.fixture(scope="module")
def shipped():
    return json.loads(LAW_PATH.read_text())


def _law(law, name, w):
    k, p = LAWS[name]
    return law[k] * w ** law[p]


def test_shipped_law_is_documented(shipped):
    for k_key, p_key in LAWS.values():
        assert shipped[k_key] > 0.0 and 0.0 < shipped[p_key] < 3.0
    assert set(shipped["residuals"]) == set(LAWS)
    prov = shipped["provenance"]
    for key in ("felupe_version", "date", "bulk_modulus_pa", "meshes", "scenes"):
        assert key in prov
    assert "centroid" in shipped["definitions"]["w"]
    assert shipped["w_hat_max"] == pytest.approx(0.15)


def test_point_law_is_near_hertz_at_small_load(shipped):
    # the FEM point law at w/D0 = 0.0135 within 6 % of Hertz crossed cylinders (rigid
    # indenter), same bound and reason as test_indent; a fit error adds a few %: 10 %
    w = 0.0135
    hz = hertz_defaults()
    assert _law(shipped, "point", w) == pytest.approx(hz["k_point"] * w ** hz["p_point"],
                                                      rel=0.10)


def test_power_fit_recovers_exact_law():
    w = np.geomspace(1e-3, 0.15, 9)
    fit = power_fit(w, 0.7 * w**1.3)
    assert fit["k"] == pytest.approx(0.7, rel=1e-9) and fit["p"] == pytest.approx(1.3)
    assert fit["max_rel_error"] < 1e-9


def test_coarse_recalibration_agrees_with_shipped_law(shipped):
    pytest.importorskip("felupe")
    from tightknot.fem.calibration import calibrate

    coarse = calibrate(mesh="coarse")
    w = np.linspace(0.02, 0.15, 14)
    for name, tol in COARSE_TOLERANCE.items():
        diff = np.max(np.abs(_law(coarse, name, w) / _law(shipped, name, w) - 1.0))
        assert diff < tol, f"{name}: {diff:.3f} >= {tol}"


def test_soft_crossing_point_law_recovers_a_power_law_and_replaces_only_the_point_law():
    from dataclasses import fields

    from tightknot.contact.law import RadialComplianceLaw
    from tightknot.fem.calibration import soft_crossing_point_law, with_point_law

    w = np.array([0.01, 0.04, 0.09, 0.15, 0.2])  # the last lies past the fitted range
    steps = [{"w_over_d0": x, "force_over_e_d0sq": 3.8 * x**1.65,
              "semi_axis_axial_over_d0": 1.2 * x**0.52,
              "peak_pressure_over_e": 1.3 * x**0.6} for x in w]
    steps[-1]["force_over_e_d0sq"] = 1e3  # would spoil the fit if it were read
    fit = soft_crossing_point_law({"steps": steps, "mesh": {"level": "coarse"}})
    assert fit["w_hat"] == pytest.approx(w[:4].tolist())
    for k, p, kv, pv in (("k_point", "p_point", 3.8, 1.65), ("k_patch", "p_patch", 1.2, 0.52),
                         ("k_pmax_point", "p_pmax_point", 1.3, 0.6)):
        assert fit[k] == pytest.approx(kv, rel=1e-9) and fit[p] == pytest.approx(pv, rel=1e-9)
    assert max(fit["residuals"].values()) < 1e-9
    shipped = RadialComplianceLaw.from_json()
    refit = with_point_law(shipped, fit, "a test")
    changed = {f.name for f in fields(shipped)
               if getattr(shipped, f.name) != getattr(refit, f.name)}
    assert changed == {"k_point", "p_point", "k_patch", "p_patch", "k_pmax_point",
                       "p_pmax_point", "source"}
    with pytest.raises(ValueError, match="two or more load steps"):
        soft_crossing_point_law({"steps": steps[:1]})


def test_crossing_law_bench_bad_input_exits_2(tmp_path, capsys):
    # bench/crossing_law.py: a report without the soft scenes, or a --fit file that is not
    # a soft crossing, is one line on stderr and exit 2, nothing written
    import sys
    from pathlib import Path

    bench = Path(__file__).resolve().parents[2] / "bench"
    sys.path.insert(0, str(bench))
    try:
        import crossing_law
    finally:
        sys.path.remove(str(bench))
    report = tmp_path / "r.json"
    report.write_text(json.dumps({"fem_results": {"indent": {"scene": "indent"}}}))
    out = tmp_path / "out.json"
    assert crossing_law.main(["--fem-json", str(report), "--out", str(out)]) == 2
    assert "--fit: not a soft_crossing scene result" in capsys.readouterr().err
    wrong = tmp_path / "w.json"
    wrong.write_text(json.dumps({"scene": "indent", "steps": []}))
    assert crossing_law.main(["--fem-json", str(report), "--fit", str(wrong)]) == 2
    assert "--fit: not a soft_crossing" in capsys.readouterr().err
    fit = tmp_path / "x.json"
    fit.write_text(json.dumps({"scene": "soft_crossing", "mesh": {"level": "coarse"},
                               "steps": [{"w_over_d0": 0.01, "force_over_e_d0sq": 1e-3,
                                          "semi_axis_axial_over_d0": 0.1,
                                          "peak_pressure_over_e": 0.1},
                                         {"w_over_d0": 0.04, "force_over_e_d0sq": 1e-2,
                                          "semi_axis_axial_over_d0": 0.2,
                                          "peak_pressure_over_e": 0.2}]}))
    assert crossing_law.main(["--fem-json", str(report), "--fit", str(fit),
                              "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "holds no FEM result of ['soft_wrap', 'clasp', 'soft_crossing']" \
        in err[0]
    assert not out.exists()
