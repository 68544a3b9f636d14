"""The trade-off table's knots' cost (tightknot.benchmarks.level_truth) from
bench/contact_levels.py's report."""

from __future__ import annotations

import pytest

from tightknot.benchmarks.level_truth import _knot_cost


def _rows(t_closed: float, t_open: float) -> list[dict]:
    return [{"case": "closed", "level": "compliant", "wall_time_s": 2.0, "converged": True},
            {"case": "open", "level": "compliant", "wall_time_s": 4.0, "converged": True},
            {"case": "closed", "level": "sectioned", "wall_time_s": t_closed, "converged": True},
            {"case": "open", "level": "sectioned", "wall_time_s": t_open, "converged": True}]


def test_the_cost_is_the_ratio_of_the_rows_times() -> None:
    cost = _knot_cost({"rows": _rows(3.0, 10.0)}, "sectioned")
    assert cost["time_ratio_to_compliant"] == [1.5, 2.5]
    assert cost["wall_time_s"] == 13.0 and cost["all_converged"]


def test_a_repeated_benchs_own_ratios_are_used() -> None:
    # --repeat: the median of each run's ratio (the two levels timed one after the other)
    # can differ from the ratio of the median times; the bench's own is taken.
    report = {"rows": _rows(3.0, 10.0),
              "ratios": [{"case": "closed", "level": "sectioned", "time_ratio_to_compliant": 1.4},
                         {"case": "open", "level": "sectioned", "time_ratio_to_compliant": 2.6}]}
    assert _knot_cost(report, "sectioned")["time_ratio_to_compliant"] == pytest.approx([1.4, 2.6])
    assert _knot_cost(report, "smoothed") is None
