"""Public API and CLI: bad input, lazy FElupe import, subcommand exit codes."""

import argparse
import json
import subprocess
import sys

import pytest

from tightknot.fem import SCENES, run_scene
from tightknot.fem.commands import register


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(name="knot"), "name"),
        (dict(name="wrap", max_approach_over_d0=0.3), "max_approach_over_d0"),
        (dict(name="wrap", max_tension_over_e_d0sq=0.0), "max_tension_over_e_d0sq"),
        (dict(name="wrap", max_tension_over_e_d0sq=0.8), "max_tension_over_e_d0sq"),
        (dict(name="wrap", max_tension_over_e_d0sq=float("inf")), "max_tension_over_e_d0sq"),
        (dict(name="wrap", wrap_angle_deg=180.0), "wrap_angle_deg"),
        (dict(name="wrap", wrap_angle_deg=5.0), "wrap_angle_deg"),
        (dict(name="wrap", length_over_d0=2.0), "length_over_d0"),
        (dict(name="wrap", mesh="huge"), "mesh"),
        (dict(name="wrap", steps=0), "steps"),
        (dict(name="wrap", diameter=-1.0), "diameter"),
        (dict(name="wrap", youngs_modulus=0.0), "youngs_modulus"),
        (dict(name="wrap", bogus=1), "bogus"),
        (dict(name="squeeze", max_approach_over_d0=1.0), "max_approach_over_d0"),
        (dict(name="squeeze", max_approach_over_d0=0.0), "max_approach_over_d0"),
        (dict(name="squeeze", max_approach_over_d0=-0.1), "max_approach_over_d0"),
        (dict(name="indent", max_approach_over_d0=float("nan")), "max_approach_over_d0"),
        (dict(name="squeeze", mesh="huge"), "mesh"),
        (dict(name="squeeze", steps=0), "steps"),
        (dict(name="squeeze", diameter=0.0), "diameter"),
        (dict(name="indent", youngs_modulus=-1.0), "youngs_modulus"),
        (dict(name="squeeze", length_over_d0=0.0), "length_over_d0"),
        (dict(name="squeeze", model="2d"), "model"),
        (dict(name="squeeze", model="3d", ends="glued"), "ends"),
        (dict(name="indent", bogus=1), "bogus"),
    ],
)
def test_bad_input_names_the_parameter(kwargs, name):
    pytest.importorskip("felupe")  # some checks sit after the lazy import of FElupe
    with pytest.raises(ValueError, match=name):
        run_scene(**kwargs)


def test_scenes_listed():
    assert SCENES == ("squeeze", "indent", "wrap", "soft_squeeze", "soft_crossing", "soft_wrap",
                      "clasp")


def _parser():
    parser = argparse.ArgumentParser(prog="tightknot")
    register(parser.add_subparsers(dest="command"))
    return parser


def test_cli_bad_scene_exit_2(capsys):
    args = _parser().parse_args(["fem", "knot"])
    assert args.handler(args) == 2
    err = capsys.readouterr().err
    assert "name must be one of" in err and err.count("\n") == 1


def test_cli_fem_writes_json(tmp_path):
    pytest.importorskip("felupe")
    out = tmp_path / "s.json"
    args = _parser().parse_args(["fem", "squeeze", "--steps", "2", "--no-convergence",
                                 "--approach", "0.05", "--json", str(out)])
    assert args.handler(args) == 0
    assert json.loads(out.read_text())["steps"][-1]["approach_over_d0"] == pytest.approx(0.05)


def test_cli_soft_squeeze_writes_json(tmp_path):
    # one level at a small approach without the rigid counterpart: about 1 s
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    out = tmp_path / "soft.json"
    args = _parser().parse_args(["fem", "soft_squeeze", "--steps", "1", "--no-compare",
                                 "--approach", "0.02", "--json", str(out)])
    assert args.handler(args) == 0
    result = json.loads(out.read_text())
    assert result["steps"][-1]["approach_over_d0"] == pytest.approx(0.02)
    assert "comparison" not in result
    assert result["mesh_convergence"]["computed"] is False


def test_missing_ipctk_gives_hint_and_exit_2():
    pytest.importorskip("felupe")
    code = (
        "import sys; sys.modules['ipctk'] = None\n"
        "import argparse\n"
        "from tightknot.fem.commands import register\n"
        "p = argparse.ArgumentParser(); register(p.add_subparsers())\n"
        "a = p.parse_args(['fem', 'soft_squeeze', '--no-compare', '--steps', '1'])\n"
        "sys.exit(a.handler(a))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert "ipctk" in proc.stderr and 'pip install "tightknot[fem]"' in proc.stderr
    assert proc.stderr.count("\n") == 1


def test_cli_help_has_examples(capsys):
    for command in ("fem", "calibrate"):
        with pytest.raises(SystemExit):
            _parser().parse_args([command, "--help"])
        assert f"tightknot {command}" in capsys.readouterr().out.split("examples:")[1]


def test_missing_felupe_gives_hint_and_exit_2():
    # run in a fresh interpreter where importing felupe fails (sys.modules entry None)
    code = (
        "import sys; sys.modules['felupe'] = None\n"
        "import tightknot.fem as f\n"
        "assert 'felupe' not in [m for m in sys.modules if sys.modules[m] is not None]\n"
        "import argparse\n"
        "from tightknot.fem.commands import register\n"
        "p = argparse.ArgumentParser(); register(p.add_subparsers())\n"
        "a = p.parse_args(['fem', 'squeeze', '--no-convergence'])\n"
        "sys.exit(a.handler(a))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert 'pip install "tightknot[fem]"' in proc.stderr


def test_import_does_not_load_felupe():
    code = ("import sys, tightknot.fem, tightknot.fem.commands; "
            "print('felupe' in sys.modules or 'ipctk' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.stdout.strip() == "False", proc.stderr


def test_cli_failed_solve_is_one_line_and_exit_1(monkeypatch, capsys):
    # A solve that fails is the physics, not the input: exit 1 with one line, no traceback.
    import tightknot.fem as fem_pkg
    from tightknot.fem.barrier_solver import BarrierNewtonFailure

    def failing(*_args, **_kwargs):
        raise BarrierNewtonFailure("no convergence in 60 iterations at load 0.5")

    monkeypatch.setattr(fem_pkg, "run_scene", failing)
    args = _parser().parse_args(["fem", "soft_crossing", "--steps", "1"])
    assert args.handler(args) == 1
    err = capsys.readouterr().err
    assert "the solve failed: no convergence" in err and err.count("\n") == 1
