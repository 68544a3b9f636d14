"""Smoke tests of the batch, scaling and tradeoff benchmarks at tiny sizes: the JSON keys
are there and the numbers finite (never their speed: targets live in the benchmarks)."""

import json
import math

import pytest

from tightknot.app.cli import main
from tightknot.benchmarks import batch, scaling, tradeoff


def _finite(v) -> bool:  # noqa: ANN001
    return isinstance(v, (int, float)) and math.isfinite(v)


def test_batch_bench_tiny(tmp_path):
    out = tmp_path / "batch.json"
    assert main(["bench", "batch", "--rods", "2", "--nodes", "48", "--json", str(out)]) == 0
    r = json.loads(out.read_text())
    for key in ("rods", "batched_s", "sequential_s", "speedup"):
        assert _finite(r[key]), key
    assert r["rods"] == 2 and r["sequential_extrapolated"] is False
    assert _finite(r["max_position_diff_over_D0"])  # agreement: tests/loading/test_batch.py
    assert r["speedup"] == pytest.approx(r["sequential_s"] / r["batched_s"])


def test_scaling_bench_tiny(tmp_path):
    out = tmp_path / "scaling.json"
    assert main(["bench", "scaling", "--sizes", "100", "200", "--json", str(out)]) == 0
    r = json.loads(out.read_text())
    assert [row["vertices"] for row in r["rows"]] == [100, 200]
    for row in r["rows"]:
        for key in ("newton_iteration_s", "elastic_s", "contact_s", "solve_s", "other_s"):
            assert _finite(row[key]) and row[key] >= 0.0, key
        assert row["contact_pairs_overlapping"] > 0  # the coil's turns do touch
        assert row["full_solve"]["converged"]
        assert _finite(row["full_solve"]["solve_s"])
    assert (tmp_path / "scaling.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_scaling_coil_contacts_grow_linearly():
    # Contact pairs per vertex that has a next turn stay constant: the turns touch at
    # every size (the last turn has no next one).
    turn = scaling.vertices_per_turn()
    small = scaling.iteration_parts(200, repeats=1)
    large = scaling.iteration_parts(800, repeats=1)
    per_small = small["contact_pairs_overlapping"] / (200 - turn)
    per_large = large["contact_pairs_overlapping"] / (800 - turn)
    # Within 10 %: the clamped ends perturb the first and last few pairs.
    assert per_large == pytest.approx(per_small, rel=0.1)


def test_tradeoff_tiny(tmp_path):
    spec = {"closed_trefoil": {"nodes": (40, 48), "levels": (), "level_nodes": ()}}
    r = tradeoff.run(spec, tolerances=(1e-3,))
    assert len(r["rows"]) == 2
    ref = [row for row in r["rows"] if row["reference"]]
    assert len(ref) == 1 and ref[0]["vertices"] == 48
    for row in r["rows"]:
        assert row["converged"], row["failure"]
        for key in ("wall_time_s", "measure", "min_area_ratio", "kappa_rms_error",
                    "measure_error", "area_error"):
            assert _finite(row[key]), key
    assert ref[0]["kappa_rms_error"] == 0.0
    out = tmp_path / "t.json"
    from tightknot.atomic import write_json_atomic
    write_json_atomic(out, r)  # NaN-free
    tradeoff.plot(r, tmp_path / "t.png")
    assert (tmp_path / "t.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bad_input():
    with pytest.raises(ValueError, match="rods"):
        batch.run(rods=0)
    with pytest.raises(ValueError, match="sizes"):
        scaling.run(sizes=(3,))
    with pytest.raises(ValueError, match="levels"):
        tradeoff._grid({"closed_trefoil": {"nodes": (40,), "levels": ("bogus",),
                                           "level_nodes": (40,)}}, (1e-3,))
    assert main(["bench", "batch", "--nodes", "10"]) == 2


def test_scaling_refuses_a_coil_tighter_than_its_rod(capsys):
    # One line naming the parameter and its range, exit 2, before any work.
    assert main(["bench", "scaling", "--sizes", "100", "--helix-radius", "0.5"]) == 2
    err = capsys.readouterr().err
    assert "helix_radius must be >= 0.75" in err and len(err.strip().splitlines()) == 1


def _report(contact: str, force: float, **extra) -> dict:
    """A cross-check report's minimal shape: indent and wrap comparisons, times."""
    cmp = {"comparison": {"levels": [{"force_rel": force, "area_points": 0.01,
                                      "curvature_rel": 0.02, "width_fraction": None}]}}
    scenes = {"indent": cmp, "wrap": cmp}
    return {"contact": contact, "scenes": scenes, "fem_wall_time_s": 100.0,
            "rod_wall_time_s": 1.0, "fem_over_rod_time_ratio": 100.0, "passed": False,
            "mesh": "medium", **extra}


def test_tradeoff_truth_table_takes_several_sectioned_reports(tmp_path, capsys):
    # bench tradeoff --fem XC --fem-sectioned A B: a sectioned row each, the bend shift's
    # named (the CLI path; the table's values: tests/fem/test_crosscheck.py)
    xc = _report("compliant", -0.1,
                 smoothed_contact_level=_report("compliant", -0.05))
    files = []
    for name, shift in (("a", False), ("b", True)):
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps(_report("sectioned", 0.03, section_bend_shift=shift)))
        files.append(str(path))
    fem = tmp_path / "xc.json"
    fem.write_text(json.dumps(xc))
    out = tmp_path / "truth.json"
    assert main(["bench", "tradeoff", "--fem", str(fem), "--fem-sectioned", *files,
                 "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "| sectioned |" in text and "| sectioned + bend shift |" in text
    rows = json.loads(out.read_text())["rows"]
    assert [r["level"] for r in rows] == ["compliant", "smoothed", "sectioned", "sectioned",
                                         "rigid"]
