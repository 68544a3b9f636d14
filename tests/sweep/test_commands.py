"""``tightknot sweep``: exit codes, the store and the JSON summary, resuming from the CLI."""

import json
from pathlib import Path

import pytest

from tightknot.app.cli import main


@pytest.mark.parametrize(("argv", "words"), [
    (["open"], "needs its levels"),
    (["closed", "--length", "0.1"], "--length: for open knots only"),
    (["open", "--l0-over-d0", "18", "--force", "1"], "--l0-over-d0: for closed knots only"),
    (["closed", "--workers", "0"], "--workers must be >= 1"),
    (["closed", "--nodes", "10"], "nodes: 10 is out of range; valid: [24, 200000]"),
    (["closed", "--poisson", "0.6"], "poisson: 0.6 is out of range; valid: (-1, 0.5]"),
    (["open", "--force", "1", "-2"], "pull_force[1]: -2.0 is out of range"),
    (["closed", "--scheduler", "tcp://x:1"], "--scheduler is for --executor dask"),
    (["closed", "--batch", "0"], "--batch must be >= 1"),
    (["open", "--force", "1", "--batch", "4"], "--batch is for closed knots"),
])
def test_bad_input_exits_2_with_one_line(tmp_path: Path, capsys: pytest.CaptureFixture,
                                         argv: list[str], words: str) -> None:
    assert main(["sweep", *argv, "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1
    assert not (tmp_path / "s").exists()  # nothing written before the input is checked


def test_every_multi_valued_option_is_an_axis() -> None:
    from tightknot.app.cli import build_parser
    from tightknot.sweep.commands import build_cases

    args = build_parser().parse_args([
        "sweep", "open", "--out", "x", "--length", "0.185", "0.16", "--nodes", "150", "300",
        "--twist", "on", "off", "--contact", "compliant", "rigid", "--lambda", "13", "14"])
    cases = build_cases(args)
    assert len(cases) == 16 and len({c.id for c in cases}) == 16
    # The levels stay one path per case, loosest first.
    assert all(c.params["target_lambda"] == [14.0, 13.0] for c in cases)
    assert {c.params["twist"] for c in cases} == {True, False}


def test_a_missing_store_parent_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["sweep", "closed", "--out", str(tmp_path / "no" / "s")]) == 2
    assert "parent folder of the sweep store does not exist" in capsys.readouterr().err


def test_a_sweep_runs_resumes_and_reports_a_failed_case(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture) -> None:
    out, js = tmp_path / "s", tmp_path / "sweep.json"
    argv = ["sweep", "closed", "--nodes", "36", "--tighten-steps", "10", "--l0-over-d0",
            "20", "--executor", "serial", "--out", str(out), "--json", str(js)]
    assert main(argv) == 0
    first = json.loads(js.read_text())
    (case,) = first["cases"]
    assert case["status"] == "ok" and case["knot_type"] == "3_1"
    assert first["ran"] == [case["id"]] and first["skipped"] == []
    assert json.loads((out / "index.json").read_text())["counts"]["ok"] == 1
    assert "L/D" in capsys.readouterr().out
    # The same command again: nothing to run, the same result.
    assert main(argv) == 0
    again = json.loads(js.read_text())
    assert again["ran"] == [] and again["skipped"] == [case["id"]]
    assert again["cases"][0]["L_over_D"] == case["L_over_D"]
    # A second axis value whose scene refuses the mesh (36 vertices are too few for a
    # knot this long: the scene's own edge-length check) is a failed case: exit 1, the
    # reason on stderr, the finished case still skipped.
    assert main([*argv[:6], "--l0-over-d0", "20", "40", *argv[8:]]) == 1
    err = capsys.readouterr().err
    assert "error: ValueError" in err and "nodes" in err
    final = json.loads(js.read_text())
    assert final["skipped"] == [case["id"]] and len(final["failed"]) == 1


def test_without_dask_the_dask_executor_says_how_to_install_it(
        tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    # A None entry in sys.modules makes "import distributed" raise ImportError, as on an
    # installation without the extra.
    monkeypatch.setitem(sys.modules, "distributed", None)
    argv = ["sweep", "closed", "--executor", "dask", "--out", str(tmp_path / "s")]
    assert main(argv) == 2
    assert "pip install tightknot[distributed]" in capsys.readouterr().err
    assert not (tmp_path / "s").exists()
