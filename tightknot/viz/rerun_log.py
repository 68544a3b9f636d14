"""Rerun visual logs of a knot run: rods as coloured tubes, contacts, scalar series.

Logging only, never physics: every method takes plain numpy arrays in SI units and fields that
the caller has already computed (curvature, area ratio, stretch, contact width, p/E).

Design notes
------------
- Each :class:`RerunLogger` owns a dedicated ``rerun.RecordingStream`` (never the global one),
  so several logs can be written by one process at the same time.
- The recording is streamed to a hidden temporary file beside the target and renamed onto the
  target by :meth:`RerunLogger.close`. A run that raises inside ``with RerunLogger(...)`` (or
  that is killed) never leaves a half-written ``.rrd`` at the target path.
- Time is the ``load_step`` sequence timeline (one step of the load continuation or of the
  dynamics), set by :meth:`RerunLogger.set_step`.
- Rerun stores positions and radii as float32: positions read back equal the input to float32
  precision (about 6e-8 relative, i.e. ~1e-8 m on a 0.14 m knot), which is far below anything
  one can see.
- ``LineStrips3D`` colours and radii apply per strip, so a tube coloured along its length is
  logged as one two-point strip per edge.
- :class:`NullLogger` has the same methods and does nothing, so a run without logging pays one
  no-op call per log site.
"""

from __future__ import annotations

import contextlib
import math
import os
import uuid
from collections.abc import Mapping
from pathlib import Path
from types import TracebackType
from typing import Literal, Protocol

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from tightknot.viz.colormap import colorize

LOAD_STEP_TIMELINE = "load_step"
"""Name of the sequence timeline that indexes every temporal entity."""

PLOTS_ROOT = "plots"
"""Entity subtree of the scalar series (``plots/<key>``); excluded from the 3D view."""

FieldLocation = Literal["vertex", "edge"]


# Fields a rod may be coloured by: name -> (colour map, default limits or None = automatic,
# where the field naturally lives). The location only settles the one ambiguous case, a closed
# rod, whose vertex and edge counts are equal (N == E); otherwise the length decides.
ROD_FIELDS: dict[str, tuple[str, tuple[float, float] | None, FieldLocation]] = {
    # Normalised curvature kappa*D0 [1], per vertex (discrete curvature lives on vertices).
    # Automatic limits: the interesting range (loose loop ~0.3 to tight contact ~2) varies by run.
    "kappa_D0": ("magma", None, "vertex"),
    # Cross-section area A/A0 [1], per vertex (reported by the contact layer per vertex).
    # Diverging map: < 1 (squeezed or stretched thin) vs > 1 reads at a glance.
    "area_ratio": ("coolwarm", None, "vertex"),
    # Axial stretch |e|/|e0| [1], per edge.
    "stretch": ("coolwarm", None, "edge"),
    # Contact width L_c / perimeter [1], per vertex; a fraction, so fixed limits [0, 1] make
    # colours comparable between steps and runs.
    "contact_width_fraction": ("viridis", (0.0, 1.0), "vertex"),
}

# Colour map of contact pressure p/E [1]; automatic limits.
CONTACT_CMAP = "magma"

# Uniform colour of a rod logged without a field (light steel blue: neutral, not on any map).
ROD_PLAIN_RGB = (176, 196, 222)

# Uniform colours of the rods of a several-rod scene, rod 0 first (blue, orange, green,
# red: the figures' colours, so that a rod has one colour in the viewer and in the plots).
ROD_COLORS_RGB = ((31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40))

# The reference (ideal) knot is drawn as its grey centreline, thinner than the tube so that the
# elastic rod around it stays visible: this fraction of the reference tube radius.
REFERENCE_LINE_FRACTION = 0.15
REFERENCE_RGB = (150, 150, 150)

