"""Read and write a user's centerline: one vertex per line, or a Geomview VECT file.

Tables (plain xyz, csv, tsv, KnotPlot's ASCII coordinates, micro-CT exports): lines
starting with ``#`` (and anything after a ``#``) are comments; blank lines are skipped; any
number of header lines (lines before the data that are not all numbers: a title, names). The
delimiter is found from the first data line: ``;``, else a tab, else ``,``, else
whitespace; with ``;`` or a tab a comma inside a value is a decimal comma (``9883,1``).
Three numeric columns are x y z; more are allowed when the header names the x, y and z
columns, when the first column is a row index (consecutive integers), or when ``columns``
picks them. A unit in the header (``x [mm]``, ``x (mm)``, ``x_mm``) is reported
(:attr:`RawCenterline.unit`). A VECT of several polylines (a link) is refused: one rod is
measured. KnotPlot's binary format is refused with a hint; its ASCII coordinates are a
table.

Geomview VECT (http://www.geomview.org/docs/html/VECT.html): ``VECT`` or ``4VECT``, then
NPolylines NVertices NColors, the vertex count of each polyline (negative: closed), the
colour count of each, the vertices (3 floats, or 4 homogeneous ones for 4VECT), the colours.

Errors are one-line :class:`CenterlineError` messages ``<file>:<line>: <what>``.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
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
#: Length units a header may name, in metres.
HEADER_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6}
_UNIT_RE = re.compile(r"^\s*([xyz])\s*(?:\[\s*(\S+?)\s*\]|\(\s*(\S+?)\s*\)|_(\S+))?\s*$",
                      re.IGNORECASE)


class CenterlineError(ValueError):
    """A centerline file that cannot be used, with file name and line number in the message."""


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


@dataclass
class RawCenterline:
    """A centerline as the file gives it: values in the file's unit.

    Attributes:
        values: (N, 3) coordinates in file units.
        lines: the line number of each vertex (1-based).
        unit: the length unit the header names (a key of :data:`HEADER_UNITS`), or None.
        closed: True when the format says the curve is closed (a VECT polyline of negative
            count), else None (not said).
        fmt: "table" or "vect".
        last_line: the file's last line (for errors about the whole file).
    """

    values: list[list[float]]
    lines: list[int]
    unit: str | None
    closed: bool | None
    fmt: str
    last_line: int


def _split(line: str, delim: str | None) -> list[str]:
    if delim is None:
        return line.split()
    tokens = [t.strip() for t in line.split(delim)]
    if delim in (";", "\t"):
        tokens = [t.replace(",", ".") for t in tokens]  # a decimal comma
    return tokens


def _delimiter(line: str) -> str | None:
    for d in (";", "\t", ","):
        if d in line:
            return d
    return None


def _header_columns(names: list[str], source: str, lineno: int) -> tuple[dict[str, int],
                                                                      str | None]:
    """Column index of x, y and z in a header line (when it names them all) and the unit
    it gives (None when none)."""
    found: dict[str, int] = {}
    units: set[str] = set()
    for i, name in enumerate(names):
        m = _UNIT_RE.match(name)
        if m is None:
            continue
        axis = m.group(1).lower()
        unit = next((g for g in m.groups()[1:] if g), None)
        if unit is not None and unit not in HEADER_UNITS:
            continue  # x_index, x (px): not a length column
        if axis not in found:
            found[axis] = i
            if unit is not None:
                units.add(unit)
    if len(units) > 1:
        raise CenterlineError(f"{source}:{lineno}: the header gives several units "
                              f"({', '.join(sorted(units))}) for x, y and z")
    return (found if len(found) == 3 else {}), (units.pop() if units else None)


def parse_columns(text: str) -> tuple[int, int, int] | tuple[str, str, str]:
    """``--columns``: three 1-based column numbers (``2,3,4``) or three header names
    (``X,Y,Z``), comma-separated. Raises ValueError naming the option and the valid form."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 3 or not all(parts):
        raise ValueError(f"--columns {text!r}: give three columns x,y,z as 1-based numbers "
                         "(2,3,4) or header names (X,Y,Z)")
    if all(p.isdigit() for p in parts):
        nums = tuple(int(p) for p in parts)
        if min(nums) < 1 or len(set(nums)) != 3:
            raise ValueError(f"--columns {text!r}: column numbers start at 1 and must differ")
        return nums  # type: ignore[return-value]
    return tuple(parts)  # type: ignore[return-value]


