"""The scripts in examples/ run and give the answers their docstrings promise."""

import importlib.util
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _load(name: str):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_cantilever_matches_the_elastica() -> None:
    # The elastica reference is inextensible; this rod (L/D0 = 24) stretches by
    # F/(EA) ~ 6e-4 under F L^2/EI = 2, which accounts for the measured 4.1e-4 L
    # (discretisation at 81 vertices is ~1e-5). 1e-3 L bound.
    assert _load("cantilever").main() < 1e-3


def test_closed_trefoil_example(tmp_path) -> None:
    s = _load("closed_trefoil").main(str(tmp_path / "k.rrd"))
    assert s["converged"] and s["knot_type"] == "3_1"
    assert (tmp_path / "k.rrd").stat().st_size > 0


def test_analyze_ideal_example() -> None:
    rep = _load("analyze_ideal").main()
    # The shipped ideal trefoil: L/D = 16.3718 (its README), 6 spikes, double contact.
    assert abs(rep["L_over_D"] - 16.372) < 0.003 and rep["n_curvature_spikes"] == 6


def test_readme_python_tour_runs(tmp_path, monkeypatch, capsys) -> None:
    # The README's first code block is run as written (in a scratch folder: it writes
    # trefoil.rrd), so the tour a newcomer copies keeps working.
    import re

    readme = (EXAMPLES.parent / "README.md").read_text()
    tour = readme.split("## Python tour", 1)[1]
    code = re.search(r"```python\n(.*?)```", tour, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {"__name__": "readme_tour"})
    printed = capsys.readouterr().out.split()
    assert printed[:2] == ["True", "3_1"]
    # The numbers the README quotes in its comment (stretch 1.0743, kappa*D0 max 0.971), to
    # the digits it shows.
    assert round(float(printed[2]), 4) == 1.0743 and round(float(printed[3]), 3) == 0.971
    assert (tmp_path / "trefoil.rrd").stat().st_size > 0


def test_readme_data_and_sweep_sections_run(tmp_path, monkeypatch) -> None:
    # The README's "Your own data" and "Sweep to table to plot" commands, run as written
    # (in a scratch folder; the shipped file's path made absolute).
    import csv
    import re
    import shlex

    from tightknot.app.cli import main

    readme = (EXAMPLES.parent / "README.md").read_text()
    monkeypatch.chdir(tmp_path)
    (tmp_path / "runs").mkdir()  # a checkout's runs/ (make demo makes it)
    for title in ("## Your own data", "## Sweep to table to plot"):
        block = re.search(r"```sh\n(.*?)```", readme.split(title, 1)[1], re.S).group(1)
        for line in block.strip().splitlines():
            argv = shlex.split(line)[1:]
            argv = [str(EXAMPLES.parent / a) if a.startswith("tightknot/knots/data") else a
                    for a in argv]
            assert main(argv) == 0, line
    assert (tmp_path / "ideal.json").is_file()
    with (tmp_path / "f.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [float(r["level_target"]) for r in rows] == [2.0, 3.0]
    assert (tmp_path / "runs/f/figures/force_extension.png").is_file()
