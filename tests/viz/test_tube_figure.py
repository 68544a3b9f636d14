"""The matplotlib tube picture: frames without twist, one band per edge, a PNG."""

import numpy as np
import pytest

from tightknot.viz.tube_figure import render_tube, transport_frames, tube_quads


def _helix(n: int = 50) -> np.ndarray:
    t = np.linspace(0.0, 4 * np.pi, n)
    return np.c_[np.cos(t), np.sin(t), 0.3 * t] * 0.01


def test_transport_frames_are_orthonormal_and_normal_to_the_curve() -> None:
    x = _helix()
    n, b = transport_frames(x, closed=False)
    t = np.cross(n, b)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
    assert np.allclose(np.einsum("ij,ij->i", n, b), 0.0, atol=1e-12)
    # Parallel transport: consecutive normals turn only as much as the tangent does, so
    # they stay close (here the tangent turns ~15 degrees per vertex; cos 15 = 0.966).
    assert np.all(np.einsum("ij,ij->i", n[1:], n[:-1]) > 0.96)
    assert np.allclose(np.linalg.norm(t, axis=1), 1.0)


@pytest.mark.parametrize("closed", [False, True])
def test_quads_sit_on_the_tube(closed: bool) -> None:
    s = np.linspace(0.0, 2 * np.pi, 40, endpoint=not closed)
    x = np.c_[np.cos(s), np.sin(s), 0 * s] * 0.02  # a ring of radius 2 cm
    r = np.full(40, 1e-3)
    q = tube_quads(x, r, closed, sides=8)
    assert q.shape == (40 if closed else 39, 8, 4, 3)
    # Every corner lies at the tube radius from the circle's centreline (to 1e-12 m: exact
    # geometry, only rounding). An open rod's end rings are normal to the end chord, not to
    # the circle, so its first and last bands are left out.
    q = q if closed else q[1:-1]
    rho = np.hypot(q[..., 0], q[..., 1])
    assert np.allclose(np.hypot(rho - 0.02, q[..., 2]), 1e-3, rtol=0, atol=1e-12)


def test_render_writes_a_png_and_refuses_unknown_fields(tmp_path) -> None:
    x = _helix()
    kappa = np.linspace(0.2, 1.5, len(x))
    out = render_tube(tmp_path / "t.png", x, 1e-3, False, kappa, "kappa_D0", "helix")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="unknown field 'curvature'"):
        render_tube(tmp_path / "u.png", x, 1e-3, False, kappa, "curvature")
    assert not (tmp_path / "u.png").exists()
