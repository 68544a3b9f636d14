"""Rerun logger: real .rrd files written to tmp_path and read back with rerun.chunk.RrdReader."""

from __future__ import annotations

import inspect
from pathlib import Path

import numpy as np
import pytest

from tightknot.viz import rrd_read
from tightknot.viz.rerun_log import (
    ROD_FIELDS,
    NullLogger,
    RerunLogger,
    edge_segments,
    make_logger,
    plot_groups,
    to_edges,
)

D0 = 8.5e-3  # rod diameter at rest [m] (the study's rods)
N = 60  # vertices of the test rod: small, the logger does not care
STEPS = 4

# Rerun stores positions and radii as float32. The read-back is exactly the input rounded to
# float32 (checked with array_equal), hence within half an ulp of the float64 input: relative
# error <= 2**-24 ~ 6e-8, i.e. ~3e-9 m on these 5 cm knots (checked with FLOAT32_RTOL).
FLOAT32_RTOL = 2.0**-24


def assert_float32_of(read: np.ndarray, given: np.ndarray) -> None:
    """``read`` (float32 from the .rrd) is ``given`` (float64) rounded to float32."""
    assert read.dtype == np.float32
    assert np.array_equal(read, given.astype(np.float32))
    # Relative rounding error bound of float32 (round to nearest); no atol needed: a 0.0
    # coordinate rounds to exactly 0.0.
    np.testing.assert_allclose(read, given, rtol=FLOAT32_RTOL, atol=0.0)


