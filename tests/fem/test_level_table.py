"""The FEM's three-mesh table at every load level (tightknot.fem.scenes._common.level_table)
and the bench that prints it for the soft scenes (bench/fem_three_mesh.py)."""

import json
import sys
from pathlib import Path

import pytest

from tightknot.fem.scenes._common import level_table

ROOT = Path(__file__).resolve().parents[2]


def _result(mesh, forces, loads=(0.1, 0.2), area=0.9):
    return {"scene": "soft_crossing", "mesh": {"level": mesh, "dofs": 10, "elements": 2},
            "wall_time_s": 1.0,
            "steps": [{"w_over_d0": w, "force_over_e_d0sq": f, "area_ratio_mid": area}
                      for w, f in zip(loads, forces, strict=True)]}


def test_values_of_the_finest_and_the_others_relative_to_them():
    rows = level_table({"coarse": _result("coarse", [1.1, 2.4]),
                        "medium": _result("medium", [1.05, 1.9]),
                        "fine": _result("fine", [1.0, 2.0])},
                       ["force_over_e_d0sq", "area_ratio_mid", "absent"], "w_over_d0")
    assert [r["load"] for r in rows] == [0.1, 0.2]
    assert rows[1]["finest"] == "fine"
    assert rows[1]["values"] == {"force_over_e_d0sq": 2.0, "area_ratio_mid": 0.9,
                                 "absent": None}
    assert rows[1]["relative"]["coarse"]["force_over_e_d0sq"] == pytest.approx(0.2)
    assert rows[1]["relative"]["medium"]["force_over_e_d0sq"] == pytest.approx(-0.05)
    assert rows[0]["relative"]["medium"]["area_ratio_mid"] == 0.0
    assert rows[0]["relative"]["coarse"]["absent"] is None
    # two meshes are a table too, the finer one the reference
    two = level_table({"coarse": _result("coarse", [1.1, 2.4]),
                       "medium": _result("medium", [1.0, 2.0])}, ["force_over_e_d0sq"],
                      "w_over_d0")
    assert two[0]["finest"] == "medium" and list(two[0]["relative"]) == ["coarse"]


def test_results_that_are_not_one_table_are_refused():
    fine = _result("fine", [1.0, 2.0])
    with pytest.raises(ValueError, match="two or more"):
        level_table({"fine": fine}, ["force_over_e_d0sq"], "w_over_d0")
    with pytest.raises(ValueError, match="two or more"):
        level_table({"finest": fine, "fine": fine}, ["force_over_e_d0sq"], "w_over_d0")
    with pytest.raises(ValueError, match="different load levels"):
        level_table({"medium": _result("medium", [1.0], loads=(0.1,)), "fine": fine},
                    ["force_over_e_d0sq"], "w_over_d0")
    # the same number of levels at other loads is not the same table
    with pytest.raises(ValueError, match="w_over_d0"):
        level_table({"medium": _result("medium", [1.0, 2.0], loads=(0.1, 0.25)),
                     "fine": fine}, ["force_over_e_d0sq"], "w_over_d0")


def test_bench_reads_scene_results_and_reports_and_writes_json(tmp_path, capsys):
    sys.path.insert(0, str(ROOT / "bench"))
    try:
        import fem_three_mesh
    finally:
        sys.path.remove(str(ROOT / "bench"))
    (tmp_path / "fine.json").write_text(json.dumps(_result("fine", [1.0, 2.0])))
    # a cross-check report holds the scene on its mesh and on the spread mesh
    report = {"fem_results": {"soft_crossing": _result("medium", [1.05, 1.9]),
                              "soft_crossing@coarse": _result("coarse", [1.1, 2.4]),
                              "soft_wrap": {"scene": "soft_wrap"}}}
    (tmp_path / "report.json").write_text(json.dumps(report))
    found = fem_three_mesh.scene_results([tmp_path / "report.json", tmp_path / "fine.json"],
                                         "soft_crossing")
    assert sorted(found) == ["coarse", "fine", "medium"]
    out = tmp_path / "table.json"
    rc = fem_three_mesh.main(["soft_crossing", "--json", str(tmp_path / "report.json"),
                              str(tmp_path / "fine.json"), "--out", str(out)])
    assert rc == 0
    table = json.loads(out.read_text())
    assert table["levels"][1]["relative"]["coarse"]["force_over_e_d0sq"] == pytest.approx(0.2)
    assert "+20.0 %" in capsys.readouterr().out
    # one mesh only: a clear error, exit 2, nothing written
    out.unlink()
    assert fem_three_mesh.main(["soft_crossing", "--json", str(tmp_path / "fine.json"),
                                "--out", str(out)]) == 2
    assert not out.exists()
    assert "two or more" in capsys.readouterr().err
