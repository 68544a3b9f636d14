"""What a run tells its user: no CUDA noise on a CPU machine, no silent overwrite, every
output listed."""

import subprocess
import sys
from pathlib import Path

import pytest

from tightknot.app.cli import main


def _cli(*argv: str) -> subprocess.CompletedProcess:
    # A fresh process: Warp's driver warning is printed once, at its initialisation.
    return subprocess.run([sys.executable, "-m", "tightknot.app.cli", *argv],
                          capture_output=True, text=True, check=False)


def test_no_cuda_driver_warning_unless_cuda_is_asked_for() -> None:
    res = _cli("verify", "--case", "euler_buckling", "--quiet")
    assert res.returncode == 0
    assert "CUDA" not in res.stderr, res.stderr


def test_a_missing_cuda_device_is_bad_input_naming_the_device() -> None:
    import warp as wp

    from tightknot.warp_setup import init_warp

    init_warp()
    if wp.get_cuda_device_count() > 0:
        pytest.skip("a CUDA device is present: --device cuda is valid here")
    res = _cli("verify", "--case", "euler_buckling", "--quiet", "--device", "cuda")
    assert res.returncode == 2
    assert "device 'cuda' is not available here" in res.stderr


def test_tie_refuses_an_earlier_run_folder_unless_overwrite(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run"
    args = ["tie", "closed", "--nodes", "40", "--tighten-steps", "10", "--out", str(out)]
    assert main(args) == 0
    printed = capsys.readouterr().out
    # Every output is named, not two of five.
    for name in ("config.json", "summary.json", "centerline.csv", "run.rrd", "figures/",
                 "tube_kappa_D0.png", "closed_profiles.png"):
        assert name in printed, (name, printed)
    before = (out / "summary.json").stat().st_mtime_ns
    assert main([*args, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "--overwrite" in err and "config.json" in err
    assert (out / "summary.json").stat().st_mtime_ns == before  # untouched
    assert main([*args, "--quiet", "--overwrite"]) == 0


def test_rigid_level_reports_no_pressure_and_no_width(tmp_path: Path) -> None:
    import json

    out = tmp_path / "rigid"
    # One Newton iteration fails the relaxation at once (as in test_cli's failed run): the
    # summary is still written and measures the state, which is all this checks.
    rc = main(["tie", "closed", "--nodes", "40", "--relax-iterations", "1", "--contact",
               "rigid", "--quiet", "--out", str(out)])
    assert rc == 1
    data = json.loads((out / "summary.json").read_text())
    assert data["max_pressure_over_E"] is None and data["max_contact_width_fraction"] is None
    assert data["calibrated_w_over_D0"] is None


def test_readme_contact_levels_are_the_cli_s() -> None:
    import re

    from tightknot.knots import scenes
    from tightknot.study.params import CONTACT_LEVELS

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    asked = set(re.findall(r"--contact[ =]([a-z]+)", readme))
    assert asked and asked <= set(CONTACT_LEVELS), asked
    # A scene level the command line rejects is named as Python-only where it is mentioned.
    para = readme.split("**Contact levels**", 1)[1].split("\n\n", 1)[0]
    for level in set(scenes.CONTACT_LEVELS) - set(CONTACT_LEVELS):
        assert f'contact="{level}"` (Python only' in para, level


def test_license_is_the_bsd_3_clause_of_pyproject() -> None:
    root = Path(__file__).resolve().parents[2]
    text = (root / "LICENSE").read_text()
    assert 'license = { text = "BSD-3-Clause" }' in (root / "pyproject.toml").read_text()
    assert text.startswith("BSD 3-Clause License") and "the tightknot developers" in text
    assert "Neither the name of the copyright holder" in text


def test_resolution_note_quotes_the_trade_off_numbers_of_the_readme() -> None:
    from tightknot.study.resolution import (
        CLOSED_KAPPA_RMS_AT_100,
        OPEN_KAPPA_ERROR_100_200,
        RECOMMENDED_NODES,
        resolution_note,
    )

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    lo, hi = OPEN_KAPPA_ERROR_100_200
    # The numbers are the README's own, not new ones.
    assert f"At 100 to 200 vertices the curvature error is {lo:g} to {hi:g}" in readme
    assert f"100 vertices, `residual_tol=1e-3`: kappa*D0 within {CLOSED_KAPPA_RMS_AT_100:g}" \
        in readme
    assert f"{RECOMMENDED_NODES['open']} vertices, `residual_tol=1e-3`" in readme
    assert resolution_note(False, 150)["warning"] is not None
    assert resolution_note(False, 400)["warning"] is None
    assert resolution_note(True, 100)["warning"] is None
    assert "not measured" in resolution_note(True, 60)["warning"]


def test_tie_keeps_the_pull_s_force_extension_apart(tmp_path: Path) -> None:
    import json

    import numpy as np

    from tightknot.viz.rrd_read import entity_paths, scalar_series

    out = tmp_path / "open"
    assert main(["tie", "open", "--nodes", "90", "--force", "3", "--tighten-steps", "20",
                 "--quiet", "--out", str(out)]) == 0
    data = json.loads((out / "summary.json").read_text())
    series = data["pull_series"]
    forces, ends = series["pull_force_N"], series["end_to_end_m"]
    assert len(forces) == len(ends) == len(series["lambda_oc"]) >= 1
    # The last equilibrium of the pull is the final state the summary describes; its end
    # reaction equals the dead load up to the Newton residual (tolerance 1e-6, scaled).
    assert forces[-1] == pytest.approx(data["pull_force_N"], rel=1e-6)
    x = np.array(data["centerline_m"])
    assert ends[-1] == float(np.linalg.norm(x[-1] - x[0]))
    assert series["lambda_oc"][-1] == data["lambda_oc"]
    # A force-driven pull only grows: a harder pull, a longer rod.
    assert forces == sorted(forces) and ends == sorted(ends)
    rrd = out / "run.rrd"
    paths = entity_paths(rrd)
    assert "/plots/open/tighten/pulling_force" in paths and "/plots/open/pulling_force" \
        not in paths
    _, logged = scalar_series(rrd, "/plots/open/pull/pulling_force")
    # One logged point per equilibrium of the pull; rerun stores float32 (1e-6 relative).
    assert np.allclose(logged, forces, rtol=1e-6, atol=0)