def trefoil(n: int = N, step: int = 0) -> np.ndarray:
    """A closed trefoil centreline, (n, 3) [m], about 5 cm across, slightly shifted per step."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    curve = np.c_[np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)]
    return 0.01 * curve + 1e-4 * step


def files_in(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def write_run(path: Path, steps: int = STEPS) -> list[np.ndarray]:
    """Log a small closed-knot run; return the rod positions of each step."""
    positions = []
    t = np.linspace(0.0, 1.0, N)
    with RerunLogger(path) as log:
        log.log_reference("ideal", trefoil(), radius=D0 / 2)
        for step in range(steps):
            p = trefoil(step=step)
            positions.append(p)
            log.set_step(step, load=0.1 * step)
            log.log_rod(
                "rod",
                p,
                closed=True,
                radii=np.full(N, D0 / 2),
                field=2.0 * t,  # varies along the rod: colours must vary too
                field_name="kappa_D0",
            )
            log.log_contacts("contacts", p[:5], p[10:15], np.linspace(0.0, 0.02, 5))
            log.log_scalars(
                {
                    "pulling_force": 0.5 * step,
                    "lambda_oc": 12.0,
                    "energy/bend": 1e-3,
                    "energy/contact": 2e-4,
                    "newton_iterations": 3,
                }
            )
    return positions


def test_entities_steps_positions_and_blueprint(tmp_path: Path) -> None:
    rrd = tmp_path / "run.rrd"
    positions = write_run(rrd)
    # Only the target remains: the temporary file was renamed onto it.
    assert files_in(tmp_path) == ["run.rrd"]

    paths = rrd_read.entity_paths(rrd)
    for entity in [
        "/rod",
        "/rod/vertices",
        "/contacts",
        "/contacts/midpoints",
        "/ideal",
        "/ideal/vertices",
        "/plots/load",
        "/plots/pulling_force",
        "/plots/lambda_oc",
        "/plots/energy/bend",
        "/plots/energy/contact",
        "/plots/newton_iterations",
    ]:
        assert entity in paths

    counts = rrd_read.row_counts(rrd)
    assert counts["/rod"] == STEPS
    assert counts["/rod/vertices"] == STEPS
    assert counts["/plots/pulling_force"] == STEPS
    assert rrd_read.steps(rrd, "rod", "LineStrips3D:strips") == list(range(STEPS))
    # The reference is static: on no timeline, shown at every step.
    assert "/ideal" not in counts
    assert rrd_read.static_entity_paths(rrd) == ["/ideal", "/ideal/vertices"]

    assert_float32_of(rrd_read.last_points3d(rrd, "rod/vertices"), positions[-1])
    assert_float32_of(rrd_read.last_points3d(rrd, "/rod/vertices", step=0), positions[0])

    steps, force = rrd_read.scalar_series(rrd, "plots/pulling_force")
    assert list(steps) == list(range(STEPS))
    # Scalars are stored as float64: exact.
    assert np.array_equal(force, 0.5 * np.arange(STEPS))

    # Default layout: the scene in 3D, one time-series view per plot group ("energy/*" share one).
    assert rrd_read.blueprint_views(rrd) == [
        ("3D", "/"),
        ("TimeSeries", "/plots/energy"),
        ("TimeSeries", "/plots/lambda_oc"),
        ("TimeSeries", "/plots/load"),
        ("TimeSeries", "/plots/newton_iterations"),
        ("TimeSeries", "/plots/pulling_force"),
    ]


def test_tube_is_one_strip_per_edge_with_varying_colours(tmp_path: Path) -> None:
    rrd = tmp_path / "tube.rrd"
    p = trefoil()
    radii_edges = np.linspace(0.9, 1.1, N - 1) * D0 / 2  # an open rod has N-1 edges
    with RerunLogger(rrd) as log:
        log.set_step(0)
        log.log_rod("rod", p, False, radii_edges, np.linspace(0.9, 1.2, N - 1), "stretch")
    strips = rrd_read.component_rows(rrd, "rod", "LineStrips3D:strips")[-1].value
    assert len(strips) == N - 1 and all(len(s) == 2 for s in strips)
    assert_float32_of(np.asarray(strips, dtype=np.float32), edge_segments(p, False))
    radii = rrd_read.component_rows(rrd, "rod", "LineStrips3D:radii")[-1].value
    assert_float32_of(np.asarray(radii, dtype=np.float32), radii_edges)
    colors = rrd_read.unpack_rgba(
        rrd_read.component_rows(rrd, "rod", "LineStrips3D:colors")[-1].value
    )
    assert colors.shape == (N - 1, 4)
    # A monotone field over ~60 edges spans the whole map: the ends differ, and most
    # neighbouring edges already get distinct colours.
    assert not np.array_equal(colors[0], colors[-1])
    assert len({tuple(c) for c in colors}) > (N - 1) // 2


def test_contacts_empty_batch_clears(tmp_path: Path) -> None:
    rrd = tmp_path / "contacts.rrd"
    p = trefoil()
    empty = np.zeros((0, 3))
    with RerunLogger(rrd) as log:
        log.set_step(0)
        log.log_contacts("contacts", p[:3], p[20:23], np.array([0.0, 0.01, 0.02]))
        log.set_step(1)
        log.log_contacts("contacts", empty, empty, np.zeros(0))
    rows = rrd_read.component_rows(rrd, "contacts", "LineStrips3D:strips")
    assert [r.step for r in rows] == [0, 1]
    assert len(rows[0].value) == 3 and rows[1].value == []
    mid = rrd_read.last_points3d(rrd, "contacts/midpoints", step=0)
    assert_float32_of(mid, 0.5 * (p[:3] + p[20:23]))
    assert rrd_read.last_points3d(rrd, "contacts/midpoints").shape == (0, 3)


def test_unknown_field_raises_before_anything_and_no_file(tmp_path: Path) -> None:
    rrd = tmp_path / "bad.rrd"
    with pytest.raises(ValueError, match="kappa_D0") as info:
        with RerunLogger(rrd) as log:
            log.set_step(0)
            log.log_rod("rod", trefoil(), True, D0 / 2, np.ones(N), "curvature")
    # The message lists every valid name.
    for name in ROD_FIELDS:
        assert name in str(info.value)
    assert files_in(tmp_path) == []


def test_unknown_field_is_checked_before_logging(tmp_path: Path) -> None:
    rrd = tmp_path / "partial.rrd"
    with RerunLogger(rrd) as log:
        log.set_step(0)
        with pytest.raises(ValueError):
            log.log_rod("rod", trefoil(), True, D0 / 2, np.ones(N), "nope")
        # Bad shapes too are refused before logging.
        with pytest.raises(ValueError):
            log.log_rod("rod", trefoil(), True, D0 / 2, np.ones(N + 3), "stretch")
    assert rrd_read.entity_paths(rrd) == []


def test_nan_scalar_refused_and_nothing_logged(tmp_path: Path) -> None:
    rrd = tmp_path / "nan.rrd"
    with RerunLogger(rrd) as log:
        log.set_step(0)
        with pytest.raises(ValueError, match="finite"):
            log.log_scalars({"pulling_force": 1.0, "energy/bend": float("nan")})
        with pytest.raises(ValueError, match="finite"):
            log.log_scalars({"pulling_force": float("inf")})
        with pytest.raises(ValueError, match="finite"):
            log.set_step(1, load=float("nan"))
        log.log_scalars({"lambda_oc": 12.4})
    # The mapping with a NaN is refused as a whole: its finite entry is not logged either.
    assert rrd_read.entity_paths(rrd) == ["/plots/lambda_oc"]


def test_exception_inside_context_leaves_no_partial_file(tmp_path: Path) -> None:
    rrd = tmp_path / "killed.rrd"
    with pytest.raises(RuntimeError, match="solver blew up"):
        with RerunLogger(rrd) as log:
            for step in range(3):
                log.set_step(step)
                log.log_rod("rod", trefoil(step=step), True, D0 / 2)
            log.log_scalars({"pulling_force": 1.0})
            raise RuntimeError("solver blew up")
    assert files_in(tmp_path) == []  # neither the target nor the temporary file


def test_failed_run_keeps_previous_file(tmp_path: Path) -> None:
    rrd = tmp_path / "run.rrd"
    write_run(rrd, steps=2)
    before = rrd.read_bytes()
    with pytest.raises(KeyboardInterrupt):
        with RerunLogger(rrd) as log:
            log.set_step(0)
            raise KeyboardInterrupt
    assert rrd.read_bytes() == before
    assert files_in(tmp_path) == ["run.rrd"]


def test_close_is_idempotent_and_logging_after_close_fails(tmp_path: Path) -> None:
    rrd = tmp_path / "twice.rrd"
    log = RerunLogger(rrd)
    log.set_step(0)
    log.log_scalars({"pulling_force": 1.0})
    log.close()
    log.close()
    log.abort()  # after a successful close, abort must not remove the committed file
    assert log.closed and rrd.exists()
    with pytest.raises(RuntimeError):
        log.set_step(1)


def test_temporal_data_needs_a_step(tmp_path: Path) -> None:
    with RerunLogger(tmp_path / "nostep.rrd") as log:
        with pytest.raises(RuntimeError, match="set_step"):
            log.log_scalars({"pulling_force": 1.0})


def test_two_loggers_coexist(tmp_path: Path) -> None:
    a, b = tmp_path / "a.rrd", tmp_path / "b.rrd"
    with RerunLogger(a) as log_a, RerunLogger(b) as log_b:
        for step in range(3):
            log_a.set_step(step)
            log_b.set_step(10 + step)
            log_a.log_scalars({"pulling_force": 1.0})
            log_b.log_rod("other", trefoil(), True, D0 / 2)
    assert rrd_read.entity_paths(a) == ["/plots/pulling_force"]
    assert rrd_read.entity_paths(b) == ["/other", "/other/vertices"]
    assert rrd_read.steps(b, "other", "LineStrips3D:strips") == [10, 11, 12]


def test_null_logger_writes_nothing(tmp_path: Path) -> None:
    log = make_logger(None)
    assert isinstance(log, NullLogger)
    with log:
        log.set_step(0, load=1.0)
        log.log_rod("rod", trefoil(), True, D0 / 2, np.ones(N), "kappa_D0")
        log.log_contacts("contacts", np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))
        log.log_scalars({"pulling_force": 1.0})
        log.log_reference("ideal", trefoil(), D0 / 2)
    assert files_in(tmp_path) == []
    assert isinstance(make_logger(tmp_path / "x.rrd"), RerunLogger)


def test_null_logger_has_the_same_methods() -> None:
    public = [m for m in dir(RerunLogger) if not m.startswith("_") and m != "closed"]
    for method in public:
        assert inspect.signature(getattr(NullLogger, method)) == inspect.signature(
            getattr(RerunLogger, method)
        ), method


def test_vertex_fields_are_averaged_onto_edges() -> None:
    v = np.array([0.0, 1.0, 3.0, 7.0])
    assert np.array_equal(to_edges(v, 4, closed=False, default_at="vertex"), [0.5, 2.0, 5.0])
    # Closed rod: N == E, the location decides; the last edge wraps to vertex 0.
    assert np.array_equal(to_edges(v, 4, True, default_at="vertex"), [0.5, 2.0, 5.0, 3.5])
    assert np.array_equal(to_edges(v, 4, True, default_at="edge"), v)
    assert np.array_equal(to_edges(v, 4, True, default_at="edge", at="vertex"), [0.5, 2, 5, 3.5])
    assert np.array_equal(to_edges(2.0, 4, False, default_at="edge"), [2.0, 2.0, 2.0])


def test_plot_groups() -> None:
    keys = {"energy/bend", "energy/twist", "pulling_force", "newton_residual"}
    assert plot_groups(keys) == ["energy", "newton_residual", "pulling_force"]


def test_missing_folder_fails_at_construction(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        RerunLogger(tmp_path / "nope" / "run.rrd")


def test_rerun_off_fails_clearly_at_construction(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # rerun reads RERUN when each stream is created, so this does not leak into other tests.
    monkeypatch.setenv("RERUN", "off")
    with pytest.raises(RuntimeError, match="RERUN=off"):
        RerunLogger(tmp_path / "off.rrd")
    assert files_in(tmp_path) == []
