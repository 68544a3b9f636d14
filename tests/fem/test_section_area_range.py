"""The sections' area range the FEM confirms (tightknot.fem.section_calibration.area_range):
the thinnest FEM section at which the sectioned level meets every cross-check target,
stored in the shipped calibration, which the knots' summaries compare their sections with.
"""

import json

import pytest

from tightknot.contact.sectioned import SectionCalibration
from tightknot.fem.crosscheck_targets import APPROACH_LIMIT
from tightknot.fem.section_calibration import (
    CALIBRATION_FILE,
    area_range,
    judged_area_ratio,
    write_area_range,
    write_section_calibration,
)


def _row(area: float, **met: bool) -> dict:
    return {"fem_area_ratio": area,
            "met": {"force": True, "area": True, "converged": True, **met}}


def test_the_judged_area_is_the_thinnest_section_that_meets_every_target() -> None:
    rows = [_row(0.95, curvature=False), _row(0.80), _row(0.66), _row(0.55, force=False)]
    assert judged_area_ratio(rows) is rows[2]
    assert judged_area_ratio([_row(0.7, width=False)]) is None
    assert judged_area_ratio([]) is None


def test_the_shipped_area_range_is_the_record_it_was_judged_from() -> None:
    """The value a knot's summary compares with is the one its stored record gives: a
    hand-edited number, or a record changed without it, fails here."""
    d = json.loads(CALIBRATION_FILE.read_text())
    rec = d["area_range"]
    judged = judged_area_ratio(rec["levels"])
    assert judged is not None
    assert d["validated_min_area_ratio"] == rec["judged_area_ratio"] == judged["fem_area_ratio"]
    assert SectionCalibration.from_json().judged_area_ratio == judged["fem_area_ratio"]
    assert judged["approach_over_d0"] <= rec["approach_limit_over_d0"] + 1e-9
    assert all(r["approach_over_d0"] > rec["approach_limit_over_d0"]
               for r in rec["past_approach_limit"])


def test_writing_the_penalty_keeps_the_area_range(tmp_path) -> None:
    path = tmp_path / "cal.json"
    path.write_text(CALIBRATION_FILE.read_text())
    shipped = json.loads(path.read_text())
    penalty_only = {k: v for k, v in shipped.items()
                    if k not in ("validated_min_area_ratio", "area_range")}
    write_section_calibration(penalty_only, path)
    assert json.loads(path.read_text()) == shipped
    with pytest.raises(ValueError, match="no level that meets every target"):
        write_area_range({"judged_area_ratio": None}, path)


def test_the_area_range_of_the_coarse_wrap(wrap_coarse: dict, tmp_path) -> None:
    """The record of the coarse FEM wrap (the cross-check's six tensions): its judged level
    meets every target within the approach limit, the deeper ones are reported apart, and
    writing it sets the value a knot's summary reads."""
    rec = area_range(wrap_coarse)
    steps = wrap_coarse["steps"]
    assert len(rec["levels"]) + len(rec["past_approach_limit"]) == len(steps)
    assert rec["judged_area_ratio"] is not None
    at = next(r for r in rec["levels"] if r["fem_area_ratio"] == rec["judged_area_ratio"])
    assert all(at["met"].values()) and at["approach_over_d0"] <= APPROACH_LIMIT + 1e-9
    # the thinnest section compared: the coarse wrap's deepest levels thin it below 0.75
    assert rec["judged_area_ratio"] < 0.75
    path = tmp_path / "cal.json"
    path.write_text(CALIBRATION_FILE.read_text())
    write_area_range(rec, path)
    assert SectionCalibration.from_json(path).judged_area_ratio == rec["judged_area_ratio"]
