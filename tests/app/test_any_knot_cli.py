"""``tightknot tie`` and ``sweep`` on any built-in knot (``--knot``), and their bad input."""

import json
from pathlib import Path

import pytest

from tightknot.app.cli import build_parser, main


def test_tie_closed_cinquefoil_names_its_knot(tmp_path: Path) -> None:
    out = tmp_path / "run"
    # Coarse (80 vertices) with a loose Newton tolerance: the CLI path, not the physics.
    assert main(["tie", "closed", "--knot", "5_1", "--nodes", "80", "--residual-tol", "1e-3",
                 "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scene"] == "closed_5_1" and summary["knot_type"] == "5_1"
    assert summary["converged"]
    config = json.loads((out / "config.json").read_text())
    assert config["knot_type"] == "5_1"


def test_sweep_shares_the_knot_flag() -> None:
    from tightknot.sweep.commands import build_cases

    args = build_parser().parse_args(["sweep", "closed", "--knot", "5_2", "7_1",
                                      "--out", "unused"])
    cases = build_cases(args)
    assert sorted(c.params["knot_type"] for c in cases) == ["5_2", "7_1"]


@pytest.mark.parametrize("argv,message", [
    (["tie", "closed", "--knot", "9_1"], "--knot-type/--knot: invalid choice: '9_1'"),
    (["tie", "closed", "--knot", "5_1", "--l0-over-d0", "12"],
     "l0_over_d0 must be >= "),
])
def test_bad_knot_input_exits_2_with_one_line(argv, message, capsys, tmp_path) -> None:
    try:
        code = main([*argv, "--out", str(tmp_path / "r")])
    except SystemExit as exc:  # argparse's own refusal
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert message in err
    assert not (tmp_path / "r").exists()