def _parse_vect(tokens: list[tuple[str, int]], source: str) -> RawCenterline:
    """A Geomview VECT (module docstring) of one polyline."""
    word, line0 = tokens[0]
    width = 4 if word.upper() == "4VECT" else 3
    pos = 1

    def ints(n: int, what: str) -> list[int]:
        nonlocal pos
        out = []
        for _ in range(n):
            if pos >= len(tokens):
                raise CenterlineError(f"{source}:{tokens[-1][1]}: VECT ends before its {what}")
            tok, ln = tokens[pos]
            try:
                out.append(int(tok))
            except ValueError:
                raise CenterlineError(f"{source}:{ln}: VECT {what}: expected an integer, "
                                      f"found {tok[:40]!r}") from None
            pos += 1
        return out

    n_lines, n_vertices, n_colors = ints(3, "counts (NPolylines NVertices NColors)")
    if n_lines != 1:
        raise CenterlineError(f"{source}:{line0}: VECT holds {n_lines} polylines; tightknot "
                              "measures one rod (save one component)")
    (nv,) = ints(1, "vertex count")
    ints(1, "colour count")
    if abs(nv) != n_vertices:
        raise CenterlineError(f"{source}:{line0}: VECT vertex count {nv} does not match "
                              f"NVertices {n_vertices}")
    if n_colors < 0:
        raise CenterlineError(f"{source}:{line0}: VECT NColors {n_colors} is negative")
    values, lines = [], []
    for _ in range(abs(nv)):
        if pos + width > len(tokens):
            raise CenterlineError(f"{source}:{tokens[-1][1]}: VECT ends after {len(values)} "
                                  f"of its {abs(nv)} vertices")
        chunk = tokens[pos:pos + width]
        bad = [t for t, _ in chunk if not _is_number(t)]
        if bad:
            raise CenterlineError(f"{source}:{chunk[0][1]}: non-numeric value {bad[0][:40]!r}")
        v = [float(t) for t, _ in chunk]
        if not all(math.isfinite(c) for c in v):
            raise CenterlineError(f"{source}:{chunk[0][1]}: NaN or infinite coordinate")
        if width == 4:
            if v[3] == 0:
                raise CenterlineError(f"{source}:{chunk[0][1]}: 4VECT vertex with w = 0 "
                                      "(a point at infinity)")
            v = [c / v[3] for c in v[:3]]
        values.append(v)
        lines.append(chunk[0][1])
        pos += width
    return RawCenterline(values, lines, None, True if nv < 0 else None, "vect",
                         tokens[-1][1])


def parse_raw(text: str, source: str = "<text>",
              columns: tuple[int, int, int] | tuple[str, str, str] | None = None
              ) -> RawCenterline:
    """The vertices of centerline ``text`` in the file's unit (module docstring for the
    formats); ``columns``: x, y, z as 1-based numbers or header names."""
    if text.startswith("KnotPlot 1.0"):
        raise CenterlineError(f"{source}:1: a binary KnotPlot file; save the knot as ASCII "
                              "coordinates (x y z per line) or as a Geomview VECT instead")
    tokens: list[tuple[str, int]] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        tokens += [(t, lineno) for t in raw.split("#", 1)[0].split()]
        if len(tokens) > 1:
            break
    if tokens and tokens[0][0].upper() in ("VECT", "4VECT"):
        every = [(t, n) for n, raw in enumerate(text.splitlines(), start=1)
                 for t in raw.split("#", 1)[0].split()]
        return _parse_vect(every, source)
    return _parse_table(text, source, columns)


def _parse_table(text: str, source: str,
                 columns: tuple[int, int, int] | tuple[str, str, str] | None) -> RawCenterline:
    rows: list[list[float]] = []
    line_of: list[int] = []
    ncols: int | None = None
    first_col_line = 0
    delim: str | None = None
    header: list[tuple[int, str]] = []
    unit: str | None = None
    pick: list[int] | None = None
    index, index0 = False, 0.0
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if not rows and ncols is None:
            d = _delimiter(line)
            tokens = _split(line, d)
            chosen = _chosen(tokens, header, d, columns)
            if not all(_is_number(t) for t in chosen):
                header.append((lineno, line))  # a header line: not all numbers
                continue
            delim = d
        tokens = _split(line, delim)
        bad = [t for t in (_chosen(tokens, header, delim, columns) if columns else tokens)
               if not _is_number(t)]
        if bad:
            raise CenterlineError(f"{source}:{lineno}: non-numeric value {bad[0][:40]!r}")
        values = [float(t) if _is_number(t) else math.nan for t in tokens]
        if ncols is None:
            ncols, first_col_line = len(tokens), lineno
            pick, unit, index = _choose_columns(ncols, header, delim, columns, values, source,
                                                lineno)
            index0 = values[0]
        elif len(tokens) != ncols:
            raise CenterlineError(
                f"{source}:{lineno}: {len(tokens)} columns, but line {first_col_line} has {ncols}")
        if index and values[0] != index0 + len(rows):
            raise CenterlineError(f"{source}:{lineno}: the first column was taken for a row "
                                  "index but does not count up by 1 here; pick x y z with "
                                  "--columns")
        row = [values[i] for i in pick] if pick is not None else values
        if not all(math.isfinite(v) for v in row):
            raise CenterlineError(f"{source}:{lineno}: NaN or infinite coordinate")
        rows.append(row)
        line_of.append(lineno)
    if not rows and header:
        # Every line was taken for a header: a column of text, most likely.
        hl, htext = header[-1]
        bad = next(t for t in _split(htext, _delimiter(htext)) if not _is_number(t))
        raise CenterlineError(f"{source}:{hl}: no line of numbers: every line holds a "
                              f"non-numeric value (here {bad[:40]!r}); a text column can be "
                              "left out with --columns")
    last_line = line_of[-1] if line_of else max(1, len(text.splitlines()))
    return RawCenterline(rows, line_of, unit, None, "table", last_line)


