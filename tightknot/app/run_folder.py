"""The run folder of ``tightknot tie``: where every output of one run goes, checked first.

Layout of ``--out DIR`` (default ``runs/<scene>-<UTC timestamp>``)::

    DIR/config.json      the exact parameters (tightknot tie --config DIR/config.json reruns it)
    DIR/summary.json     the JSON summary (converged, failure, measurements, centerline_m)
    DIR/centerline.csv   the final centerline x,y,z [m] (tightknot analyze reads it back)
    DIR/figures/         the study's figures and the tube coloured by curvature
    DIR/run.rrd          the rerun log of every load step

``--json``, ``--rrd`` and ``--figures`` send one output elsewhere. Every path is checked
before the run starts (folder exists and takes a file, path not a folder), so bad output
paths cost a message, not minutes of work.
"""

from __future__ import annotations

import datetime as _dt
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

SUMMARY_JSON = "summary.json"
CONFIG_JSON = "config.json"
CENTERLINE_CSV = "centerline.csv"
RUN_RRD = "run.rrd"
FIGURES_DIR = "figures"


#: The tree of run folders in the working folder, created on demand.
RUNS_ROOT = Path("runs")


def in_runs_tree(path: Path) -> bool:
    """True for a relative path under ``runs/``: its missing parents are made on demand (a
    fresh checkout has no ``runs/`` yet); any other new folder needs an existing parent."""
    return not path.is_absolute() and path.parts[:1] == RUNS_ROOT.parts


def default_run_dir(scene_name: str, now: _dt.datetime | None = None,
                    root: Path = RUNS_ROOT) -> Path:
    """``runs/<scene>-<YYYYmmdd-HHMMSS>`` (UTC); ``-2``, ``-3``... when that one exists."""
    stamp = (now or _dt.datetime.now(_dt.timezone.utc)).strftime("%Y%m%d-%H%M%S")
    base = root / f"{scene_name}-{stamp}"
    path, k = base, 1
    while path.exists():
        k += 1
        path = base.with_name(f"{base.name}-{k}")
    return path


def _probe(folder: Path, what: str) -> None:
    """Create and delete a file in ``folder``: the only sure test that it takes files."""
    try:
        with tempfile.TemporaryFile(dir=folder, prefix=".tightknot-probe-"):
            pass
    except OSError as exc:
        raise ValueError(f"{what}: cannot write in {folder} ({exc.strerror})") from None


def check_output_file(path: Path, what: str) -> Path:
    """An output file whose folder exists and takes files, and that is not a folder."""
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise ValueError(f"{what} {path}: output folder does not exist: {folder}")
    if path.is_dir():
        raise ValueError(f"{what} {path}: is a folder, not a file")
    _probe(folder, f"{what} {path}")
    return path


def check_output_dir(path: Path, what: str, parents: bool = False) -> Path:
    """An output folder that exists and takes files, or whose parent does (it is created
    later, so bad input leaves no empty folder). ``parents``: missing parents are fine too
    (the default ``runs/`` tree); the nearest existing ancestor must then take files."""
    if path.exists():
        if not path.is_dir():
            raise ValueError(f"{what} {path}: exists and is not a folder")
        _probe(path, f"{what} {path}")
        return path
    parent = path.parent if str(path.parent) else Path(".")
    if parents:
        while not parent.exists():
            parent = parent.parent if str(parent.parent) else Path(".")
    if not parent.is_dir():
        raise ValueError(f"{what} {path}: parent folder does not exist: {parent}")
    _probe(parent, f"{what} {path}")
    return path


@dataclass(frozen=True)
class RunOutputs:
    """Paths of one run's outputs (see the module docstring)."""

    folder: Path
    summary: Path
    config: Path
    centerline: Path
    rrd: Path
    figures: Path

    def files(self) -> list[Path]:
        """Every output, in the order a run writes them (the figures folder last)."""
        return [self.config, self.summary, self.centerline, self.rrd, self.figures]

    def create(self) -> None:
        """Make the run folder (and the default tree above it); the figures folder is
        made by the figure writer."""
        self.folder.mkdir(parents=True, exist_ok=True)


def plan_outputs(scene_name: str, out: str | None = None, json: str | None = None,
                 rrd: str | None = None, figures: str | None = None,
                 overwrite: bool = False) -> RunOutputs:
    """Resolve and check every output path of a run before it starts (ValueError if bad).

    ``out`` None: :func:`default_run_dir`. A folder under ``runs/`` is made with its parents;
    any other may be new but its parent must exist (a missing parent is a typo more often
    than a wish). An output that exists already (a file, or a figures folder with files in
    it) is refused unless ``overwrite``: a rerun must not replace a run without being asked.
    """
    folder = Path(out) if out is not None else default_run_dir(scene_name)
    check_output_dir(folder, "--out", parents=in_runs_tree(folder))
    summary = Path(json) if json is not None else folder / SUMMARY_JSON
    rrd_path = Path(rrd) if rrd is not None else folder / RUN_RRD
    figs = Path(figures) if figures is not None else folder / FIGURES_DIR
    if json is not None:
        check_output_file(summary, "--json")
    if rrd is not None:
        if rrd_path.suffix != ".rrd":
            raise ValueError(f"--rrd {rrd}: the file name must end in .rrd (the viewer "
                             "recognises recordings by it)")
        check_output_file(rrd_path, "--rrd")
    if figures is not None:
        check_output_dir(figs, "--figures")
    outs = RunOutputs(folder, summary, folder / CONFIG_JSON, folder / CENTERLINE_CSV,
                      rrd_path, figs)
    if not overwrite:
        refuse_existing(outs.files(), "--overwrite")
    return outs


def refuse_existing(paths: list[Path], flag: str) -> None:
    """ValueError naming the outputs in ``paths`` that exist already (a figures folder
    counts when it holds a file), and the ``flag`` that allows replacing them."""
    taken = [p for p in paths if p.is_file() or (p.is_dir() and any(p.iterdir()))]
    if taken:
        names = ", ".join(str(p) for p in taken)
        raise ValueError(f"{names}: already written by an earlier run; give {flag} to "
                         "replace it, or choose another output")


def write_centerline(path: Path, x: np.ndarray, scene_name: str, diameter: float,
                     rest_length: float, closed: bool) -> None:
    """The final centerline as csv [m], with a header saying how to measure it again."""
    from tightknot.knots.centerline_io import write_centerline_csv

    kind = "--closed" if closed else "--open"
    header = (f"final centerline [m] of {scene_name}, D0 = {diameter!r} m, L0 = "
              f"{rest_length!r} m\n"
              f"measure it: tightknot analyze {path.name} --diameter {diameter!r} "
              f"--rest-length {rest_length!r} --radii stretch {kind}\n"
              "x_m,y_m,z_m")
    write_centerline_csv(path, x, header=header)

