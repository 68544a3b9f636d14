"""The command line: help of every subcommand, exit codes, and verify's JSON."""

import json
import subprocess
import sys

import numpy as np
import pytest

from tightknot.cli import build_parser, main

SUBCOMMANDS = ["verify", "bench", "tie", "demo", "analyze", "fem", "calibrate"]


@pytest.mark.parametrize("sub", SUBCOMMANDS)
def test_help_works(sub: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main([sub, "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "usage:" in out


def test_top_level_help_lists_subcommands() -> None:
    text = build_parser().format_help()
    for sub in SUBCOMMANDS:
        assert sub in text


def test_bad_arguments_exit_2() -> None:
    with pytest.raises(SystemExit) as exc:
        main(["no-such-command"])
    assert exc.value.code == 2
    assert main(["verify", "--case", "no_such_case"]) == 2
    assert main(["verify", "--json", "/no/such/folder/out.json"]) == 2


def test_verify_json(tmp_path) -> None:
    out = tmp_path / "v.json"
    rc = main(["verify", "--case", "neo_hookean_stretch", "--case", "ring_at_rest",
               "--json", str(out), "--quiet"])
    assert rc == 0
    rows = json.loads(out.read_text())
    assert {r["case"] for r in rows} >= {"neo_hookean_uniaxial tension"}
    for r in rows:
        assert set(r) >= {"case", "reference", "computed", "rel_error", "order", "passed"}
        assert r["passed"] is True


def test_console_script_runs() -> None:
    # The installed entry point, as a user calls it.
    res = subprocess.run([sys.executable, "-m", "tightknot.cli", "--version"],
                         capture_output=True, text=True, check=False)
    assert res.returncode == 0 and "tightknot" in res.stdout


def test_tie_closed_writes_json_and_rrd(tmp_path) -> None:
    from tightknot.viz.rrd_read import last_points3d

    out, rrd = tmp_path / "c.json", tmp_path / "c.rrd"
    rc = main(["tie", "closed", "--nodes", "60", "--json", str(out), "--rrd", str(rrd),
               "--quiet"])
    assert rc == 0
    data = json.loads(out.read_text())
    assert data["knot_type"] == "3_1" and data["converged"] is True
    for key in ("alexander_at_minus1", "newton_iterations", "wall_time_s", "stretch",
                "L_over_D", "min_gap_over_D0", "max_pressure_over_E", "min_area_ratio",
                "max_contact_width_fraction", "s", "kappa", "rho", "z", "area_ratio",
                "contact_width_fraction", "contact_s", "contact_sigma"):
        assert key in data, key
    # The last logged rod equals the final centerline of the JSON (float32 in rerun).
    pts = last_points3d(rrd, "/closed/rod/vertices")
    assert np.allclose(pts, np.array(data["centerline_m"]), rtol=0, atol=1e-7)


def test_tie_bad_input_exit_2(tmp_path) -> None:
    assert main(["tie", "open", "--force", "5", "--end-distance", "0.1"]) == 2
    assert main(["tie", "open"]) == 2
    assert main(["tie", "closed", "--force", "5"]) == 2
    assert main(["tie", "open", "--force", "5", "--json", "/no/such/dir/x.json"]) == 2
    assert main(["tie", "closed", "--nodes", "5"]) == 2
    assert main(["tie", "closed", "--poisson", "0.7"]) == 2
    assert main(["tie", "open", "--target-lambda", "10.1", "--force", "3"]) == 2
    assert main(["tie", "open", "--target-lambda", "-1"]) == 2
