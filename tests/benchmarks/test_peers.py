"""``tightknot bench peers``: tightknot's row, the shared measurements, and missing peers.

The peers themselves (PyElastica, dismech-newton) are optional and slow; only the slow test
runs PyElastica, and it skips when PyElastica is not installed.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from tightknot.app.cli import main
from tightknot.benchmarks import peers


def test_profile_rms_diff_of_a_constant_offset_is_the_offset() -> None:
    u = np.linspace(0.0, 1.0, 57)
    k = np.sin(3 * u)
    assert peers.profile_rms_diff((u, k), (u, k)) == 0.0
    # Linear interpolation of a constant offset is exact: only round-off remains.
    assert peers.profile_rms_diff((u, k + 0.3), (u, k)) == pytest.approx(0.3, rel=1e-12)


def test_measure_a_straight_rod() -> None:
    d0 = 0.0085
    x = np.c_[np.linspace(0.0, 0.2, 81), np.zeros(81), np.zeros(81)]
    m = peers.measure(x, d0, rest_length=0.2)
    assert m["knot_type"] == "0_1"
    assert m["lambda_oc"] is None  # no contact, no knot length
    # The closest non-local pair of a straight line is one exclusion window (pi D0 / 2)
    # apart, up to one edge (the window is measured between vertices).
    assert np.pi / 2 <= m["min_gap_over_D0"] <= np.pi / 2 + 0.2 / 80 / d0
    assert m["penetration_over_D0"] == 0.0
    assert np.all(m["_profile"][1] == 0.0)


def test_measure_refuses_nothing_but_reports_non_finite_positions() -> None:
    x = np.zeros((10, 3))
    x[3] = np.nan
    m = peers.measure(x, 0.0085, 0.2)
    assert m["min_gap_over_D0"] is None and m["knot_type"].startswith("undefined")


def test_tightknot_row_keeps_the_knot_at_the_end_distance() -> None:
    row, x = peers.tightknot_row(vertices=85)  # the scene's minimum for this start is 82
    assert row["converged"], row.get("error")
    assert row["knot_type"] == "3_1"
    assert np.linalg.norm(x[-1] - x[0]) == pytest.approx(peers.END_DISTANCE, abs=1e-12)
    # Tight knot in contact: the sections flatten, so the centerlines come closer than D0
    # (measured 0.81 D0); below 0.5 D0 would mean the rod has nearly passed through itself.
    assert 0.5 < row["min_gap_over_D0"] < 1.0
    # Measured Lambda_OC 12.1 at 85 vertices (12.0 at 300): a tight knot; +-2 for the
    # discretisation and the contact set's jumps.
    assert 10.0 < row["lambda_oc"] < 14.0
    assert row["steps"] > 0 and row["wall_time_s"] > 0


def test_a_missing_or_failing_peer_gives_an_error_row(tmp_path) -> None:
    scene = tmp_path / "scene.npz"
    np.savez(scene, start=np.zeros((5, 3)))
    script = peers.peers_dir() / "pyelastica_pull.py"
    row = peers._peer_row("dismech-newton", str(tmp_path / "no-python"), script, scene,
                          tmp_path, [], 10.0, 0.0085, 0.185)
    assert row["code"] == "dismech-newton" and "no Python" in row["error"]
    failing = tmp_path / "fails.py"
    failing.write_text("import sys\nprint('boom', file=sys.stderr)\nsys.exit(3)\n")
    row = peers._peer_row("pyelastica", sys.executable, failing, scene, tmp_path, [], 10.0,
                          0.0085, 0.185)
    assert "exit 3" in row["error"] and "boom" in row["error"]
    row = peers._peer_row("pyelastica", sys.executable, tmp_path / "absent.py", scene,
                          tmp_path, [], 10.0, 0.0085, 0.185)
    assert "not found" in row["error"]


@pytest.mark.parametrize("args", [["--vertices", "10"], ["--end-distance", "0.3"],
                                  ["--peers", "abaqus"], ["--timeout", "-1"]])
def test_bad_input_exits_2(args, capsys) -> None:
    assert main(["bench", "peers", *args]) == 2
    assert "error" in capsys.readouterr().err


@pytest.mark.slow
def test_pyelastica_driver_holds_the_ends(tmp_path) -> None:
    """A few hundred PyElastica steps of the scene: finite, ends where the schedule puts them."""
    pytest.importorskip("elastica")
    import subprocess

    start, d0 = peers.start_curve(41)
    scene = peers._scene_file(tmp_path, start, d0, peers.END_DISTANCE, peers.REST_LENGTH)
    out = tmp_path / "pe.npz"
    subprocess.run([sys.executable, str(peers.peers_dir() / "pyelastica_pull.py"), str(scene),
                    str(out), "--t-max", "0.002", "--check-every", "50"], check=True,
                   capture_output=True)
    with np.load(out) as z:
        final = z["final"]
    assert np.isfinite(final).all()
    np.testing.assert_allclose(final[0], start[0], atol=1e-12)
    # After 2 ms of a 1 s smoothstep shrink the end has moved by < 1e-4 of the span.
    assert abs(final[-1, 0] - start[-1, 0]) < 1e-4 * start[-1, 0]
