"""Shared FEM results: each scene is solved once per test session (they cost seconds)."""

import pytest


@pytest.fixture(scope="session")
def squeeze_plane_strain_convergence():
    """Plane-strain squeeze, coarse mesh plus the three-mesh table (about 13 s)."""
    pytest.importorskip("felupe")
    from tightknot.fem import run_scene

    return run_scene("squeeze", mesh="coarse", model="plane_strain", convergence=True)


@pytest.fixture(scope="session")
def indent_coarse():
    """Indent on the coarse mesh (1080 hexahedra, about 10 s)."""
    pytest.importorskip("felupe")
    from tightknot.fem import run_scene

    return run_scene("indent", mesh="coarse", convergence=False)


@pytest.fixture(scope="session")
def wrap_coarse():
    """Wrap on the coarse mesh (960 hexahedra, 6 tension levels, about 20 s)."""
    pytest.importorskip("felupe")
    from tightknot.fem import run_scene

    return run_scene("wrap", mesh="coarse", convergence=False)


@pytest.fixture(scope="session")
def soft_squeeze_coarse():
    """Two soft rods pressed together (barrier contact), coarse, 4 levels, with the
    rigid-plane squeeze on the same mesh (about 4 s)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return run_scene("soft_squeeze", mesh="coarse")


@pytest.fixture(scope="session")
def soft_crossing_coarse():
    """Two soft rods crossing at 90 degrees, coarse, 4 levels, with the rigid indent
    (about 3 min: slow tests only)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return run_scene("soft_crossing", mesh="coarse")


@pytest.fixture(scope="session")
def soft_wrap_one_level():
    """A soft rod pulled around a soft rod: one coarse level at T = 0.0069 E D0^2 (the
    wrap's first level), no rigid run (about 30 s)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return run_scene("soft_wrap", mesh="coarse", max_tension_over_e_d0sq=0.0069, steps=1,
                     compare=False)


@pytest.fixture(scope="session")
def soft_crossing_one_level():
    """Two soft rods crossing: one coarse level at w = 0.0375 D0 per rod (the scene's
    second level), no rigid run (about 40 s)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return run_scene("soft_crossing", mesh="coarse", max_approach_over_d0=0.075, steps=1,
                     compare=False)


@pytest.fixture(scope="session")
def clasp_one_level():
    """The clasp: relaxation in the clamps and one coarse level at a pull of 0.7 D0 (the
    FEM's bends touch from about 0.4 D0 on, the rod model's, clamped at the same points,
    from about 0.55 D0; about 85 s)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return run_scene("clasp", mesh="coarse", max_pull_over_d0=0.7, steps=1)
