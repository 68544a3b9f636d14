"""Command-line subcommand of the knots part: ``analyze FILE --diameter D0``.

The study's measurements (physics.md sec. 2, Johanns et al. 2021) on a user's own centerline,
e.g. one traced in a micro-CT scan. The CLI owner calls :func:`register` from
``tightknot/app/cli.py``; the parser gets a ``handler`` default (``args.handler(args) -> int``):
0 ok, 2 bad input (one line on stderr naming the file and line, or the bad option).

Lengths on the command line (file coordinates, ``--diameter``, ``--rest-length``) share one
unit, given by ``--units``; everything written to JSON is SI (metres) or non-dimensional.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

EXIT_OK, EXIT_BAD_INPUT = 0, 2

#: Named units of ``--units``: metres per file unit.
UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6}

#: Contact tolerance of the ideal trefoil drawn on the contact map: 0.2 % of D keeps only the
#: double-contact lines of the tight knot (figures.plot_contact_map docstring).
IDEAL_CONTACT_TOL = 0.002

#: Figure file names written under ``--figures DIR``.
CLOSED_PROFILES_PNG = "closed_profiles.png"
CONTACT_MAP_PNG = "contact_map.png"
OPEN_KNOT_PNG = "open_knot.png"

_ANALYZE_EXAMPLES = """examples:
  # micro-CT centerline in mm of a closed trefoil, D0 = 8.5 mm, the study's smoothing
  tightknot analyze knot.csv --units mm --diameter 8.5 --closed --smooth 25
  # stretch and L/D against the rest length L0 = 139.1 mm, JSON and figures
  tightknot analyze knot.csv --units mm --diameter 8.5 --rest-length 139.1 \\
      --json out/knot.json --figures out/figs
  # open (overhand) knot, coordinates in metres
  tightknot analyze overhand.txt --diameter 0.0085 --open --figures out/
  # the shipped ideal trefoil (tube diameter 1 in its own units)
  tightknot analyze tightknot/knots/data/ideal_trefoil_ridgerunner_cc0_n2400.tsv --diameter 1

  # a micro-CT export: index column, 'x [mm];y [mm];z [mm]' header, decimal commas
  tightknot analyze scan.csv --diameter 8.5 --closed        # units from the header
  tightknot analyze table.csv --columns 3,4,5 --diameter 8.5 --units mm
  tightknot analyze knot.vect --diameter 0.1                # Geomview VECT (KnotPlot too)

