"""A sweep store as a flat table (csv, parquet, DataFrame) and the tightness plots."""

import csv
import json
import math
from pathlib import Path

import pytest

from tightknot.app.cli import main
from tightknot.sweep import Store, grid, run_sweep, table_rows, write_table
from tightknot.sweep.cases import CASE_KEYS, defaults
from tightknot.sweep.executors import SerialExecutor


@pytest.fixture(scope="module")
def force_store(tmp_path_factory) -> Path:
    # The 185 mm open trefoil at 90 vertices (about the fewest its edges allow), two force
    # levels on one path: about 2 s.
    folder = tmp_path_factory.mktemp("sweep") / "s"
    cases = grid({"knot": "open", "nodes": 90, "tighten_steps": 20, "pull_force": [2.0, 3.0]})
    report = run_sweep(cases, folder, SerialExecutor())
    assert report.ok
    return folder


def test_one_row_per_level_with_every_parameter_and_default(force_store: Path) -> None:
    rows = table_rows(force_store)
    assert [r["level_target"] for r in rows] == [2.0, 3.0]
    (record,) = Store.open(force_store, create=False).records()
    given = {"knot", "nodes", "tighten_steps", "pull_force"}
    for key, value in defaults("open").items():
        assert key in rows[0], key
        if key not in given:
            assert rows[0][key] == value, key  # a default, written out
    assert set(CASE_KEYS["open"]) <= set(rows[0])
    for row, level in zip(rows, record["result"]["levels"], strict=True):
        s = level["summary"]
        assert row["reached"] is True and row["pull_force_N"] == level["target"]
        assert row["lambda_oc"] == s["lambda_oc"] and row["min_area_ratio"] == s["min_area_ratio"]
        assert row["outside_calibrated_range"] is s["outside_calibrated_range"]
        assert row["warnings"] == "; ".join(s["warnings"])
        x = s["centerline_m"]
        assert row["end_to_end_m"] == math.dist(x[0], x[-1])
    # A harder pull: a longer rod, a shorter knot.
    assert rows[1]["end_to_end_m"] > rows[0]["end_to_end_m"]
    assert rows[1]["lambda_oc"] < rows[0]["lambda_oc"]


def test_csv_and_parquet_and_dataframe_agree(force_store: Path, tmp_path: Path) -> None:
    rows = table_rows(force_store)
    out = tmp_path / "t.csv"
    assert main(["table", str(force_store), "--out", str(out), "--quiet"]) == 0
    with out.open() as handle:
        back = list(csv.DictReader(handle))
    assert len(back) == 2 and list(back[0]) == list(rows[0])
    # repr floats: the csv holds every digit.
    assert float(back[1]["end_to_end_m"]) == rows[1]["end_to_end_m"]
    assert main(["table", str(force_store), "--out", str(out), "--quiet"]) == 2  # exists
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    from tightknot.sweep import to_dataframe

    frame = to_dataframe(force_store)
    assert list(frame.columns) == list(rows[0]) and len(frame) == 2
    pq = tmp_path / "t.parquet"
    assert main(["table", str(force_store), "--out", str(pq), "--quiet"]) == 0
    pd.testing.assert_frame_equal(pd.read_parquet(pq), frame)


def test_bad_table_outputs_exit_2(force_store: Path, tmp_path: Path, capsys) -> None:
    assert main(["table", str(force_store), "--out", str(tmp_path / "t.xlsx")]) == 2
    assert "must end in .csv or .parquet" in capsys.readouterr().err
    assert main(["table", str(tmp_path / "none"), "--out", str(tmp_path / "t.csv")]) == 2
    assert "no such folder" in capsys.readouterr().err
    assert not (tmp_path / "t.csv").exists()


