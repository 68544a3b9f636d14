"""Shared FEM results: each scene is solved once per test run (they cost seconds to
minutes), also under pytest-xdist, where session fixtures are per worker."""

import os
import pickle
from collections.abc import Callable
from typing import Any

import pytest

try:
    import fcntl
except ImportError:  # not POSIX: each worker solves its own
    fcntl = None


@pytest.fixture(scope="session")
def once_per_run(tmp_path_factory: pytest.TempPathFactory) -> Callable[[str, Callable], Any]:
    """``once_per_run(name, compute)``: ``compute()``, solved by the first xdist worker that
    needs it and read by the others from the run's shared temporary folder (pytest-xdist's
    pattern for session fixtures, "Making session-scoped fixtures execute only once", with
    a POSIX file lock): several test files share the long scenes, and the two workers
    solved each of them twice."""
    if fcntl is None or not os.environ.get("PYTEST_XDIST_WORKER"):
        return lambda name, compute: compute()
    root = tmp_path_factory.getbasetemp().parent  # one folder per run, shared by workers

    def cached(name: str, compute: Callable[[], Any]) -> Any:
        path = root / f"fem-{name}.pickle"
        with open(root / f"fem-{name}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # a second worker waits for the first's result
            try:
                if path.is_file():
                    return pickle.loads(path.read_bytes())
                value = compute()
                part = path.with_suffix(".part")
                part.write_bytes(pickle.dumps(value))
                part.replace(path)  # whole or absent: never a half-written result
                return value
            finally:
                fcntl.flock(lock, fcntl.LOCK_UN)

    return cached


@pytest.fixture(scope="session")
def squeeze_plane_strain_convergence(once_per_run):
    """Plane-strain squeeze, coarse mesh plus the three-mesh table (about 13 s)."""
    pytest.importorskip("felupe")
    from tightknot.fem import run_scene

    return once_per_run("squeeze_plane_strain_convergence", lambda: run_scene(
        "squeeze", mesh="coarse", model="plane_strain", convergence=True))


@pytest.fixture(scope="session")
def indent_coarse(once_per_run):
    """Indent on the coarse mesh (1080 hexahedra, about 10 s)."""
    pytest.importorskip("felupe")
    from tightknot.fem import run_scene

    return once_per_run("indent_coarse",
                        lambda: run_scene("indent", mesh="coarse", convergence=False))


@pytest.fixture(scope="session")
def wrap_coarse(once_per_run):
    """Wrap on the coarse mesh (960 hexahedra, 6 tension levels, about 20 s)."""
    pytest.importorskip("felupe")
    from tightknot.fem import run_scene

    return once_per_run("wrap_coarse",
                        lambda: run_scene("wrap", mesh="coarse", convergence=False))


@pytest.fixture(scope="session")
def soft_squeeze_coarse(once_per_run):
    """Two soft rods pressed together (barrier contact), coarse, 4 levels, with the
    rigid-plane squeeze on the same mesh (about 4 s)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return once_per_run("soft_squeeze_coarse",
                        lambda: run_scene("soft_squeeze", mesh="coarse"))


@pytest.fixture(scope="session")
def soft_crossing_coarse(once_per_run):
    """Two soft rods crossing at 90 degrees, coarse, 4 levels, with the rigid indent
    (about 3 min: slow tests only)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return once_per_run("soft_crossing_coarse",
                        lambda: run_scene("soft_crossing", mesh="coarse"))


@pytest.fixture(scope="session")
def soft_wrap_one_level(once_per_run):
    """A soft rod pulled around a soft rod: one coarse level at T = 0.0069 E D0^2 (the
    wrap's first level), no rigid run (about 30 s)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return once_per_run("soft_wrap_one_level", lambda: run_scene(
        "soft_wrap", mesh="coarse", max_tension_over_e_d0sq=0.0069, steps=1, compare=False))


@pytest.fixture(scope="session")
def soft_crossing_one_level(once_per_run):
    """Two soft rods crossing: one coarse level at w = 0.0375 D0 per rod (the scene's
    second level), no rigid run (about 40 s)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return once_per_run("soft_crossing_one_level", lambda: run_scene(
        "soft_crossing", mesh="coarse", max_approach_over_d0=0.075, steps=1, compare=False))


@pytest.fixture(scope="session")
def clasp_one_level(once_per_run):
    """The clasp: relaxation in the clamps and one coarse level at a pull of 0.7 D0 (the
    FEM's bends touch from about 0.4 D0 on, the rod model's, clamped at the same points,
    from about 0.55 D0; about 85 s)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return once_per_run("clasp_one_level", lambda: run_scene(
        "clasp", mesh="coarse", max_pull_over_d0=0.7, steps=1))
