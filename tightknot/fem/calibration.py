"""Calibration of the radial-compliance contact law from the FEM scenes.

Output file ``tightknot/data/contact_law.json`` (flat keys; consumed by the rod contact
layer). All laws are PER SIDE, non-dimensional, with w_hat = w / D0 (see
:mod:`tightknot.fem.overlap` for w and delta), valid for w_hat in [w_hat_min, w_hat_max]:

====================  =====================================================  ==============
keys                  law                                                    source scene
====================  =====================================================  ==============
k_line, p_line        f / (E D0) = k_line w_hat^p_line  (f: force/length)    squeeze 2D+3D
k_width, p_width      b / D0 = k_width w_hat^p_width  (b: half-width)        squeeze 2D
c_lc, p_lc            L_c,side = c_lc w_hat^p_lc  (contact fraction of the   squeeze 2D
                      deformed perimeter on one side)
k_pmax_line,          p_max / E = k_pmax_line w_hat^p_pmax_line              squeeze 2D
p_pmax_line
k_point, p_point      F / (E D0^2) = k_point w_hat^p_point  (F: force)       indent
k_patch_axial, ...    a_axial / D0 = k_patch_axial w_hat^p_patch_axial        indent
k_patch_transverse,   a_transverse / D0 = k_patch_transverse w_hat^...       indent
k_pmax_point, ...     p_max / E = k_pmax_point w_hat^p_pmax_point            indent
k_area, p_area        A / A0 = (1 / stretch) (1 - k_area w_hat^p_area)       squeeze 3D free
====================  =====================================================  ==============

``fits_w_hat_ge_0p01`` holds the same laws fitted over w_hat in [0.01, 0.15] only (a
single power law cannot follow the logarithmic small-load line contact, Johnson 1985
sec. 5.6, and the coarse meshes do not resolve patches below w_hat = 0.01), with their
own max relative errors. ``residuals`` holds, per law, the maximum relative error of
the fit over the fitted FEM points; ``hertz`` the small-strain (Hertz) values of the
same laws for comparison; ``provenance`` the scenes, meshes, FElupe version, date,
bulk modulus and definitions. Fits are least squares in log-log space
(scipy.optimize.curve_fit on log y = log k + p log w_hat).
"""

from __future__ import annotations

import datetime as _dt
import math
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import OptimizeWarning, curve_fit

from . import hertz
from ._backend import felupe_version
from .material import BULK_MODULUS, BULK_RATIO, ROD_DIAMETER, YOUNGS_MODULUS, poisson_ratio
from .overlap import __doc__ as _OVERLAP_DOC
from .scenes import indent, squeeze
from .scenes._common import MESH_LEVELS, finite

LAW_PATH = Path(__file__).resolve().parents[1] / "data" / "contact_law.json"
"""Default location of the shipped law."""

W_HAT_MAX: float = 0.15
"""Upper end of the calibrated range of w_hat (total approach 0.3 D0)."""

W_HAT_RESTRICTED: float = 0.01
"""Lower end of the alternative fits ``fits_w_hat_ge_0p01`` (smaller residuals)."""

SCHEMA = "tightknot.contact_law/1"

DEFINITIONS = {
    "delta": "pair overlap delta = r_i + r_j - d [m]: d the distance between the two "
             "centerline points, r the (deformed) section radii",
    "w": "per-side approach [m]: reduction of the distance from the section centroid to "
         "the contact plane on one side; plates squeezing a rod by a total diameter "
         "reduction Delta give w = Delta/2; two identical rods: w_i = w_j = delta/2; "
         "different rods: f_side_i(w_i) = f_side_j(w_j), w_i + w_j = delta",
    "w_hat": "w / D0",
    "line": "parallel strands (squeeze): f = force per unit length on one side [N/m]",
    "point": "crossing strands at 90 degrees (indent, rigid crossing cylinder of "
             "diameter D0): F = force on one side [N]",
    "half_width": "b: half-width of the line contact [m] at the mid cross-section",
    "contact_fraction": "L_c,side: contact length on one side over the deformed perimeter",
    "patch": "a: semi-axes of the point-contact patch along the rod axis (axial) and "
             "across it (transverse) [m]",
    "area": "A/A0: area of the mid cross-section, deformed over rest; stretch is the "
            "rod's axial stretch from tension (1 in the calibration scene)",
}


