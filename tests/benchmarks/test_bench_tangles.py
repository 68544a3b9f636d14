"""``tightknot bench tangles`` runs and reports (its 5 s target is judged by the benchmark,
never here)."""

from __future__ import annotations

import json

import pytest

from tightknot.app.cli import main


def test_bench_tangles_tiny(tmp_path, capsys):
    out = tmp_path / "t.json"
    assert main(["bench", "tangles", "--nodes", "60", "--repeats", "1", "--json",
                 str(out)]) == 0
    result = json.loads(out.read_text())
    (row,) = result["rows"]
    assert row["kind"] == "clasp" and row["converged"] and row["tangle_kept"]
    assert row["total_s"] == pytest.approx(row["build_s"] + row["pull_s"], rel=1e-9)
    # Not the target's size (2 x 100): the target is not judged.
    assert result["target_met"] is None
    assert "clasp" in capsys.readouterr().out
