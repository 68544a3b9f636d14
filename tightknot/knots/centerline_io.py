"""Read and write a user's centerline: x y z per line, one line per vertex.

Accepted: comma-separated (csv), tab- or whitespace-separated; lines starting with ``#``
(and anything after a ``#``) are comments; blank lines are skipped; one optional header line
(the first non-comment line, if it holds no number). Exactly three numeric columns.
Errors are one-line :class:`CenterlineError` messages ``<file>:<line>: <what>``.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tightknot.atomic import write_text_atomic

#: Fewest vertices: the Bergou curvature needs a vertex with two edges, a closed polygon three.
MIN_POINTS = 3
#: A closed curve's closing edge (last vertex back to the first) longer than this many mean
#: edge lengths means the data is an open curve: a closed sampled curve joins up within about
#: one edge (a few on non-uniform data), while an open knot's ends are its tails, many rod
#: diameters, i.e. tens to hundreds of edges, apart.
CLOSING_GAP_FACTOR = 5.0


class CenterlineError(ValueError):
    """A centerline file that cannot be used, with file name and line number in the message."""


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def parse_centerline_text(
    text: str, source: str = "<text>", units: float = 1.0, closed: bool | None = None
) -> NDArray[np.float64]:
    """Parse centerline text into (N, 3) points [m] = values * ``units``.

    ``closed``: True checks the curve closes (see CLOSING_GAP_FACTOR) and drops a last vertex
    equal to the first (a repeated closing vertex); False/None do no closure check.
    """
    if not (isinstance(units, int | float) and math.isfinite(units) and units > 0):
        raise CenterlineError(f"{source}: units factor must be a positive finite number")
    rows: list[list[float]] = []
    line_of: list[int] = []
    ncols: int | None = None
    first_col_line = 0
    seen_data = False
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        tokens = [t.strip() for t in line.split(",")] if "," in line else line.split()
        if not seen_data and not any(_is_number(t) for t in tokens):
            seen_data = True  # a header line: names, no numbers
            continue
        seen_data = True
        bad = [t for t in tokens if not _is_number(t)]
        if bad:
            raise CenterlineError(f"{source}:{lineno}: non-numeric value {bad[0][:40]!r}")
        if ncols is None:
            ncols, first_col_line = len(tokens), lineno
            if ncols != 3:
                raise CenterlineError(
                    f"{source}:{lineno}: expected 3 columns (x y z), found {ncols}")
        elif len(tokens) != ncols:
            raise CenterlineError(
                f"{source}:{lineno}: {len(tokens)} columns, but line {first_col_line} has {ncols}")
        values = [float(t) for t in tokens]
        if not all(math.isfinite(v) for v in values):
            raise CenterlineError(f"{source}:{lineno}: NaN or infinite coordinate")
        rows.append(values)
        line_of.append(lineno)
    last_line = line_of[-1] if line_of else max(1, len(text.splitlines()))
    if closed and len(rows) > MIN_POINTS and rows[-1] == rows[0]:
        rows.pop()  # a closed polygon written with its first vertex repeated at the end
        line_of.pop()
    if len(rows) < MIN_POINTS:
        raise CenterlineError(
            f"{source}:{last_line}: {len(rows)} point(s), need at least {MIN_POINTS}")
    with np.errstate(over="ignore", invalid="ignore"):
        pts = np.asarray(rows, dtype=np.float64) * float(units)
    if not np.all(np.isfinite(pts)):
        raise CenterlineError(f"{source}:{line_of[0]}: coordinates overflow after units scaling")
    with np.errstate(over="ignore", invalid="ignore"):
        lengths = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    if not np.all(np.isfinite(lengths)):
        raise CenterlineError(f"{source}:{line_of[0]}: coordinates too large to measure")
    same = np.nonzero(lengths == 0)[0]
    if same.size:
        k = int(same[0])
        raise CenterlineError(
            f"{source}:{line_of[k + 1]}: point repeats the previous one (line {line_of[k]})")
    if closed:
        gap = float(np.linalg.norm(pts[-1] - pts[0]))
        mean_edge = float(lengths.mean())
        if gap == 0:
            raise CenterlineError(f"{source}:{line_of[-1]}: last point repeats the first")
        if gap > CLOSING_GAP_FACTOR * mean_edge:
            raise CenterlineError(
                f"{source}:{line_of[-1]}: curve passed as closed but its ends are "
                f"{gap / mean_edge:.3g} mean edge lengths apart (limit {CLOSING_GAP_FACTOR:g}): "
                "it looks open")
    return pts


def read_centerline(
    path: str | os.PathLike[str], units: float = 1.0, closed: bool | None = None
) -> NDArray[np.float64]:
    """Read a centerline file (csv, tsv, whitespace) into (N, 3) points [m] (values * ``units``)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise CenterlineError(f"{p}:1: not a UTF-8 text file ({exc.reason})") from None
    except OSError as exc:
        raise CenterlineError(f"{p}:0: cannot read ({exc.strerror})") from None
    return parse_centerline_text(text, source=str(p), units=units, closed=closed)


def write_centerline_csv(
    path: str | os.PathLike[str], points: ArrayLike, header: str | None = "x,y,z"
) -> None:
    """Write points (N, 3) as csv atomically; full float precision (round trip exact).

    ``header``: a column-name line (no number in it) or None. Lines of a multi-line header are
    written as ``#`` comments except the last.
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must have shape (N, 3), got {pts.shape}")
    lines = []
    if header:
        *comments, names = header.splitlines()
        lines += [f"# {c}" for c in comments]
        if any(_is_number(t) for t in names.replace(",", " ").split()):
            raise ValueError("header names must not be numbers (they would read back as data)")
        lines.append(names)
    lines += [",".join(repr(float(v)) for v in row) for row in pts]
    write_text_atomic(path, "\n".join(lines) + "\n")
