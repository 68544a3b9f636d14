"""The command line: help of every subcommand, exit codes, and verify's JSON."""

import json
import subprocess
import sys

import pytest

from tightknot.cli import build_parser, main

SUBCOMMANDS = ["verify", "bench", "demo", "analyze", "fem", "calibrate"]


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
