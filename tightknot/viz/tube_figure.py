"""A still picture of a rod as a shaded 3D tube coloured by a field (matplotlib, PNG).

The same colours as the rerun log (:mod:`tightknot.viz.colormap`, per edge), for figures and
the README. Only drawing: the caller passes the centerline [m], the tube radii [m] and the
field. Rings of ``sides`` points around each vertex, framed by parallel transport (no
artificial twist); each edge is a band of quads with the edge's colour, shaded by a fixed
light so that the crossings of a knot read in a still image.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tightknot.viz.colormap import colorize
from tightknot.viz.rerun_log import ROD_FIELDS, FieldLocation, edge_count, to_edges

#: Light direction of the shading (from the viewer's upper left).
_LIGHT = np.array([-0.4, -0.5, 0.77])


def _tangents(x: np.ndarray, closed: bool) -> np.ndarray:
    nxt = np.roll(x, -1, axis=0) if closed else np.vstack([x[1:], 2 * x[-1] - x[-2]])
    prv = np.roll(x, 1, axis=0) if closed else np.vstack([2 * x[0] - x[1], x[:-1]])
    t = nxt - prv
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def transport_frames(x: np.ndarray, closed: bool) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals and binormals (N, 3) along ``x``, parallel-transported from vertex 0."""
    t = _tangents(x, closed)
    seed = np.eye(3)[int(np.argmin(np.abs(t[0])))]
    n = np.empty_like(x)
    n[0] = np.cross(t[0], seed)
    n[0] /= np.linalg.norm(n[0])
    for i in range(1, len(x)):
        # Remove the new tangent's component: the smallest rotation carrying the frame on.
        v = n[i - 1] - (n[i - 1] @ t[i]) * t[i]
        n[i] = v / np.linalg.norm(v)
    return n, np.cross(t, n)


def tube_quads(x: np.ndarray, radii_v: np.ndarray, closed: bool,
               sides: int = 16) -> np.ndarray:
    """Quads (E, sides, 4, 3) [m] of the tube around centerline ``x`` with vertex radii."""
    n, b = transport_frames(x, closed)
    phi = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    ring = (x[:, None, :] + radii_v[:, None, None]
            * (np.cos(phi)[None, :, None] * n[:, None, :]
               + np.sin(phi)[None, :, None] * b[:, None, :]))
    a = ring if closed else ring[:-1]
    c = np.roll(ring, -1, axis=0) if closed else ring[1:]
    if closed:
        # The transported frame comes back rotated after one turn (the curve's writhe and
        # torsion): match the last ring to the first by the nearest rotation of its points.
        shift = int(np.argmin([np.sum((np.roll(ring[-1], -k, axis=0) - ring[0] + x[-1] - x[0])
                                      ** 2) for k in range(sides)]))
        c = c.copy()
        c[-1] = np.roll(ring[0], shift, axis=0)
    a1 = np.roll(a, -1, axis=1)
    c1 = np.roll(c, -1, axis=1)
    return np.stack([a, a1, c1, c], axis=2)


def render_tube(path: str | Path, x: np.ndarray, radii: np.ndarray | float, closed: bool,
                field: np.ndarray, field_name: str, title: str = "",
                limits: tuple[float, float] | None = None, *,
                field_at: FieldLocation | None = None, sides: int = 16,
                view: tuple[float, float] = (60.0, -60.0), dpi: int = 130) -> Path:
    """Draw the tube of centerline ``x`` (N, 3) [m] with ``radii`` [m] (scalar or per vertex)
    coloured by ``field`` (per vertex or per edge; a name of
    :data:`tightknot.viz.rerun_log.ROD_FIELDS`) and save it as a PNG at ``path``.
    ``view``: camera elevation and azimuth [degrees]."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import cm, colors
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    if field_name not in ROD_FIELDS:
        raise ValueError(f"unknown field {field_name!r}; valid: {', '.join(ROD_FIELDS)}")
    p = np.asarray(x, dtype=np.float64)
    nv = p.shape[0]
    r_v = np.broadcast_to(np.asarray(radii, dtype=np.float64), (nv,)).copy()
    cmap, default_limits, natural_at = ROD_FIELDS[field_name]
    values = to_edges(field, nv, closed, default_at=natural_at, at=field_at, what="field")
    lims = limits if limits is not None else default_limits
    if lims is None:
        finite = values[np.isfinite(values)]
        lims = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    rgba = colorize(values, cmap, lims).astype(np.float64) / 255.0
    quads = tube_quads(p, r_v, closed, sides)
    # Lambert shading per quad (normal from the quad's diagonals), with an ambient floor.
    nq = np.cross(quads[:, :, 2] - quads[:, :, 0], quads[:, :, 3] - quads[:, :, 1])
    nq /= np.maximum(np.linalg.norm(nq, axis=-1, keepdims=True), 1e-300)
    shade = 0.45 + 0.55 * np.clip(nq @ (_LIGHT / np.linalg.norm(_LIGHT)), 0.0, 1.0)
    face = rgba[:, None, :3] * shade[..., None]
    face = np.concatenate([face, np.ones(face.shape[:2] + (1,))], axis=-1)
    assert quads.shape[0] == edge_count(nv, closed)

    fig = plt.figure(figsize=(6.0, 5.2))
    ax = fig.add_subplot(projection="3d")
    scale = 1e3  # mm on the axes: the study's unit
    # Edges in the face colour: hairline seams between the quads disappear.
    coll = Poly3DCollection((quads * scale).reshape(-1, 4, 3), facecolors=face.reshape(-1, 4),
                            edgecolors=face.reshape(-1, 4), linewidths=0.3)
    ax.add_collection3d(coll)
    lo = (p - r_v[:, None]).min(axis=0) * scale
    hi = (p + r_v[:, None]).max(axis=0) * scale
    for setter, a, b in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), lo, hi, strict=True):
        setter(a, b)
    # Equal scales on the three axes with a box fitted to the data (a cube would leave an
    # elongated knot small in an empty box); zoom fills the frame.
    ax.set_box_aspect(hi - lo, zoom=1.1)
    ax.set_proj_type("ortho")
    ax.view_init(elev=view[0], azim=view[1])
    ax.set_axis_off()
    sm = cm.ScalarMappable(norm=colors.Normalize(*lims), cmap=cmap)
    label = {"kappa_D0": r"curvature $\kappa D_0$", "area_ratio": r"section area $A/A_0$",
             "stretch": r"stretch $|e|/|e_0|$",
             "contact_width_fraction": r"contact width $L_c$"}[field_name]
    fig.colorbar(sm, ax=ax, shrink=0.6, pad=0.02, label=label)
    if title:
        ax.set_title(title, fontsize=10)
    out = Path(path)
    fig.savefig(out, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return out
