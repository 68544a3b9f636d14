"""Shared FEM results: each scene is solved once per test session (they cost seconds)."""

import pytest


@pytest.fixture(scope="session")
def squeeze_plane_strain_convergence():
    """Plane-strain squeeze, coarse mesh plus the three-mesh table (about 10 s)."""
    pytest.importorskip("felupe")
    from tightknot.fem import run_scene

    return run_scene("squeeze", mesh="coarse", model="plane_strain", convergence=True)


@pytest.fixture(scope="session")
def indent_coarse():
    """Indent on the coarse mesh (1080 hexahedra, about 15 s on 2 cores)."""
    pytest.importorskip("felupe")
    from tightknot.fem import run_scene

    return run_scene("indent", mesh="coarse", convergence=False)


@pytest.fixture(scope="session")
def wrap_coarse():
    """Wrap on the coarse mesh (960 hexahedra, 6 tension levels, 30 to 40 s on 2 cores)."""
    pytest.importorskip("felupe")
    from tightknot.fem import run_scene

    return run_scene("wrap", mesh="coarse", convergence=False)


@pytest.fixture(scope="session")
def soft_squeeze_coarse():
    """Two soft rods pressed together (barrier contact), coarse, 4 levels, with the
    rigid-plane squeeze on the same mesh (about 4 s on 2 cores)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return run_scene("soft_squeeze", mesh="coarse")


@pytest.fixture(scope="session")
def soft_crossing_coarse():
    """Two soft rods crossing at 90 degrees, coarse, 4 levels, with the rigid indent
    (about 500 s on 2 shared cores: slow tests only)."""
    pytest.importorskip("felupe")
    pytest.importorskip("ipctk")
    from tightknot.fem import run_scene

    return run_scene("soft_crossing", mesh="coarse")
