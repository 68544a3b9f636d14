"""The command line: help of every subcommand, exit codes, and verify's JSON."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tightknot.app.cli import build_parser, main

SUBCOMMANDS = ["verify", "bench", "tie", "demo", "view", "analyze", "fem", "calibrate", "sweep",
               "table", "plot"]


@pytest.mark.parametrize("sub", SUBCOMMANDS)
def test_help_works(sub: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main([sub, "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "usage:" in out
    assert "examples:" in out, sub


def test_top_level_help_lists_subcommands() -> None:
    text = build_parser().format_help()
    for sub in SUBCOMMANDS:
        assert f"\n    {sub} " in text or f"\n    {sub}\n" in text, sub
    assert "examples:" in text


def test_bad_arguments_exit_2() -> None:
    with pytest.raises(SystemExit) as exc:
        main(["no-such-command"])
    assert exc.value.code == 2
    assert main(["verify", "--case", "no_such_case"]) == 2
    assert main(["verify", "--json", "/no/such/folder/out.json"]) == 2
    assert main(["demo", "--out", "/no/such/folder/demo"]) == 2


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
    res = subprocess.run([sys.executable, "-m", "tightknot.app.cli", "--version"],
                         capture_output=True, text=True, check=False)
    assert res.returncode == 0 and "tightknot" in res.stdout


# -- tie: the run folder -------------------------------------------------------------------
# One small closed trefoil (60 vertices, ~3 s) tied once and shared by the checks below.
TIE_ARGS = ["tie", "closed", "--nodes", "60", "--quiet"]


@pytest.fixture(scope="module")
def closed_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("tie") / "run"
    assert main([*TIE_ARGS, "--out", str(out)]) == 0
    return out


def _summary(folder: Path) -> dict:
    return json.loads((folder / "summary.json").read_text())


def test_tie_run_folder_holds_every_output(closed_run: Path) -> None:
    for name in ("config.json", "summary.json", "centerline.csv", "run.rrd",
                 "figures/closed_profiles.png", "figures/closed_contact_map.png",
                 "figures/tube_kappa_D0.png"):
        assert (closed_run / name).stat().st_size > 0, name
    data = _summary(closed_run)
    assert data["knot_type"] == "3_1" and data["converged"] is True and data["failure"] == ""
    for key in ("alexander_at_minus1", "newton_iterations", "wall_time_s", "stretch",
                "L_over_D", "min_gap_over_D0", "max_pressure_over_E", "min_area_ratio",
                "max_contact_width_fraction", "s", "kappa", "rho", "z", "area_ratio",
                "contact_width_fraction", "peak_pressure_over_E", "contact_s",
                "contact_sigma", "load_steps"):
        assert key in data, key
    cfg = json.loads((closed_run / "config.json").read_text())
    assert cfg["knot"] == "closed" and cfg["nodes"] == 60 and cfg["color_by"] == "kappa_D0"
    assert cfg["device"] == "cpu"  # what ran, not "the default"


def test_tie_contact_level_flag_reaches_the_scene(tmp_path: Path) -> None:
    out = tmp_path / "run"
    assert main(["tie", "closed", "--nodes", "48", "--quiet", "--contact", "smoothed",
                 "--out", str(out)]) == 0
    cfg = json.loads((out / "config.json").read_text())
    assert cfg["contact"] == "smoothed"
    data = _summary(out)
    assert data["converged"] is True and data["knot_type"] == "3_1"
    with pytest.raises(SystemExit) as bad:  # argparse's choices: one line, exit code 2
        main(["tie", "closed", "--contact", "sticky"])
    assert bad.value.code == 2


def test_tie_rrd_has_rod_contacts_series_steps_and_final_centerline(closed_run: Path) -> None:
    from tightknot.viz.rrd_read import entity_paths, last_points3d, scalar_series, steps

    rrd = closed_run / "run.rrd"
    data = _summary(closed_run)
    paths = entity_paths(rrd)
    for entity in ("/closed/rod", "/closed/contacts", "/ideal_trefoil",
                   "/plots/closed/energy/bend", "/plots/closed/newton_iterations"):
        assert entity in paths, (entity, paths)
    # One logged row per converged load step (the solver's count, in the summary), and the
    # converged closed knot's last step is its final state (no extra step).
    n = data["load_steps"]
    assert n >= 40  # 40 initial steps; adaptive halving only adds steps
    assert steps(rrd, "/closed/rod/vertices", "Points3D:positions") == list(range(n))
    assert steps(rrd, "/closed/rod", "LineStrips3D:strips") == list(range(n))
    assert len(scalar_series(rrd, "/plots/closed/energy/bend")[1]) == n
    # The last logged rod equals the final centerline of the JSON (rerun stores float32:
    # 1e-7 m covers its ~6e-8 relative rounding on a ~0.05 m knot).
    pts = last_points3d(rrd, "/closed/rod/vertices")
    assert np.allclose(pts, np.array(data["centerline_m"]), rtol=0, atol=1e-7)


def test_tie_config_round_trip_reproduces_the_summary(closed_run: Path, tmp_path) -> None:
    again = tmp_path / "again"
    assert main(["tie", "--config", str(closed_run / "config.json"), "--out", str(again),
                 "--quiet"]) == 0
    a, b = _summary(closed_run), _summary(again)
    a.pop("wall_time_s")
    b.pop("wall_time_s")
    # Same parameters, same machine: the solve is deterministic, so every number (the
    # centerline included) is identical, not merely close.
    assert a == b
    assert json.loads((again / "config.json").read_text()) == json.loads(
        (closed_run / "config.json").read_text())


def test_tie_centerline_csv_reads_back_in_analyze(closed_run: Path, tmp_path) -> None:
    data = _summary(closed_run)
    out = tmp_path / "a.json"
    rc = main(["analyze", str(closed_run / "centerline.csv"), "--diameter", "0.0085",
               "--rest-length", repr(data["rest_length_m"]), "--closed", "--json", str(out),
               "--quiet"])
    assert rc == 0
    rep = json.loads(out.read_text())
    # The csv keeps full precision (repr), so the measurement of the file is the run's own,
    # bit for bit: same points, same functions.
    assert np.array_equal(np.loadtxt(closed_run / "centerline.csv", delimiter=",", comments="#",
                                     skiprows=3), np.array(data["centerline_m"]))
    assert rep["knot_type"] == data["knot_type"]
    assert rep["stretch_L_over_L0"] == data["stretch"] and rep["L_over_D"] == data["L_over_D"]
    assert rep["kappa_D0"] == data["kappa"] and rep["s"] == data["s"]
    assert rep["kappa_D0_max"] == data["kappa_D0_max"]


def test_tie_failed_run_writes_summary_and_rrd_and_exits_1(tmp_path, capsys) -> None:
    from tightknot.viz.rrd_read import component_rows, last_points3d, steps

    out = tmp_path / "fail"
    # One Newton iteration cannot relax the start curve (it is far from equilibrium): an
    # honest failure of the physics, found in a fraction of a second. The tube is coloured
    # by stretch here, to check --color-by on the same cheap run.
    rc = main(["tie", "closed", "--nodes", "40", "--relax-iterations", "1", "--color-by",
               "stretch", "--out", str(out)])
    assert rc == 1
    err = capsys.readouterr().err
    assert "failed: relax: Newton" in err and "run.rrd" in err
    data = _summary(out)
    assert data["converged"] is False and data["failure"].startswith("relax: Newton")
    assert data["load_steps"] == 0
    # The state it stopped in is in the .rrd (one step: nothing converged before it) and in
    # the csv, for the user to look at.
    rrd = out / "run.rrd"
    assert steps(rrd, "/closed/rod/vertices", "Points3D:positions") == [0]
    assert np.allclose(last_points3d(rrd, "/closed/rod/vertices"), data["centerline_m"],
                       rtol=0, atol=1e-7)  # float32 in rerun
    assert (out / "centerline.csv").is_file()
    assert (out / "figures" / "tube_stretch.png").is_file()
    assert json.loads((out / "config.json").read_text())["color_by"] == "stretch"
    colours = component_rows(rrd, "/closed/rod", "LineStrips3D:colors")
    assert len(colours) == 1 and len(colours[0].value) == 40  # one colour per edge
    assert len(set(colours[0].value)) > 1  # a field, not the plain colour


def test_tie_bad_input_exit_2(tmp_path) -> None:
    assert main(["tie", "open", "--force", "5", "--end-distance", "0.1"]) == 2
    assert main(["tie", "open"]) == 2
    assert main(["tie"]) == 2
    assert main(["tie", "closed", "--force", "5"]) == 2
    assert main(["tie", "closed", "--nodes", "5"]) == 2
    assert main(["tie", "closed", "--poisson", "0.7"]) == 2
    assert main(["tie", "open", "--target-lambda", "10.1", "--force", "3"]) == 2
    assert main(["tie", "open", "--target-lambda", "-1"]) == 2
    with pytest.raises(SystemExit) as exc:
        main(["tie", "closed", "--color-by", "curvature"])
    assert exc.value.code == 2


def test_tie_bad_outputs_fail_before_the_run(tmp_path, capsys) -> None:
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    folder = tmp_path / "folder.rrd"
    folder.mkdir()
    bad_config = tmp_path / "bad.json"
    bad_config.write_text('{"knot": "closed", "nodes": 60, "colour": "red"}')
    out = tmp_path / "never"
    cases = [
        (["--out", str(tmp_path / "no" / "such" / "dir")], "parent folder does not exist"),
        (["--out", str(a_file)], "exists and is not a folder"),
        (["--out", str(out), "--rrd", str(tmp_path / "no" / "x.rrd")], "folder does not exist"),
        (["--out", str(out), "--rrd", str(folder)], "is a folder"),
        (["--out", str(out), "--rrd", str(tmp_path / "x.log")], "must end in .rrd"),
        (["--out", str(out), "--json", str(tmp_path / "no" / "s.json")], "does not exist"),
        (["--out", str(out), "--figures", str(a_file)], "not a folder"),
        (["--out", str(out), "--config", str(bad_config)], "unknown key(s) 'colour'"),
        (["--out", str(out), "--config", str(tmp_path / "missing.json")], "cannot read"),
    ]
    for extra, words in cases:
        args = ["tie", *(["closed"] if "--config" not in extra else []), *extra]
        assert main(args) == 2, extra
        assert words in capsys.readouterr().err, (extra, words)
        # Refused before any work: not even the run folder was made.
        assert not out.exists(), extra


def test_tie_flags_override_the_config_file(tmp_path) -> None:
    from tightknot.app.cli import tie_config

    cfg = tmp_path / "c.json"
    cfg.write_text(json.dumps({"knot": "open", "length": 0.125, "target_lambda": 10.1,
                               "nodes": 120, "youngs_modulus": 2e6}))

    def resolved(*argv: str):
        return tie_config(build_parser().parse_args(["tie", *argv]))

    same = resolved("--config", str(cfg))
    assert (same.knot, same.length, same.target_lambda, same.nodes) == ("open", 0.125, 10.1, 120)
    more = resolved("--config", str(cfg), "--nodes", "200", "--color-by", "contact_width")
    assert more.nodes == 200 and more.youngs_modulus == 2e6
    assert more.color_by == "contact_width_fraction"
    # A load flag replaces the file's load (an open knot takes exactly one).
    forced = resolved("--config", str(cfg), "--force", "3")
    assert forced.force == 3.0 and forced.target_lambda is None and forced.length == 0.125
    # Another knot drops the file's knot-specific values (its nodes, length and load).
    from tightknot.knots.scenes import default_nodes

    closed = resolved("closed", "--config", str(cfg))
    assert closed.knot == "closed" and closed.length is None
    assert closed.nodes == default_nodes(closed.l0_over_d0, True)  # from its own length
    assert closed.youngs_modulus == 2e6


def test_tie_default_run_folder(tmp_path, monkeypatch) -> None:
    from tightknot.app.run_folder import default_run_dir, plan_outputs

    monkeypatch.chdir(tmp_path)
    # A fresh checkout has no runs/: a folder under it is fine (made on demand), a folder
    # under another missing parent is refused.
    assert plan_outputs("closed_trefoil", "runs/a/b").folder == Path("runs/a/b")
    with pytest.raises(ValueError, match="parent folder does not exist"):
        plan_outputs("closed_trefoil", "other/a")
    assert not Path("runs").exists()  # checking makes nothing
    first = default_run_dir("closed_trefoil")
    assert first.parent == Path("runs") and first.name.startswith("closed_trefoil-")
    first.mkdir(parents=True)
    second = default_run_dir("closed_trefoil", root=Path("runs"))
    # Same second: a suffix, never the same folder.
    assert second != first


# -- view ------------------------------------------------------------------------------------
def test_view_missing_or_wrong_file_exit_2(tmp_path, capsys) -> None:
    assert main(["view", str(tmp_path / "none.rrd")]) == 2
    assert "no such file" in capsys.readouterr().err
    text = tmp_path / "x.rrd"
    text.write_text("not a recording")
    assert main(["view", str(text)]) == 2
    assert "not a rerun recording" in capsys.readouterr().err


def test_view_print_only_prints_the_command(closed_run: Path, capsys) -> None:
    rrd = closed_run / "run.rrd"
    assert main(["view", str(rrd), "--print-only"]) == 0
    line = capsys.readouterr().out.strip()
    assert line.endswith(str(rrd)) and "rerun" in line


def test_analyze_of_a_tied_open_knot_gives_its_lambda_oc(tmp_path) -> None:
    # One Lambda_OC: the command the centerline.csv header gives (sections thinned by their
    # stretch) measures the file as the tie measured its state (10.115 against 10.331 when
    # analyze took nominal radii).
    out = tmp_path / "open"
    assert main(["tie", "open", "--nodes", "90", "--force", "3", "--tighten-steps", "20",
                 "--quiet", "--out", str(out)]) == 0
    data = _summary(out)
    header = (out / "centerline.csv").read_text().splitlines()[1]
    args = header.split("tightknot ", 1)[1].split()
    assert args[0] == "analyze" and "--radii" in args
    rep_json = tmp_path / "a.json"
    assert main([args[0], str(out / args[1]), *args[2:], "--json", str(rep_json),
                 "--quiet"]) == 0
    rep = json.loads(rep_json.read_text())
    # Same points (repr floats), same radii up to the round-off of the rest lengths.
    assert rep["Lambda_OC"] == pytest.approx(data["lambda_oc"], abs=1e-9)


@pytest.mark.parametrize("args, key", [
    (["closed", "--section-bend-shift", "on"], "section_bend_shift: on"),
    (["closed", "--section-thinning", "rod"], "section_thinning: rod"),
    (["open", "--section-path", "pull", "--force", "1"], "section_path: pull"),
])
def test_a_section_option_without_the_sectioned_level_exits_2(tmp_path, capsys, args: list,
                                                              key: str) -> None:
    out = tmp_path / "run"
    assert main(["tie", *args, "--contact", "compliant", "--nodes", "60",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert key in err and "needs contact sectioned" in err and "got contact compliant" in err
    assert not out.exists()  # refused before anything is written


def test_an_unknown_section_thinning_exits_2(tmp_path, capsys) -> None:
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as bad:  # argparse's choices: exit code 2
        main(["tie", "closed", "--contact", "sectioned", "--section-thinning", "mean",
              "--out", str(out)])
    assert bad.value.code == 2
    assert "--section-thinning" in capsys.readouterr().err
    assert not out.exists()