# Recommended scalar keys for :meth:`RerunLogger.log_scalars` (free-form keys are accepted too).
# "a/b" keys are drawn together in one plot "a"; a plain key gets a plot of its own.
STANDARD_SCALARS: dict[str, str] = {
    "pulling_force": "pulling force on the ends [N]",
    "lambda_oc": "open-knot length Lambda_OC = (s2 - s1)/D0 [1]",
    "end_to_end": "end-to-end distance [m]",
    "energy/stretch": "stretching energy [J]",
    "energy/bend": "bending energy [J]",
    "energy/twist": "twisting energy [J]",
    "energy/contact": "contact energy [J]",
    "newton_residual": "norm of the Newton force residual [N]",
    "newton_iterations": "Newton iterations of the step [1]",
}


class VisualLogger(Protocol):
    """What a solver or CLI command may call; both loggers below satisfy it."""

    def set_step(self, step: int, load: float | None = None) -> None: ...
    def log_rod(
        self,
        name: str,
        positions: np.ndarray,
        closed: bool,
        radii: np.ndarray | float,
        field: np.ndarray | None = None,
        field_name: str | None = None,
        limits: tuple[float, float] | None = None,
        *,
        field_at: FieldLocation | None = None,
        radii_at: FieldLocation | None = None,
        color: tuple[int, int, int] | None = None,
    ) -> None: ...
    def log_contacts(
        self,
        name: str,
        points_a: np.ndarray,
        points_b: np.ndarray,
        pressure_over_E: np.ndarray,
        limits: tuple[float, float] | None = None,
        radius: float | None = None,
    ) -> None: ...
    def log_scalars(self, mapping: Mapping[str, float]) -> None: ...
    def log_reference(
        self, name: str, positions: np.ndarray, radius: float, closed: bool = True
    ) -> None: ...
    def close(self) -> None: ...
    def abort(self) -> None: ...


# --------------------------------------------------------------------------------------------
# Array checks and the vertex -> edge mapping (pure functions, shared by the logger).


def _positions(positions: np.ndarray, what: str, min_count: int = 0) -> np.ndarray:
    """Check an (N, 3) array of finite positions [m]; return it as float64."""
    p = np.asarray(positions, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"{what} must have shape (N, 3), got {p.shape}")
    if p.shape[0] < min_count:
        raise ValueError(f"{what} needs at least {min_count} points, got {p.shape[0]}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{what} contains non-finite values")
    return p


def edge_count(vertex_count: int, closed: bool) -> int:
    """Number of edges of a rod with ``vertex_count`` vertices (closed rods wrap around)."""
    return vertex_count if closed else vertex_count - 1


def edge_segments(positions: np.ndarray, closed: bool) -> np.ndarray:
    """Edge end points, shape (E, 2, 3) [m]: edge i joins vertex i to vertex i+1 (mod N)."""
    nxt = np.roll(positions, -1, axis=0) if closed else positions[1:]
    start = positions if closed else positions[:-1]
    return np.stack([start, nxt], axis=1)


def to_edges(
    values: np.ndarray | float,
    vertex_count: int,
    closed: bool,
    default_at: FieldLocation,
    at: FieldLocation | None = None,
    what: str = "field",
) -> np.ndarray:
    """Return a per-edge array (E,) from a scalar, a per-vertex (N,) or a per-edge (E,) array.

    A vertex field is averaged onto edges: edge i gets (v_i + v_{i+1})/2 (mod N when closed),
    the midpoint value of a linear interpolation along the edge. NaN propagates (drawn grey).
    ``at`` forces the location; without it the length decides, and ``default_at`` settles a
    closed rod, where N == E.
    """
    n_edges = edge_count(vertex_count, closed)
    v = np.asarray(values, dtype=np.float64)
    if v.ndim == 0:
        return np.full(n_edges, float(v))
    if v.ndim != 1:
        raise ValueError(f"{what} must be 1-D, got shape {v.shape}")
    if at is None:
        if v.shape[0] == vertex_count and v.shape[0] != n_edges:
            at = "vertex"
        elif v.shape[0] == n_edges and v.shape[0] != vertex_count:
            at = "edge"
        else:
            at = default_at
    expected = vertex_count if at == "vertex" else n_edges
    if v.shape[0] != expected:
        raise ValueError(
            f"{what} has length {v.shape[0]}; expected {vertex_count} (per vertex) or "
            f"{n_edges} (per edge) for a {'closed' if closed else 'open'} rod of "
            f"{vertex_count} vertices"
        )
    if at == "edge":
        return v
    nxt = np.roll(v, -1) if closed else v[1:]
    start = v if closed else v[:-1]
    return 0.5 * (start + nxt)