def power_fit(w_hat: np.ndarray, y: np.ndarray) -> dict[str, float]:
    """Fit y = k w_hat^p in log-log space; return k, p and the max relative error [-]."""
    w_hat, y = np.asarray(w_hat, float), np.asarray(y, float)
    keep = (w_hat > 0) & (y > 0)
    if keep.sum() < 2:
        raise ValueError("need at least two positive points to fit a power law")
    lx, ly = np.log(w_hat[keep]), np.log(y[keep])
    with warnings.catch_warnings():
        # the covariance is not used; two points or exact data leave it undefined
        warnings.simplefilter("ignore", OptimizeWarning)
        (logk, p), _ = curve_fit(lambda x, a, b: a + b * x, lx, ly, p0=(0.0, 1.0))
    pred = np.exp(logk + p * lx)
    err = np.max(np.abs(pred / y[keep] - 1.0))
    return {"k": float(math.exp(logk)), "p": float(p), "max_rel_error": float(err),
            "points": int(keep.sum())}


def hertz_defaults(w_hat_max: float = W_HAT_MAX, w_hat_min: float = 1e-3) -> dict[str, float]:
    """Small-strain (Hertz) values of the laws, for comparison (rigid counter-body).

    Point contact (sphere of radius R = D0/2 on a flat, E* = E/(1-nu^2) = 4E/3 at
    nu = 1/2): F/(E D0^2) = (4/3)(E*/E) (1/2)^(1/2) w_hat^(3/2) (Johnson 1985 eq. 4.23),
    a/D0 = (w_hat/2)^(1/2) (eq. 4.22), p0/E = (2/pi)(E*/E)(2 w_hat)^(1/2) (eq. 4.21).
    Line contact: the plane-strain relation of Johnson (1985) sec. 5.6 is not a power
    law (logarithmic); its log-log fit over [w_hat_min, w_hat_max] is given.
    """
    nu = 0.5
    es = 1.0 / (1.0 - nu**2)  # E*/E
    out = {
        "k_point": 4.0 / 3.0 * es * math.sqrt(0.5), "p_point": 1.5,
        "k_patch": math.sqrt(0.5), "p_patch": 0.5,
        "k_pmax_point": 2.0 / math.pi * es * math.sqrt(2.0), "p_pmax_point": 0.5,
    }
    w = np.geomspace(w_hat_min, w_hat_max, 40)
    radius = 0.5  # D0 = 1, E = 1
    f = np.array([hertz.line_force_per_length(x, radius, 1.0, nu) for x in w])
    b = np.array([hertz.line_half_width(x, radius, es) for x in f])
    p0 = 2.0 * f / (math.pi * b)
    for name, y in (("line", f), ("width", b), ("pmax_line", p0)):
        fit = power_fit(w, y)
        out[f"k_{name}"], out[f"p_{name}"] = fit["k"], fit["p"]
    return out


def _steps(result: dict[str, Any], key: str) -> tuple[np.ndarray, np.ndarray]:
    rows = [s for s in result["steps"] if s["w_over_d0"] <= W_HAT_MAX + 1e-12]
    return (np.array([s["w_over_d0"] for s in rows]),
            np.array([s[key] if s[key] is not None else np.nan for s in rows]))