file formats: one vertex per line, x y z separated by ';', tabs, commas or spaces (with ';'
or tabs a comma is a decimal comma); '#' starts a comment; any number of header lines; a
4th column that counts 1, 2, 3... is a row index and dropped; other columns are chosen by
the header's x/y/z names or by --columns. A header unit ('x [mm]', 'x (mm)', 'x_mm') is
the file's unit unless --units says the same. Geomview VECT/4VECT of one polyline (a
negative vertex count: closed); KnotPlot's ASCII coordinates (its binary files are
refused). Without --closed/--open the curve is closed when its ends join within 5 mean
edge lengths (a closed file may repeat its first vertex at the end).
--smooth on an open curve moves its ends inward (the study's truncated window): its length,
stretch and L/D come out low, and a warning says by how much (measure them unsmoothed).
Exit codes: 0 ok, 2 bad input (one line on stderr naming the file and line, or the option).
"""


def register(subparsers: Any) -> None:
    """Add the ``analyze`` subcommand to an argparse ``subparsers``."""
    p = subparsers.add_parser(
        "analyze", help="measure a centerline file as the reference study did",
        description="Measure a rod centerline (csv, tsv or whitespace x y z) the way Johanns "
                    "et al. 2021 measured their micro-CT knots: Bergou curvature kappa*D0 "
                    "(optionally after the study's Gaussian smoothing), length, stretch and "
                    "L/D, knot type, contact map, and rho(s), z(s) and double contact "
                    "(closed knots) or Lambda_OC (open knots).",
        epilog=_ANALYZE_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", metavar="FILE", help="centerline file, one 'x y z' vertex per line")
    p.add_argument("--diameter", type=float, required=True, metavar="D0",
                   help="rod diameter at rest, in --units (required)")
    p.add_argument("--closed", action="store_true",
                   help="the curve is closed (checked: its ends must join)")
    p.add_argument("--open", action="store_true",
                   help="the curve is open (default: inferred from the file)")
    p.add_argument("--smooth", type=float, default=None, metavar="N_GAUSS",
                   help="apply the study's smoothing first: resample at D0/60, Gaussian window "
                        "round(N_b/N_GAUSS) points (the study used 25); default: raw polygon")
    p.add_argument("--units", default=None, metavar="UNIT",
                   help="unit of the file and of --diameter/--rest-length: m, cm, mm, um, or "
                        "a factor in metres per file unit (default: the unit the header "
                        "names, as in 'x [mm]' or 'x_mm', else m)")
    p.add_argument("--columns", default=None, metavar="X,Y,Z",
                   help="the x, y, z columns: 1-based numbers (2,3,4) or header names "
                        "(default: the only three, the header's x y z, or the three after a "
                        "row-index column)")
    p.add_argument("--rest-length", type=float, default=None, metavar="L0",
                   help="rest length L0 in --units (default: the measured length, stretch 1)")
    p.add_argument("--poisson", type=float, default=0.5, metavar="NU",
                   help="Poisson ratio of D = D0 [1 - nu (L - L0)/L0] (default 0.5)")
    p.add_argument("--radii", choices=("nominal", "stretch"), default="nominal",
                   help="radii of the contact test: nominal D0/2 (measured data; default), "
                        "or stretch: each section thinned by the rod's mean stretch L/L0, "
                        "L0 = --rest-length (a simulation's own measure at the default "
                        "contact level: a tie's centerline.csv header asks for it)")
    p.add_argument("--json", default=None, metavar="OUT",
                   help="write every measurement to OUT as JSON (atomically; SI units)")
    p.add_argument("--figures", default=None, metavar="DIR",
                   help="write PNG figures to DIR (created if its parent exists)")
    p.add_argument("--quiet", action="store_true", help="print nothing but errors")
    p.set_defaults(handler=run_analyze)


class _BadInput(ValueError):
    """A bad option or output path, reported as one line with exit code 2."""


def _fail(message: str) -> int:
    # One line whatever the message holds (argparse-style prefix, like cli.main's errors).
    one_line = " ".join(str(message).split())
    print(f"tightknot analyze: error: {one_line}", file=sys.stderr)
    return EXIT_BAD_INPUT


def parse_units(text: str) -> float:
    """Metres per file unit from ``--units`` (a name in :data:`UNITS` or a positive factor)."""
    key = text.strip()
    if key in UNITS:
        return UNITS[key]
    try:
        factor = float(key)
    except ValueError:
        raise _BadInput(f"--units {text!r}: unknown unit; use m, cm, mm, um or a factor "
                        "(metres per file unit)") from None
    if not (math.isfinite(factor) and factor > 0):
        raise _BadInput(f"--units {text!r}: the factor must be a positive finite number")
    return factor


def _positive(name: str, value: float | None) -> None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise _BadInput(f"{name} must be a positive finite number, got {value:g}")


def _check_options(args: argparse.Namespace) -> float:
    """Validate the options before any work; return the units factor [m per file unit]."""
    if args.closed and args.open:
        raise _BadInput("--closed and --open are exclusive; give one or neither")
    _positive("--diameter", args.diameter)
    _positive("--rest-length", args.rest_length)
    _positive("--smooth", args.smooth)
    # -1 < nu <= 0.5: the range of an isotropic elastic solid (0.5 incompressible).
    if not (math.isfinite(args.poisson) and -1.0 < args.poisson <= 0.5):
        raise _BadInput(f"--poisson must be in (-1, 0.5], got {args.poisson:g}")
    if args.units is not None:
        parse_units(args.units)
    if args.columns is not None:
        from tightknot.knots.centerline_io import parse_columns

        try:
            args.columns = parse_columns(args.columns)
        except ValueError as err:
            raise _BadInput(str(err)) from None
    _check_json_path(args.json)
    _check_figures_dir(args.figures)
    return 1.0 if args.units is None else parse_units(args.units)


def _check_scaled(args: argparse.Namespace, factor: float) -> None:
    # The lengths in SI must stay finite and non-zero after scaling.
    for name, value in (("--diameter", args.diameter), ("--rest-length", args.rest_length)):
        if value is not None and not (0 < value * factor < math.inf):
            raise _BadInput(f"{name} {value:g} overflows or vanishes in metres (--units)")


def _check_json_path(path: str | None) -> None:
    # Fail before the analysis, not after it (issue 5: output paths are checked first).
    if path is None:
        return
    p = Path(path)
    folder = p.parent if str(p.parent) else Path(".")
    if not folder.is_dir():
        raise _BadInput(f"--json {path}: output folder does not exist: {folder}")
    if p.is_dir():
        raise _BadInput(f"--json {path}: is a folder, not a file")
    if not os.access(folder, os.W_OK):
        raise _BadInput(f"--json {path}: output folder is not writable: {folder}")


def _check_figures_dir(path: str | None) -> None:
    if path is None:
        return
    p = Path(path)
    if p.exists():
        if not p.is_dir():
            raise _BadInput(f"--figures {path}: exists and is not a folder")
        if not os.access(p, os.W_OK):
            raise _BadInput(f"--figures {path}: folder is not writable")
        return
    # Created after the analysis succeeds (no empty folder left behind by bad input), so
    # only its parent must exist now; a missing parent is a typo more often than a wish.
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise _BadInput(f"--figures {path}: parent folder does not exist: {parent}")


def read_points(path: str, factor: float, closed: bool | None,
                columns: tuple | None = None) -> tuple[np.ndarray, bool]:
    """Read FILE [m]; with ``closed`` None take it from the file (a VECT's closed polyline)
    or infer it from its ends. Returns (points, closed).

    Inference uses the reader's closure test (``CLOSING_GAP_FACTOR`` mean edge lengths): a
    closed sampled curve joins up within about one edge, an open knot's tails are far apart.
    """
    from tightknot.knots.centerline_io import CLOSING_GAP_FACTOR, checked_points, read_raw

    raw = read_raw(path, columns)
    if closed is None and raw.closed is not None:
        closed = raw.closed
    if closed is not None:
        return checked_points(raw, path, factor, closed), closed
    pts = checked_points(raw, path, factor, None)
    n = pts.shape[0]
    edges = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    gap = float(np.linalg.norm(pts[-1] - pts[0]))
    if gap == 0:
        is_closed = True  # the first vertex repeated at the end: written as closed
    elif n - 1 <= CLOSING_GAP_FACTOR:
        # Any open polyline of so few edges has its ends within the threshold: the test
        # cannot tell, so measure what was given literally (an open polyline).
        is_closed = False
    else:
        is_closed = gap <= CLOSING_GAP_FACTOR * float(edges.mean())
    if is_closed:
        # Checked again as closed: drops a repeated closing vertex, with the reader's checks.
        pts = checked_points(raw, path, factor, True)
    return pts, is_closed


def file_units(path: str, units: str | None, columns: tuple | None) -> tuple[float, str]:
    """Metres per file unit and where that came from: ``--units`` when given (it must agree
    with a unit the file's header names), else the header's unit, else metres."""
    from tightknot.knots.centerline_io import HEADER_UNITS, read_raw

    header = read_raw(path, columns).unit
    if units is None:
        if header is None:
            return 1.0, "m (default: no --units, no unit in the header)"
        return HEADER_UNITS[header], f"{header} (from the file's header)"
    factor = parse_units(units)
    if header is not None and not math.isclose(factor, HEADER_UNITS[header], rel_tol=1e-12):
        raise _BadInput(f"--units {units}: the header of {path} gives {header}; drop --units "
                        "or fix the header")
    return factor, f"{units} (--units)"


def json_safe(obj: Any) -> Any:
    """``obj`` with NaN/inf as None, numpy arrays and tuples as lists, numpy scalars as Python."""
    if isinstance(obj, Mapping):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, list | tuple):
        return [json_safe(v) for v in obj]
    if isinstance(obj, bool | np.bool_):
        return bool(obj)
    if isinstance(obj, int | np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        v = float(obj)
        return v if math.isfinite(v) else None
    return obj


def summary_lines(report: Mapping[str, Any], path: str, closed_source: str,
                  rest_length_given: bool) -> list[str]:
    """Short human summary of an ``analyze_centerline`` report (non-dimensional numbers)."""
    kind = "closed" if report["closed"] else "open"
    smooth = (f"smoothed (N_gauss = {report['smooth_n_gauss']:g}, "
              f"window {report['smooth_window_points']} points)" if report["smoothed"] else "raw")
    lines = [
        f"{path}: {report['n_points']} points, {kind} ({closed_source}), {smooth}",
        f"  knot type          {report['knot_type']}",
        f"  L/D0               {report['L_over_D0']:.4f}",
    ]
    if rest_length_given:
        lines += [f"  stretch L/L0       {report['stretch_L_over_L0']:.4f}",
                  f"  L/D                {report['L_over_D']:.4f}  "
                  f"(D = D0 [1 - nu (L - L0)/L0], nu = {report['poisson']:g})"]
    else:
        lines.append(f"  L/D                {report['L_over_D']:.4f}  (no --rest-length: D = D0)")
    lines += [
        f"  kappa*D0           max {report['kappa_D0_max']:.3f}, min {report['kappa_D0_min']:.3f}",
        f"  curvature spikes   {report['n_curvature_spikes']} "
        f"(kappa*D0 > {report['spike_threshold_kappa_D0']:g})",
    ]
    dmin = report.get("min_nonlocal_distance_over_D0")
    if dmin is not None:
        lines.append(f"  min distance/D0    {dmin:.4f}  (non-local pairs)")
    if report["closed"]:
        lines.append(f"  double contact     {report['double_contact_fraction']:.3f} of vertices")
    else:
        lam = report.get("Lambda_OC")
        lines.append("  Lambda_OC          " + ("none (no contact)" if lam is None
                                                 else f"{lam:.3f}"))
    return lines


def write_figures(report: Mapping[str, Any], folder: Path, label: str) -> list[Path]:
    """Closed knot: profiles and contact map with the ideal knot of its type where one is
    shipped (a trefoil's as measured; another's placed by its best-matching curvature,
    tightknot.knots.ideal_overlay); open knot: one figure."""
    from tightknot.viz.figures import plot_closed_profiles, plot_contact_map, plot_open_knots

    folder.mkdir(exist_ok=True)
    if not report["closed"]:
        out = folder / OPEN_KNOT_PNG
        plot_open_knots({label: report}, out)
        return [out]
    from tightknot.knots.ideal_overlay import aligned, ideal_report

    # The plotted quantities (s, rho, z, kappa*D0) are non-dimensional, so the ideal knot is
    # measured at D = 1 (with a tight contact tolerance: only its double-contact lines).
    kt = report["knot_type"]
    ideal = ideal_report(kt, 1.0)
    ideal = None if ideal is None else aligned(report, ideal)
    name = {"3_1": "closed trefoil 3_1", "4_1": "closed figure-eight 4_1"}.get(
        kt, f"closed {kt} knot")
    profiles, contact = folder / CLOSED_PROFILES_PNG, folder / CONTACT_MAP_PNG
    plot_closed_profiles(report, profiles, ideal=ideal, label=label, knot=name)
    plot_contact_map(report, contact, ideal=ideal, label=label, knot=name)
    return [profiles, contact]


def run_analyze(args: argparse.Namespace) -> int:
    """Handler of ``tightknot analyze``: returns the exit code (0 ok, 2 bad input)."""
    from tightknot.atomic import write_json_atomic
    from tightknot.knots.centerline_io import CenterlineError
    from tightknot.knots.measure import analyze_centerline

    try:
        _check_options(args)
        factor, unit_source = file_units(args.file, args.units, args.columns)
        _check_scaled(args, factor)
    except _BadInput as err:
        return _fail(str(err))
    except CenterlineError as err:
        return _fail(str(err))  # already "<file>:<line>: <what>"
    given = True if args.closed else (False if args.open else None)
    try:
        points, closed = read_points(args.file, factor, given, args.columns)
    except CenterlineError as err:
        return _fail(str(err))
    rest_length = None if args.rest_length is None else args.rest_length * factor
    if args.radii == "stretch" and rest_length is None:
        return _fail("--radii stretch needs --rest-length (the rod's length at rest)")
    try:
        report = analyze_centerline(points, args.diameter * factor, closed,
                                    smooth_n_gauss=args.smooth, rest_length=rest_length,
                                    poisson=args.poisson,
                                    radii="stretch" if args.radii == "stretch" else None)
    except ValueError as err:
        # Geometry the measures cannot handle (a polygon folding back on itself, ...): the
        # whole curve is at fault, so the message names the file without a line.
        return _fail(f"{args.file}: cannot analyze: {err}")
    if not report["reduced_diameter_D"] > 0:
        # D = D0 [1 - nu (L - L0)/L0] <= 0: L0 is far too short, most likely in other units.
        return _fail(f"--rest-length {args.rest_length:g}: stretch L/L0 = "
                     f"{report['stretch_L_over_L0']:.3g} makes the reduced diameter D <= 0 "
                     "(check --units)")
    closed_source = "as given" if given is not None else "inferred from the file ends"
    warnings = smoothing_warnings(report)
    report = json_safe(report)
    report["input"] = {"file": str(args.file), "units_m_per_file_unit": factor,
                       "units": unit_source,
                       "closed_source": "option" if given is not None else "inferred"}
    report["warnings"] = warnings
    if args.json is not None:
        write_json_atomic(args.json, report)
    written: list[Path] = []
    if args.figures is not None:
        written = write_figures(report, Path(args.figures), Path(args.file).name)
    if not args.quiet:
        print("\n".join(summary_lines(report, args.file, closed_source,
                                      args.rest_length is not None)))
        print(f"  units              {unit_source}")
        for path in ([Path(args.json)] if args.json else []) + written:
            print(f"  wrote {path}")
    for warning in warnings:
        print(f"tightknot analyze: warning: {warning}", file=sys.stderr)
    return EXIT_OK


#: Relative length change by smoothing worth a warning: the 4th decimal of the printed
#: stretch L/L0 (smaller changes do not show in the summary).
SMOOTHING_LENGTH_TOL = 1e-4


def smoothing_warnings(report: Mapping[str, Any]) -> list[str]:
    """A warning when the study's smoothing shortened an open curve: its truncated window
    pulls each end inward along its tail (tightknot.knots.smoothing, "Ends of an open
    curve"), so length, stretch and L/D come out low by that much, noise or none."""
    if not report.get("smoothed") or report["closed"]:
        return []
    before, after = report["length_before_smoothing"], report["length_L"]
    change = (after - before) / before
    if abs(change) <= SMOOTHING_LENGTH_TOL:
        return []
    return [f"--smooth changed the open curve's length by {100 * change:+.2f} % (the "
            "study's truncated window pulls each end inward along its tail), so stretch "
            "and L/D are biased by as much; measure them without --smooth"]