def test_a_missed_level_is_a_marked_row(tmp_path: Path) -> None:
    # A synthetic record (the file format only): the first level missed, the second reached.
    case = grid({"knot": "open", "nodes": 90, "pull_force": [0.3, 3.0]})[0]
    summary = {"knot_type": "3_1", "pull_force_N": 3.0, "lambda_oc": 12.0, "stretch": 1.07,
               "centerline_m": [[0, 0, 0], [0.1, 0, 0]], "min_area_ratio": 0.87,
               "outside_calibrated_range": True,
               "warnings": ["the contact reaches w/D0 = 0.2", "a crossing reaches w/D0 = 0.2"]}
    levels = [{"kind": "pull_force", "target": 0.3, "reached": False, "failure": "slipped",
               "pull_force_N": 1.4, "lambda_oc": None, "newton_iterations": 9, "solves": 3,
               "wall_time_s": 0.1, "summary": None},
              {"kind": "pull_force", "target": 3.0, "reached": True, "failure": "",
               "pull_force_N": 3.0, "lambda_oc": 12.0, "newton_iterations": 5, "solves": 1,
               "wall_time_s": 0.1, "summary": summary}]
    store = Store.open(tmp_path / "s")
    store.put({"id": case.id, "params": case.params, "status": "ok", "failure": "",
               "warnings": ["level pull_force = 0.3 not reached: slipped"],
               "result": {"levels": levels, "table": []}, "wall_time_s": 0.2})
    rows = table_rows(store)
    assert [(r["reached"], r["level_failure"]) for r in rows] == [(False, "slipped"),
                                                                    (True, None)]
    assert rows[0]["stretch"] is None and rows[0]["pull_force_N"] == 1.4
    # the level outside its model's range says so in its row
    assert rows[0]["outside_calibrated_range"] is None and rows[0]["warnings"] is None
    assert rows[1]["outside_calibrated_range"] is True
    assert rows[1]["warnings"] == ("the contact reaches w/D0 = 0.2; a crossing reaches w/D0 "
                                   "= 0.2")
    assert rows[1]["end_to_end_m"] == pytest.approx(0.1, abs=1e-15)  # exact up to rounding
    assert write_table(store, tmp_path / "t.csv") == 2


def test_plot_writes_the_tightness_figures(force_store: Path, tmp_path: Path, capsys) -> None:
    from tightknot.viz.sweep_figures import FIGURES

    out = tmp_path / "figs"
    assert main(["plot", str(force_store), "--out", str(out)]) == 0
    for name in FIGURES:
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    printed = capsys.readouterr().out
    assert all(name in printed for name in FIGURES)
    assert main(["plot", str(force_store), "--out", str(out), "--quiet"]) == 2  # exists
    assert main(["plot", str(force_store), "--out", str(out), "--quiet", "--overwrite"]) == 0


def test_plot_of_a_store_without_levels_is_bad_input(tmp_path: Path, capsys) -> None:
    case = grid({"knot": "closed", "nodes": 60})[0]
    store = Store.open(tmp_path / "c")
    store.put({"id": case.id, "params": case.params, "status": "ok", "failure": "",
               "result": {"knot_type": "3_1", "stretch": 1.07}, "wall_time_s": 1.0})
    (row,) = table_rows(store)
    assert row["l0_over_d0"] == defaults("closed")["l0_over_d0"] and row["level_kind"] is None
    assert main(["plot", str(tmp_path / "c")]) == 2
    assert "no open-knot levels" in capsys.readouterr().err
    json.loads((tmp_path / "c" / "index.json").read_text())  # the store is untouched


def test_plotted_levels_outside_the_calibrated_range_are_marked(tmp_path: Path) -> None:
    """A reached level that left its contact model's range is drawn ringed (it is split
    out from the reached ones), a missed one as a cross; the figures are written."""
    from tightknot.viz.sweep_figures import FIGURES, marked_levels, plot_tightness_sweep

    def level(force, lam, reached=True, outside=False):
        return {"case_id": "c", "status": "ok", "knot": "open", "level_kind": "pull_force",
                "reached": reached, "pull_force_N": force, "lambda_oc": lam,
                "end_to_end_m": 0.1 + 0.01 * force, "stretch": 1.0 + 0.01 * force,
                "min_area_ratio": 1.0 - 0.02 * force, "outside_calibrated_range": outside,
                "length": 0.185, "nodes": 90}

    rows = [level(2.0, 15.0), level(5.0, 11.0, outside=True), level(9.0, 9.0, reached=False)]
    ok, missed, outside = marked_levels(rows, "lambda_oc", "pull_force_N")
    assert [r["pull_force_N"] for r in ok] == [2.0, 5.0]
    assert [r["pull_force_N"] for r in missed] == [9.0]
    assert [r["pull_force_N"] for r in outside] == [5.0]
    paths = plot_tightness_sweep(rows, ["length", "nodes"], tmp_path / "figs")
    assert sorted(p.name for p in paths) == sorted(FIGURES)
    assert all(p.stat().st_size > 0 for p in paths)