def calibrate(mesh: str = "medium", steps: int = 12) -> dict[str, Any]:
    """Run the calibration scenes on ``mesh`` and fit the per-side laws.

    Returns the JSON-serialisable law (see the module docstring for the keys).
    """
    if mesh not in MESH_LEVELS:
        raise ValueError(f"mesh must be one of {MESH_LEVELS}, got {mesh!r}")
    start = time.perf_counter()
    common = dict(mesh=mesh, max_approach_over_d0=2.0 * W_HAT_MAX, steps=steps,
                  convergence=False)
    plane = squeeze.run(model="plane_strain", **common)
    plane3d = squeeze.run(model="3d", ends="plane", **common)
    free3d = squeeze.run(model="3d", ends="free", **common)
    point = indent.run(**common)

    law: dict[str, Any] = {"schema": SCHEMA}
    residuals: dict[str, float] = {}

    restricted: dict[str, dict[str, float]] = {}

    def put(name: str, k_key: str, p_key: str, w: np.ndarray, y: np.ndarray) -> None:
        fit = power_fit(w, y)
        law[k_key], law[p_key] = fit["k"], fit["p"]
        residuals[name] = fit["max_rel_error"]
        # the same law fitted only where the contact spans several elements and the
        # logarithmic small-load regime of line contact is left out (w_hat >= 0.01)
        keep = w >= W_HAT_RESTRICTED
        restricted[name] = dict(power_fit(w[keep], y[keep]), k_key=k_key, p_key=p_key)

    w2, f2 = _steps(plane, "force_per_length_over_e_d0")
    w3, f3 = _steps(plane3d, "force_per_length_over_e_d0")
    put("line", "k_line", "p_line", np.concatenate([w2, w3]), np.concatenate([f2, f3]))
    put("width", "k_width", "p_width", *_steps(plane, "half_width_over_d0"))
    put("contact_fraction", "c_lc", "p_lc", *_steps(plane, "contact_fraction_side"))
    put("pmax_line", "k_pmax_line", "p_pmax_line", *_steps(plane, "peak_pressure_mid_over_e"))
    put("point", "k_point", "p_point", *_steps(point, "force_over_e_d0sq"))
    put("patch_axial", "k_patch_axial", "p_patch_axial",
        *_steps(point, "semi_axis_axial_over_d0"))
    put("patch_transverse", "k_patch_transverse", "p_patch_transverse",
        *_steps(point, "semi_axis_transverse_over_d0"))
    put("pmax_point", "k_pmax_point", "p_pmax_point", *_steps(point, "peak_pressure_over_e"))
    wa, area = _steps(free3d, "area_ratio")
    put("area", "k_area", "p_area", wa, 1.0 - area)

    law["w_hat_min"] = float(min(w2.min(), point["steps"][0]["w_over_d0"]))
    law["w_hat_max"] = W_HAT_MAX
    law["residuals"] = residuals
    law["fits_w_hat_ge_0p01"] = restricted
    law["line_plane_strain_vs_3d_max_rel_diff"] = float(np.max(np.abs(f3 / f2 - 1.0)))
    law["hertz"] = hertz_defaults()
    law["provenance"] = {
        "scenes": {
            "line": "squeeze plane strain + squeeze 3d plane ends (u_z = 0 on end faces)",
            "width, contact_fraction, pmax_line": "squeeze plane strain",
            "point, patch, pmax_point": f"indent (rigid crossing cylinders of diameter D0, "
                                        f"segment {point['parameters']['segment_length_m']} m)",
            "area": f"squeeze 3d free ends, segment length "
                    f"{free3d['parameters']['segment_length_m']} m = 2 D0, stretch = 1",
        },
        "meshes": {
            "level": mesh,
            "squeeze_plane_strain_quads": plane["mesh"]["elements"],
            "squeeze_3d_plane_ends_hexahedra": plane3d["mesh"]["elements"],
            "squeeze_3d_free_ends_hexahedra": free3d["mesh"]["elements"],
            "indent_hexahedra": point["mesh"]["elements"],
        },
        "fem": "FElupe SolidBodyNearlyIncompressible (u, p, J-bar mixed, Q1/P0) with an "
               "isochoric neo-Hookean material; frictionless smoothed penalty contact with "
               "rigid bodies (tightknot.fem.contact)",
        "felupe_version": felupe_version(),
        "date": _dt.date.today().isoformat(),
        "youngs_modulus_pa": YOUNGS_MODULUS,
        "diameter_m": ROD_DIAMETER,
        "bulk_modulus_pa": BULK_MODULUS,
        "bulk_over_shear": BULK_RATIO,
        "poisson_ratio_small_strain": poisson_ratio(),
        "load_steps": steps,
        "fit": "least squares of log y = log k + p log w_hat over all load steps",
        "wall_time_s": time.perf_counter() - start,
    }
    law["definitions"] = dict(DEFINITIONS, overlap_module=" ".join(
        (_OVERLAP_DOC or "").split()))
    return finite(law)


#: The point law's keys of the shipped law and the soft crossing's step keys they fit.
POINT_KEYS: dict[str, tuple[str, str, str]] = {
    "point": ("k_point", "p_point", "force_over_e_d0sq"),
    "patch": ("k_patch", "p_patch", "semi_axis_axial_over_d0"),
    "pmax_point": ("k_pmax_point", "p_pmax_point", "peak_pressure_over_e"),
}