def _chosen(tokens: list[str], header: list[tuple[int, str]], delim: str | None,
            columns: tuple | None) -> list[str]:
    """The tokens of the ``columns`` asked for (all tokens when none were, or when they
    cannot be found on this line: the caller then reports the line as it is)."""
    if columns is None:
        return tokens
    if isinstance(columns[0], int):
        idx = [c - 1 for c in columns]
    else:
        names = [n.lower() for n in _split(header[-1][1], delim)] if header else []
        if not all(c.lower() in names for c in columns):
            return tokens
        idx = [names.index(c.lower()) for c in columns]
    return [tokens[i] for i in idx] if max(idx) < len(tokens) else tokens


def _choose_columns(ncols: int, header: list[tuple[int, str]], delim: str | None,
                    columns: tuple | None, first: list[float], source: str, lineno: int
                    ) -> tuple[list[int] | None, str | None, bool]:
    """Which columns are x, y, z (None: all three), the header's unit, and whether the
    first column was taken for a row index (to be checked on every line)."""
    named: dict[str, int] = {}
    unit: str | None = None
    names: list[str] = []
    for hl, text in header:
        names = _split(text, delim)
        found, u = _header_columns(names, source, hl)
        unit = u or unit
        if found and len(names) == ncols:
            named = found
    if columns is not None:
        if isinstance(columns[0], int):
            if max(columns) > ncols:
                raise CenterlineError(f"{source}:{lineno}: --columns {max(columns)} but the "
                                      f"data has {ncols} columns")
            return [c - 1 for c in columns], unit, False
        lower = [n.lower() for n in names] if len(names) == ncols else []
        missing = [c for c in columns if c.lower() not in lower]
        if missing:
            raise CenterlineError(f"{source}:{lineno}: --columns {missing[0]!r} is not a "
                                  "header name" + (f" (names: {', '.join(names)})" if lower
                                                   else " (no header of as many names)"))
        return [lower.index(c.lower()) for c in columns], unit, False
    if ncols == 3:
        return None, unit, False
    if named:
        return [named["x"], named["y"], named["z"]], unit, False
    if ncols == 4 and float(first[0]).is_integer() and not header:
        return [1, 2, 3], unit, True  # a row index first, checked on every line
    raise CenterlineError(
        f"{source}:{lineno}: expected 3 columns (x y z), found {ncols}; pick them with "
        "--columns (1-based numbers like 2,3,4, or header names)")


def parse_centerline_text(
    text: str, source: str = "<text>", units: float = 1.0, closed: bool | None = None,
    columns: tuple[int, int, int] | tuple[str, str, str] | None = None,
) -> NDArray[np.float64]:
    """Parse centerline text into (N, 3) points [m] = values * ``units``.

    ``closed``: True checks the curve closes (see CLOSING_GAP_FACTOR) and drops a last vertex
    equal to the first (a repeated closing vertex); False/None do no closure check.
    ``columns``: x, y, z as 1-based column numbers or header names (:func:`parse_columns`).
    """
    if not (isinstance(units, int | float) and math.isfinite(units) and units > 0):
        raise CenterlineError(f"{source}: units factor must be a positive finite number")
    return checked_points(parse_raw(text, source, columns), source, units, closed)


def checked_points(raw: RawCenterline, source: str, units: float = 1.0,
                   closed: bool | None = None) -> NDArray[np.float64]:
    """The points [m] of ``raw`` (values * ``units``), checked: enough of them, finite,
    no vertex repeating the previous one, and (``closed`` True) ends that join."""
    rows, line_of = [list(r) for r in raw.values], list(raw.lines)
    last_line = raw.last_line
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


def read_raw(path: str | os.PathLike[str],
             columns: tuple[int, int, int] | tuple[str, str, str] | None = None
             ) -> RawCenterline:
    """The vertices of a centerline file in its own unit (:func:`parse_raw`)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise CenterlineError(f"{p}:1: not a UTF-8 text file ({exc.reason})") from None
    except OSError as exc:
        raise CenterlineError(f"{p}:0: cannot read ({exc.strerror})") from None
    return parse_raw(text, str(p), columns)


def read_centerline(
    path: str | os.PathLike[str], units: float = 1.0, closed: bool | None = None,
    columns: tuple[int, int, int] | tuple[str, str, str] | None = None,
) -> NDArray[np.float64]:
    """Read a centerline file (module docstring) into (N, 3) points [m] (values *
    ``units``)."""
    if not (isinstance(units, int | float) and math.isfinite(units) and units > 0):
        raise CenterlineError(f"{path}: units factor must be a positive finite number")
    return checked_points(read_raw(path, columns), str(path), units, closed)


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