def _check_field_name(field_name: str) -> None:
    if field_name not in ROD_FIELDS:
        raise ValueError(
            f"unknown rod field {field_name!r}; valid names: {', '.join(sorted(ROD_FIELDS))}"
        )


def _check_name(name: str) -> str:
    """Entity names are relative paths outside the plots subtree (kept for scalar series)."""
    clean = name.strip("/")
    if not clean:
        raise ValueError("entity name must not be empty")
    if clean == PLOTS_ROOT or clean.startswith(PLOTS_ROOT + "/"):
        raise ValueError(f"entity names under '{PLOTS_ROOT}/' are reserved for scalar series")
    return clean


# --------------------------------------------------------------------------------------------
# Blueprint.


def plot_groups(keys: list[str] | set[str]) -> list[str]:
    """Top-level plot names of scalar keys: "energy/bend" -> "energy", "pulling_force" -> itself.

    Sorted, without duplicates; one time-series view is made per group.
    """
    return sorted({key.strip("/").split("/")[0] for key in keys})


def default_blueprint(groups: list[str] | None = None) -> rrb.Blueprint:
    """The default layout: the 3D scene on the left, one time-series view per plot group.

    ``groups`` are the children of ``plots/`` (see :func:`plot_groups`); None or empty gives one
    view of the whole ``plots/`` subtree.
    """
    scene = rrb.Spatial3DView(name="knot", origin="/", contents=["+ /**", f"- /{PLOTS_ROOT}/**"])
    if groups:
        plots = [rrb.TimeSeriesView(name=g, origin=f"/{PLOTS_ROOT}/{g}") for g in groups]
    else:
        plots = [rrb.TimeSeriesView(name=PLOTS_ROOT, origin=f"/{PLOTS_ROOT}")]
    return rrb.Blueprint(
        rrb.Horizontal(scene, rrb.Grid(*plots), column_shares=[3, 2]),
        # Side panels folded to leave room for the views; the time panel stays open on the
        # load_step timeline, since scrubbing the steps is the point of the log.
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(timeline=LOAD_STEP_TIMELINE, state="expanded"),
    )


# --------------------------------------------------------------------------------------------
# Loggers.