def soft_crossing_point_law(result: dict[str, Any]) -> dict[str, Any]:
    """The point law fitted to two soft rods crossing (a ``soft_crossing`` scene result,
    :mod:`tightknot.fem.scenes.soft_crossing`) instead of a rod against a rigid crossing
    cylinder (``indent``, the shipped law's source).

    Both scenes load each rod by the same per-rod approach w, so the fit reads as the
    shipped law's keys: F / (E D0^2) = k_point w_hat^p_point per rod, the patch's axial
    semi-axis and the peak pressure likewise (the pair's overlap 2 w split evenly, as the
    kernels split it). Hertz puts the soft pair sqrt(2) above the rigid indenter at equal w
    (E* halved over twice the approach, Johnson 1985 eqs. 4.22-4.23). Returns the keys with
    each fit's largest relative error (``residuals``) and the levels fitted."""
    steps = [s for s in result["steps"] if 0.0 < s["w_over_d0"] <= W_HAT_MAX + 1e-12]
    if len(steps) < 2:
        raise ValueError("soft_crossing_point_law: need two or more load steps with "
                         f"0 < w / D0 <= {W_HAT_MAX}, got {len(steps)}")
    w = np.array([s["w_over_d0"] for s in steps])
    out: dict[str, Any] = {"residuals": {}, "w_hat": w.tolist(),
                           "mesh": result.get("mesh", {}).get("level")}
    for name, (k_key, p_key, step_key) in POINT_KEYS.items():
        fit = power_fit(w, np.array([s[step_key] for s in steps]))
        out[k_key], out[p_key] = fit["k"], fit["p"]
        out["residuals"][name] = fit["max_rel_error"]
    return out


def with_point_law(law: Any, fit: dict[str, Any], source: str) -> Any:
    """``law`` (a :class:`~tightknot.contact.law.RadialComplianceLaw`) with its point law,
    patch and peak pressure taken from ``fit`` (:func:`soft_crossing_point_law`)."""
    from dataclasses import replace

    keys = {key: float(fit[key]) for k_key, p_key, _ in POINT_KEYS.values()
            for key in (k_key, p_key)}
    return replace(law, **keys, source=f"{law.source} with the point law of {source}")


def write_law(path: str | Path = LAW_PATH, mesh: str = "medium",
              law: dict[str, Any] | None = None) -> dict[str, Any]:
    """Calibrate (unless ``law`` is given) and write the law atomically as JSON to ``path``."""
    from tightknot.atomic import write_json_atomic

    if law is None:
        law = calibrate(mesh=mesh)
    write_json_atomic(path, law)
    return law


#: Deepest total approach over D0 of the core's squezes (plane strain): the medium mesh
#: converges to it; past it the incompressible elements lock.
CORE_APPROACH: float = 0.65
#: Per-side approach [w/D0] above which the core is fitted: where the power law starts to
#: fall short of the FEM and the barrier can start.
CORE_FIT_FROM: float = 0.05


