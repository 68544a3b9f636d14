"""Bad input to the centerline reader of ``tightknot analyze`` (issue 8): any text, any
bytes, any units give (N, 3) finite points or a CenterlineError (a ValueError) whose message
names the source and line; the analyze command then exits 0 or 2, never with a traceback."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from tightknot.knots.centerline_io import CenterlineError, parse_centerline_text, read_centerline

#: Tokens a centerline file might hold: numbers of every form, the special floats, junk.
number = st.one_of(st.floats(-1e3, 1e3).map(repr), st.integers(-10**6, 10**6).map(str),
                   st.floats(allow_nan=True, allow_infinity=True).map(repr),
                   st.sampled_from(["1e400", "-1e-400", "nan", "inf", "-Infinity", "1_000",
                                    "0x10", "1,5", "", " ", "x", "1e", "--1", "+.5"]))
sep = st.sampled_from([",", "\t", " ", "  ", ", ", ";"])
line = st.builds(lambda toks, s, c: s.join(toks) + c,
                 st.lists(number, min_size=0, max_size=5), sep,
                 st.sampled_from(["", " # comment", "#", "\r"]))
text = st.one_of(
    st.lists(line, max_size=12).map("\n".join),
    st.builds(lambda h, body: h + "\n" + body, st.sampled_from(["x,y,z", "# hdr", "x y", ""]),
              st.lists(line, max_size=12).map("\n".join)),
    st.text(max_size=200))
units = st.one_of(st.floats(1e-6, 1e3), st.floats(allow_nan=True, allow_infinity=True),
                  st.sampled_from([1, 0, -1, 1e300, True, "mm", None]))


def _check(pts_or_err, source: str) -> None:
    if isinstance(pts_or_err, CenterlineError):
        msg = str(pts_or_err)
        assert msg.startswith(source), msg  # "<file>:<line>: <what>"
        assert len(msg.splitlines()) == 1, msg
        return
    pts = pts_or_err
    assert pts.ndim == 2 and pts.shape[1] == 3 and pts.shape[0] >= 3
    assert np.isfinite(pts).all()
    assert (np.linalg.norm(np.diff(pts, axis=0), axis=1) > 0).all()


@settings(max_examples=100)
@given(body=text, u=units, closed=st.sampled_from([None, True, False]))
def test_parse_any_text(body: str, u, closed) -> None:
    try:
        pts = parse_centerline_text(body, source="f.csv", units=u, closed=closed)
    except CenterlineError as err:
        _check(err, "f.csv")
        return
    _check(pts, "f.csv")


@settings(max_examples=30)
@given(data=st.binary(max_size=200))
def test_read_any_bytes(tmp_path_factory, data: bytes) -> None:
    path = tmp_path_factory.mktemp("c") / "c.txt"
    path.write_bytes(data)
    try:
        pts = read_centerline(path)
    except CenterlineError as err:
        _check(err, str(path))
        return
    _check(pts, str(path))


def test_missing_file_is_a_clean_error(tmp_path) -> None:
    try:
        read_centerline(tmp_path / "absent.csv")
    except CenterlineError as err:
        assert "absent.csv" in str(err)
    else:
        raise AssertionError("a missing file must raise")


@settings(max_examples=25)
@given(pts=st.lists(st.tuples(*[st.floats(-1, 1)] * 3), min_size=0, max_size=12),
       diameter=st.sampled_from(["0.1", "1", "-1", "nan", "0", "1e-300", "1e300"]),
       mode=st.sampled_from([[], ["--closed"], ["--open"]]))
def test_analyze_command_exits_0_or_2(tmp_path_factory, pts, diameter: str, mode) -> None:
    # The whole command on random polygons: a result (0) or bad input (2), the only exits
    # it defines for analyze; an exception escaping main() would fail here.
    from tightknot.app.cli import main

    folder = tmp_path_factory.mktemp("a")
    f = folder / "c.csv"
    f.write_text("\n".join(f"{x!r},{y!r},{z!r}" for x, y, z in pts) + "\n")
    out = folder / "out.json"
    code = main(["analyze", str(f), "--diameter", diameter, "--quiet", "--json", str(out),
                 *mode])
    assert code in (0, 2)
    if code == 0:
        import json

        def refuse(token: str) -> float:
            raise AssertionError(f"analyze wrote {token} into its JSON")

        # NaN/Infinity are not JSON; Python would read them back unless refused.
        json.loads(out.read_text(), parse_constant=refuse)


def test_units_must_be_positive_finite() -> None:
    for u in (0, -1.0, math.nan, math.inf):
        try:
            parse_centerline_text("0 0 0\n1 0 0\n1 1 0\n", units=u)
        except CenterlineError as err:
            assert "units" in str(err)
        else:
            raise AssertionError(f"units={u} accepted")
