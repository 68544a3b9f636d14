"""``tightknot tie clasp`` and ``tightknot tie bend``: outputs, exit codes, one-line errors."""

from __future__ import annotations

import json

import pytest

from tightknot.app.cli import main
from tightknot.viz import rrd_read

# Coarse rods (clasp ~23 D0 long, reef ~39 D0: edges <= pi/4 D0, the scenes' limit) and a
# small force, so that each run takes a second or two.
CLASP = ["tie", "clasp", "--nodes", "60", "--force", "0.5", "--quiet"]


def test_clasp_writes_everything(tmp_path):
    out = tmp_path / "clasp"
    assert main([*CLASP, "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["converged"] and s["failure"] == ""
    assert s["tangle_type"]["kept"] and abs(s["tangle_type"]["linking_number"]) == 1
    fe = s["force_extension"]
    assert len(fe["end_to_end_m"]) == len(fe["pulling_force_N"]) == len(fe["phase"]) >= 3
    assert fe["pulling_force_N"][-1] == pytest.approx(0.5, rel=1e-6)
    assert len(s["end_reactions"]) == 4
    assert {(r["rod"], r["end"]) for r in s["end_reactions"]} == {
        ("A", "start"), ("A", "end"), ("B", "start"), ("B", "end")}
    assert [r["rod"] for r in s["rods"]] == ["A", "B"]
    for rod in s["rods"]:
        assert rod["contact_with_other_rod"]["vertices"] > 0  # hooked: they touch
        assert rod["stretch"] > 1.0
    assert (out / "figures" / "force_extension.png").stat().st_size > 0
    assert (out / "centerline_A.csv").is_file() and (out / "centerline_B.csv").is_file()
    paths = rrd_read.entity_paths(out / "run.rrd")
    for entity in ("/clasp/rod_A", "/clasp/rod_B", "/clasp/contacts_between_rods"):
        assert entity in paths
    # Every converged load step is logged, each rod at each.
    steps = rrd_read.steps(out / "run.rrd", "clasp/rod_B", "LineStrips3D:strips")
    assert len(steps) == s["load_steps"]


def test_bend_reef(tmp_path):
    out = tmp_path / "reef"
    assert main(["tie", "bend", "--kind", "reef", "--nodes", "60", "--force", "0.5",
                 "--quiet", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["scene"] == "reef_bend" and s["converged"] and s["tangle_type"]["kept"]
    assert s["tangle_type"]["linking_number"] == 0
    assert s["tangle_type"]["candidates"] == ["reef", "thief"]


def test_overlapping_rods_are_bad_input(tmp_path, capsys):
    code = main([*CLASP, "--helix-radius", "0.3", "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "rods A and B overlap at the start" in err[0]


@pytest.mark.parametrize("flags, words", [
    (["--youngs-modulus-b", "0"], "rod B (--youngs-modulus-b, --poisson-b)"),
    (["--poisson", "0.7"], "rod A (--youngs-modulus, --poisson)"),
    (["--end-distance", "0.01"], "end_distance must exceed the start's"),
    (["--nodes", "10"], "nodes must be a whole number >= 40"),
    (["--side-offset", "0.9"], "rod A: centerline overlaps itself"),
])
def test_bad_input_is_one_line_exit_2(tmp_path, capsys, flags, words):
    code = main(["tie", "clasp", "--nodes", "60", "--quiet", *flags,
                 "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and words in err[0]


def test_bend_needs_its_kind(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["tie", "bend", "--nodes", "80"])
    assert exc.value.code == 2
    assert "--kind" in capsys.readouterr().err


def test_unreached_force_exits_1_and_says_why(tmp_path, capsys):
    out = tmp_path / "weak"
    code = main([*CLASP[:-3], "--force", "50", "--max-end-distance", "0.132", "--quiet",
                 "--out", str(out)])
    assert code == 1
    err = capsys.readouterr().err
    assert "the force 50 N was not reached" in err
    assert json.loads((out / "summary.json").read_text())["converged"] is False


def test_a_tangle_that_comes_apart_exits_1_with_its_state(tmp_path, capsys, monkeypatch):
    from tightknot.knots import tangle_scenes, tangles

    real = tangle_scenes.TangleScene.tangle_type
    calls = [0]

    def apart(self, x):
        calls[0] += 1
        return real(self, x) if calls[0] < 3 else tangles.TangleType(0, ("0_1", "0_1"), "0_1")

    monkeypatch.setattr(tangle_scenes.TangleScene, "tangle_type", apart)
    out = tmp_path / "apart"
    assert main([*CLASP, "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "the tangle came apart" in err and "rods A and B" in err
    assert (out / "failed_centerline_A.csv").is_file()
    assert (out / "summary.json").is_file()


def _write_reef_files(tmp_path):
    """The built-in reef's start curves as a user's files: in mm, moved and turned, rod B
    written from its other end."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    from tightknot.knots import tangles

    a, b = tangles.tangle_curves("reef", samples=120)
    rot = Rotation.from_euler("xyz", [0.4, -1.1, 2.0]).as_matrix()
    shift = np.array([12.0, -3.0, 40.0])
    paths = []
    for name, c in (("a.csv", a), ("b.csv", b[::-1])):
        pts = (c * 8.5) @ rot.T + shift  # mm
        path = tmp_path / name
        path.write_text("x,y,z\n" + "\n".join(f"{p[0]:.9g},{p[1]:.9g},{p[2]:.9g}" for p in pts))
        paths.append(str(path))
    return paths


def test_user_start_curves(tmp_path):
    fa, fb = _write_reef_files(tmp_path)
    out = tmp_path / "own"
    assert main(["tie", "bend", "--kind", "reef", "--nodes", "60", "--force", "0.5", "--quiet",
                 "--start-a", fa, "--start-b", fb, "--units", "mm", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["converged"] and s["tangle_type"]["kept"]
    assert s["tangle_type"]["linking_number"] == 0


def test_user_start_curves_of_another_kind_name_the_files(tmp_path, capsys):
    fa, fb = _write_reef_files(tmp_path)
    code = main(["tie", "bend", "--kind", "granny", "--nodes", "60", "--quiet",
                 "--start-a", fa, "--start-b", fb, "--units", "mm",
                 "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert fa in err[0] and "the start curves are not a granny" in err[0]
    assert main(["tie", "clasp", "--start-a", fa, "--out", str(tmp_path / "y")]) == 2