def rod_line_force(w_hat: float, law: Any, core_fraction: float, hard_relative: float,
                   core_stiffness: float, edges_per_d0: int = 12) -> float:
    """Line force per length over E D0 [-] that the rod model's contact layer puts between
    two parallel straight rods of diameter D0 at per-side approach ``w_hat`` (centerline
    distance D0 (1 - 2 w_hat)): the law's kernels and the hard core as a knot sees them
    (Gauss quadrature on edges of D0/``edges_per_d0``), read off the middle third."""
    from tightknot.contact.layer import ContactLayer
    from tightknot.rods.builder import RodBuilder
    from tightknot.rods.material import Material

    d0, e = ROD_DIAMETER, YOUNGS_MODULUS
    length = 6.0 * d0
    n = 6 * edges_per_d0 + 1
    z = np.linspace(0.0, length, n)
    b = RodBuilder(twist=False)
    for x0 in (0.0, d0 * (1.0 - 2.0 * w_hat)):
        b.add_rod(np.c_[np.full(n, x0), np.zeros(n), z], d0, Material(e, 0.5, 1000.0))
    m = b.finalize()
    layer = ContactLayer(m, law, core_fraction=core_fraction, hard_relative=hard_relative,
                         core_stiffness=core_stiffness)
    _, g, _ = layer.evaluate(m.vertex_initial_position, m.edge_rest_length, True, False)
    mid = slice(n // 3, 2 * n // 3)
    per_length = float(np.abs(g[mid, 0]).sum()) / ((mid.stop - mid.start) * length / (n - 1))
    return per_length / (e * d0)


def calibrate_core(mesh: str = "medium", spread_mesh: str | None = "coarse",
                   approach: float = CORE_APPROACH) -> dict[str, Any]:
    """Fit the hard core of the shipped law to deep plane-strain squeezes.

    The power laws are fitted up to w/D0 = 0.15 (total approach 0.3); deeper, an
    incompressible section stiffens far more steeply (the force per length grows about
    thirteen-fold from w/D0 = 0.15 to 0.33 where the power law gives 2.7). The contact
    layer's hard core (a barrier in the centerline distance, zero above core_fraction R,
    diverging at hard_relative R) is fitted so that the rod model's line force (power-law
    kernel plus core, :func:`rod_line_force`) follows the FEM's from w/D0 =
    :data:`CORE_FIT_FROM` to the deepest level (least squares of the log force over the
    three parameters). Returns the parameters, the fit's relative errors per level, and the
    same comparison against ``spread_mesh`` (the FEM's own mesh spread)."""
    from scipy.optimize import least_squares

    from tightknot.contact.law import RadialComplianceLaw

    start = time.perf_counter()
    base = RadialComplianceLaw.from_json()
    runs = {m: squeeze.run(mesh=m, model="plane_strain", max_approach_over_d0=approach,
                           convergence=False) for m in {mesh, spread_mesh} - {None}}
    def deep(result: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
        rows = result["steps"]
        return (np.array([s["w_over_d0"] for s in rows]),
                np.array([s["force_per_length_over_e_d0"] for s in rows]))

    w, f = deep(runs[mesh])
    sel = w >= CORE_FIT_FROM

    def residual(p: np.ndarray) -> list[float]:
        c, h, k = p[0], p[1] * p[0], math.exp(p[2])
        return [math.log(rod_line_force(wi, base, c, h, k)) - math.log(fi)
                for wi, fi in zip(w[sel], f[sel], strict=True)]

    # Start from a barrier near the end of the power laws' range; h is fitted as a
    # fraction of c, so that 0 <= h < c holds by the bounds.
    sol = least_squares(residual, [0.8, 0.3, 0.0], bounds=([0.62, 0.0, -8.0],
                                                           [0.95, 0.9, 8.0]))
    c, h, k = float(sol.x[0]), float(sol.x[1] * sol.x[0]), float(math.exp(sol.x[2]))
    rows = [{"w_hat": float(wi), "fem": float(fi),
             "rod": rod_line_force(float(wi), base, c, h, k),
             "power_law_alone": base.k_line * float(wi) ** base.p_line}
            for wi, fi in zip(w, f, strict=True)]
    for r in rows:
        r["rod_rel"] = r["rod"] / r["fem"] - 1.0
    spread = None
    if spread_mesh is not None and spread_mesh != mesh:
        ws, fs = deep(runs[spread_mesh])
        spread = [{"w_hat": float(a), "rel_to_" + mesh: float(b / np.interp(a, w, f) - 1.0)}
                  for a, b in zip(ws, fs, strict=True) if a <= w.max()]
    fitted = [r["rod_rel"] for r in rows if r["w_hat"] >= CORE_FIT_FROM]
    return finite({
        "core_fraction": c, "core_hard_relative": h, "core_stiffness": k,
        "calibrated_w_hat": float(w.max()),
        "core_fit": {
            "what": "hard core of the contact layer fitted with the power laws to deep "
                    "plane-strain squeezes (tightknot.fem.calibration.calibrate_core)",
            "mesh": mesh, "approach_over_d0": approach, "fit_from_w_hat": CORE_FIT_FROM,
            "max_rel_error": float(np.max(np.abs(fitted))), "levels": rows,
            "mesh_spread": spread, "felupe_version": felupe_version(),
            "date": _dt.date.today().isoformat(),
            "wall_time_s": time.perf_counter() - start,
        },
    })


def write_core(path: str | Path = LAW_PATH, mesh: str = "medium") -> dict[str, Any]:
    """Fit the core (:func:`calibrate_core`) and add it to the law file at ``path``
    (atomically; the power laws are kept)."""
    import json

    from tightknot.atomic import write_json_atomic

    law = json.loads(Path(path).read_text())
    core = calibrate_core(mesh=mesh)
    law.update(core)
    write_json_atomic(path, law)
    return core