class RerunLogger:
    """Write a rerun recording (.rrd) of a run, atomically.

    Parameters
    ----------
    path:
        Target ``.rrd`` file. Its folder must exist. Data goes to a hidden temporary file
        beside it (``.<name>.<hex>.tmp``) until :meth:`close` renames it onto ``path``.
    application_id:
        Rerun application id (the viewer groups recordings and blueprints by it).
    recording_id:
        Rerun recording id; None = a fresh random one, so loggers never merge by accident.

    Use as a context manager: leaving the block normally closes (commits) the file, leaving it
    by an exception aborts it (temporary file removed, ``path`` untouched).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        application_id: str = "tightknot",
        *,
        recording_id: str | None = None,
    ) -> None:
        self.path = Path(path)
        folder = self.path.parent if str(self.path.parent) else Path(".")
        if not folder.is_dir():
            raise FileNotFoundError(f"output folder does not exist: {folder}")
        # A unique hidden name that rerun creates itself (so the file gets the usual
        # umask-derived permissions, unlike mkstemp's 0600).
        self._tmp: Path | None = folder / f".{self.path.name}.{uuid.uuid4().hex}.tmp"
        self._step: int | None = None
        self._scalar_keys: set[str] = set()
        try:
            # A dedicated stream (make_default False): several loggers may coexist, and the
            # process-wide recording of other code is left alone.
            self._rec: rr.RecordingStream | None = rr.RecordingStream(
                application_id,
                recording_id=recording_id,
                make_default=False,
                make_thread_default=False,
            )
            if not rr.is_enabled(recording=self._rec):
                # RERUN=off in the environment disables every stream: fail here, clearly,
                # rather than produce no file (or a confusing error at close).
                raise RuntimeError(
                    "rerun logging is disabled (RERUN=off in the environment); unset RERUN "
                    "or run without a log path"
                )
            self._rec.save(self._tmp)
        except BaseException:
            self._discard()
            raise

    # -- state --------------------------------------------------------------------------------

    @property
    def closed(self) -> bool:
        """True once :meth:`close` or :meth:`abort` has run."""
        return self._rec is None

    def _stream(self) -> rr.RecordingStream:
        if self._rec is None:
            raise RuntimeError(f"logger for {self.path} is closed")
        return self._rec

    def _temporal(self) -> rr.RecordingStream:
        """The stream, checked to have a step: temporal data without one would be missing
        from the load_step timeline and invisible when scrubbing it."""
        rec = self._stream()
        if self._step is None:
            raise RuntimeError("call set_step() before logging temporal data")
        return rec

    # -- logging ------------------------------------------------------------------------------

    def set_step(self, step: int, load: float | None = None) -> None:
        """Set the ``load_step`` timeline for what follows; optionally log ``plots/load``.

        ``load`` is the continuation parameter of the step, in the unit of the scene's load
        (for example the end displacement [m] or the pulling force [N]); it must be finite.
        """
        rec = self._stream()
        if int(step) != step or step < 0:
            raise ValueError(f"step must be a non-negative integer, got {step!r}")
        if load is not None and not math.isfinite(float(load)):
            raise ValueError(f"load must be finite, got {load!r}")
        rec.set_time(LOAD_STEP_TIMELINE, sequence=int(step))
        self._step = int(step)
        if load is not None:
            self._scalar_keys.add("load")
            rec.log(f"{PLOTS_ROOT}/load", rr.Scalars(float(load)))

    def log_rod(
        self,
        name: str,
        positions: np.ndarray,
        closed: bool,
        radii: np.ndarray | float,
        field: np.ndarray | None = None,
        field_name: str | None = None,
        limits: tuple[float, float] | None = None,
        *,
        field_at: FieldLocation | None = None,
        radii_at: FieldLocation | None = None,
        color: tuple[int, int, int] | None = None,
    ) -> None:
        """Log a rod as a tube: one ``LineStrips3D`` strip per edge, plus ``<name>/vertices``.

        Parameters
        ----------
        name:
            Entity path of the rod (for example ``"rod"``).
        positions:
            Centreline vertices, shape (N, 3) [m], N >= 2.
        closed:
            True for a closed rod (edge N-1 joins the last vertex to the first).
        radii:
            Deformed tube radius [m]: a scalar, per vertex (N,) or per edge (E,). Vertex values
            are averaged onto edges. Must be finite and positive.
        field:
            Scalar field colouring the tube, per vertex (N,) or per edge (E,), in the unit
            of ``field_name`` (all are dimensionless). NaN is drawn grey. None: plain colour.
        field_name:
            One of :data:`ROD_FIELDS`; required when ``field`` is given. Checked before
            anything is logged.
        limits:
            Colour limits ``(low, high)``; None = the field's default (fixed for
            ``contact_width_fraction``, else min and max of this step).
        field_at, radii_at:
            Force "vertex" or "edge"; only needed for a closed rod (N == E), where the default
            is the field's natural place (:data:`ROD_FIELDS`) and "edge" for radii.
        color:
            Uniform RGB colour (0..255) of a rod logged without a field (default
            :data:`ROD_PLAIN_RGB`; several rods: :data:`ROD_COLORS_RGB`).
        """
        if field_name is not None:
            _check_field_name(field_name)
        if field is not None and field_name is None:
            raise ValueError(
                f"field_name is required with a field; valid names: {', '.join(sorted(ROD_FIELDS))}"
            )
        entity = _check_name(name)
        p = _positions(positions, "positions", min_count=2)
        n = p.shape[0]
        r = to_edges(radii, n, closed, default_at="edge", at=radii_at, what="radii")
        if not np.all(np.isfinite(r)) or np.any(r <= 0.0):
            raise ValueError("radii must be finite and positive")
        if field is not None and field_name is not None:
            cmap, default_limits, natural_at = ROD_FIELDS[field_name]
            values = to_edges(field, n, closed, default_at=natural_at, at=field_at, what="field")
            colors = colorize(values, cmap, limits if limits is not None else default_limits)
        else:
            rgb = ROD_PLAIN_RGB if color is None else tuple(int(c) for c in color)
            if len(rgb) != 3 or not all(0 <= c <= 255 for c in rgb):
                raise ValueError(f"color must be three integers in [0, 255], got {color!r}")
            colors = np.broadcast_to(
                np.array(rgb + (255,), dtype=np.uint8), (r.shape[0], 4)
            )
        rec = self._temporal()
        rec.log(entity, rr.LineStrips3D(edge_segments(p, closed), radii=r, colors=colors))
        # Vertices as points, radius = local tube radius would hide the tube: draw them at a
        # third of the smallest radius, just enough to pick them in the viewer.
        rec.log(f"{entity}/vertices", rr.Points3D(p, radii=float(r.min()) / 3.0))

    def log_contacts(
        self,
        name: str,
        points_a: np.ndarray,
        points_b: np.ndarray,
        pressure_over_E: np.ndarray,
        limits: tuple[float, float] | None = None,
        radius: float | None = None,
    ) -> None:
        """Log contact pairs as segments a-b coloured by p/E, plus their midpoints.

        Parameters
        ----------
        name:
            Entity path (for example ``"contacts"``); midpoints go to ``<name>/midpoints``.
        points_a, points_b:
            The two centreline points of each contact pair, shape (M, 3) [m]; M = 0 is valid
            and clears the contacts shown at this step.
        pressure_over_E:
            Contact pressure over Young's modulus p/E [1], shape (M,); NaN drawn grey.
        limits:
            Colour limits of p/E; None = min and max of this step.
        radius:
            Drawn segment radius [m]; None = the viewer's default line width.
        """
        entity = _check_name(name)
        a = _positions(points_a, "points_a")
        b = _positions(points_b, "points_b")
        pe = np.asarray(pressure_over_E, dtype=np.float64)
        if a.shape != b.shape or pe.shape != (a.shape[0],):
            raise ValueError(
                f"points_a {a.shape}, points_b {b.shape} and pressure_over_E {pe.shape} "
                "must be (M, 3), (M, 3) and (M,)"
            )
        if radius is not None and not (math.isfinite(radius) and radius > 0.0):
            raise ValueError(f"radius must be finite and positive, got {radius!r}")
        colors = colorize(pe, CONTACT_CMAP, limits)
        rec = self._temporal()
        # An empty batch is logged on purpose: it replaces the previous step's contacts, which
        # a latest-at query (the viewer) would otherwise keep showing.
        rec.log(
            entity,
            rr.LineStrips3D(np.stack([a, b], axis=1), colors=colors, radii=radius),
        )
        rec.log(f"{entity}/midpoints", rr.Points3D(0.5 * (a + b), colors=colors, radii=radius))

    def log_scalars(self, mapping: Mapping[str, float]) -> None:
        """Log scalar series ``plots/<key>`` at the current step.

        Keys are free-form entity paths (see :data:`STANDARD_SCALARS` for the usual ones and
        their units); "a/b" keys share a plot "a". Every value must be finite: the whole
        mapping is refused (ValueError, nothing logged) if one is not, so a NaN never reaches
        a plot or a later analysis.
        """
        items: list[tuple[str, float]] = []
        for key, value in mapping.items():
            clean = str(key).strip("/")
            if not clean:
                raise ValueError("scalar keys must not be empty")
            v = float(value)
            if not math.isfinite(v):
                raise ValueError(f"scalar {key!r} is not finite ({value!r}); refusing to log it")
            items.append((clean, v))
        rec = self._temporal()
        for key, v in items:
            self._scalar_keys.add(key)
            rec.log(f"{PLOTS_ROOT}/{key}", rr.Scalars(v))

    def log_reference(
        self, name: str, positions: np.ndarray, radius: float, closed: bool = True
    ) -> None:
        """Log an ideal (reference) knot, static: a thin grey centreline plus its vertices.

        ``positions`` (N, 3) [m] is the reference centreline; ``radius`` [m] its tube radius
        (D0/2 for an ideal knot of diameter D0); the line is drawn at
        :data:`REFERENCE_LINE_FRACTION` of it so the elastic rod around it stays visible.
        Static: shown at every step, independent of :meth:`set_step`.
        """
        entity = _check_name(name)
        p = _positions(positions, "positions", min_count=2)
        if not (math.isfinite(radius) and radius > 0.0):
            raise ValueError(f"radius must be finite and positive, got {radius!r}")
        line = np.vstack([p, p[:1]]) if closed else p
        thin = REFERENCE_LINE_FRACTION * float(radius)
        rec = self._stream()
        rec.log(entity, rr.LineStrips3D([line], radii=thin, colors=[REFERENCE_RGB]), static=True)
        rec.log(
            f"{entity}/vertices",
            rr.Points3D(p, radii=thin, colors=[REFERENCE_RGB]),
            static=True,
        )

    # -- end ----------------------------------------------------------------------------------

    def close(self) -> None:
        """Send the blueprint, finish the file and rename it onto ``path``. Idempotent."""
        if self._rec is None:
            return
        rec = self._rec
        try:
            rec.send_blueprint(default_blueprint(plot_groups(self._scalar_keys)))
            rec.flush()
            # disconnect() closes the file sink and writes the footer (manifest).
            rec.disconnect()
            assert self._tmp is not None
            with open(self._tmp, "rb") as handle:
                os.fsync(handle.fileno())
            os.replace(self._tmp, self.path)
            self._tmp = None
        except BaseException:
            self._discard()
            raise
        self._rec = None

    def abort(self) -> None:
        """Stop logging and delete the temporary file; ``path`` is left untouched. Idempotent."""
        self._discard()

    def _discard(self) -> None:
        rec, self._rec = getattr(self, "_rec", None), None
        if rec is not None:
            with contextlib.suppress(Exception):
                rec.disconnect()
        tmp, self._tmp = getattr(self, "_tmp", None), None
        if tmp is not None:
            with contextlib.suppress(FileNotFoundError):
                tmp.unlink()

    def __enter__(self) -> RerunLogger:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()

    def __del__(self) -> None:
        # Dropped without close(): the run did not finish, so never commit; clean up instead.
        with contextlib.suppress(Exception):
            self._discard()


class NullLogger:
    """Same methods as :class:`RerunLogger`, doing nothing (no checks, no file, no cost)."""

    def set_step(self, step: int, load: float | None = None) -> None:
        """Do nothing."""

    def log_rod(
        self,
        name: str,
        positions: np.ndarray,
        closed: bool,
        radii: np.ndarray | float,
        field: np.ndarray | None = None,
        field_name: str | None = None,
        limits: tuple[float, float] | None = None,
        *,
        field_at: FieldLocation | None = None,
        radii_at: FieldLocation | None = None,
        color: tuple[int, int, int] | None = None,
    ) -> None:
        """Do nothing."""

    def log_contacts(
        self,
        name: str,
        points_a: np.ndarray,
        points_b: np.ndarray,
        pressure_over_E: np.ndarray,
        limits: tuple[float, float] | None = None,
        radius: float | None = None,
    ) -> None:
        """Do nothing."""

    def log_scalars(self, mapping: Mapping[str, float]) -> None:
        """Do nothing."""

    def log_reference(
        self, name: str, positions: np.ndarray, radius: float, closed: bool = True
    ) -> None:
        """Do nothing."""

    def close(self) -> None:
        """Do nothing."""

    def abort(self) -> None:
        """Do nothing."""

    def __enter__(self) -> NullLogger:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        return None


def make_logger(
    path: str | os.PathLike[str] | None, application_id: str = "tightknot"
) -> RerunLogger | NullLogger:
    """A :class:`RerunLogger` writing ``path``, or a :class:`NullLogger` when ``path`` is None."""
    if path is None:
        return NullLogger()
    return RerunLogger(path, application_id)
