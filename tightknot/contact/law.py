"""The radial-compliance contact law: how hard two pieces of a deformable rod press.

Definitions (the FEM calibration's, ``tightknot/fem/overlap.py``): two centerline points at
distance d, section radii r_i, r_j (stretched sections), overlap ``delta = r_i + r_j - d``.
The law is calibrated per side: ``w`` is the approach of one section's centroid to the
contact plane; two identical rods pressed together have ``w = delta/2`` each.

Per-side laws (non-dimensional power laws fitted to the small 3D solid FEM; defaults
from the shipped ``tightknot/data/contact_law.json``):

* line contact of parallel strands, force per unit length
  ``f = k_line E D (w/D)^p_line`` [N/m];
* point contact of crossing strands, force per contact
  ``F = k_point E D^2 (w/D)^p_point`` [N].

For the pair (``w = delta/2``) the energies are the integrals of the force over delta:
``e_line(delta) = 2 k_line E D^2 (delta/2D)^(p+1)/(p+1)`` [J/m] and likewise
``e_point(delta) = 2 k_point E D^3 (delta/2D)^(q+1)/(q+1)`` [J].

Realisation on the rods (:mod:`tightknot.contact.pair_kernel`): the contact energy is a
double integral over both centerlines of a pair kernel psi(rho) of the distance rho between
two points, evaluated by Gauss quadrature on the edges, with R = r_i + r_j (stretched radii)
and delta = R - d. The kernels are the exact inverses of the laws, so that straight strands
reproduce them at every overlap:

* line: for two parallel straight strands at distance d, ``int psi(sqrt(d^2 + w^2)) dw =
  e_line(R - d)`` is an Abel transform, inverted by
  ``psi_l(rho) = (K m/pi) int_rho^R (R - t)^(m-1)/sqrt(t^2 - rho^2) dt
  = (K m/pi) R^(m-1) Phi_m(rho/R)`` (Bracewell 2000, Abel pair), Phi tabulated;
* point: two straight strands crossing at angle phi, ``int int psi dA / sin(phi) =
  (2 pi/sin phi) int_d^R psi(t) t dt``, so with a pair weight sin(phi)
  ``psi_p(rho) = K m (R - rho)^(m-1)/(2 pi rho)``.


The two are blended by crossing angle (Meier, Popp, Wall 2016, "A unified approach for
beam-to-beam contact", CMAME 315:972: line contact below ``angle_line``, point contact above
``angle_point``, a C2 blend between). The tables take T at 1 - h(1 - u - b), h a C2 ramp
of band b = 1e-4 in u = rho/R (its ramp spans 7 table intervals): the energy is C2 at first
touch and exactly zero while d >= R; past the band the kernels act at delta - b R (a shift
of 1e-4 R: 3 % of the force at the smallest overlap the FEM cross-check uses, 0.003 D).

Resolution: the contact zone of a pair at overlap x has half-length sqrt(2 R x) along the
strands; the Gauss quadrature reproduces the laws within a few per cent when it spans two
Gauss spacings or more (docs/design_notes.md, contact).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import inspect
import json
import math
import os
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from tightknot.atomic import atomic_open

_LAW_FILE = Path(__file__).resolve().parents[1] / "data" / "contact_law.json"


#: Kernel tables: u = rho/R from U_MIN to 1 in TABLE_INTERVALS cubic pieces; the onset band
#: (C2 smoothing of first touch) is TABLE_BAND wide in u.
U_MIN = 0.02
TABLE_INTERVALS = 32768
TABLE_BAND = 1e-4


@dataclass(frozen=True)
class RadialComplianceLaw:
    """Parameters of the radial-compliance contact law (non-dimensional unless stated).

    Attributes:
        k_line, p_line: per-side line-contact force per length, f/(E D) = k (w/D)^p.
        k_point, p_point: per-side point-contact force, F/(E D^2) = k (w/D)^p.
        k_width, p_width: line-contact half-width, b/D = k (w/D)^p.
        c_lc, p_lc: fraction of the perimeter in contact on one side, c (w/D)^p.
        k_pmax_line, p_pmax_line: line-contact peak pressure, p_max/E = k (w/D)^p.
        k_pmax_point, p_pmax_point: point-contact peak pressure, p_max/E = k (w/D)^p.
        k_patch, p_patch: point-contact patch semi-axis, a/D = k (w/D)^p.
        k_area, p_area: section area under squeeze, A/A0 = (1/stretch)(1 - k (w/D)^p).
        onset_band: width of the C2 onset of the kernels in u = rho/R (the law acts at
            delta - band R): 1e-4 for the compliant law; a stiff penalty needs a smoother
            onset (the rigid tube uses 2e-3).
        angle_line_deg, angle_point_deg: crossing angles [deg] below which the contact is
            a line contact and above which it is a point contact.
        rigid: a rigid-tube law (stiff, for comparison): the outputs of a deformable
            section (width, pressure, area) are then reported as zero / unchanged.
        core_fraction, core_hard_relative, core_stiffness: the hard core that stiffens the
            contact of deep squeezes (the contact layer's barrier: from the centerline
            distance core_fraction R, diverging at core_hard_relative R, stiffness over
            E/D), fitted together with the power laws to the FEM's deep squeezes
            (:func:`tightknot.fem.calibration.calibrate_core`); None: the layer's defaults.
        calibrated_w_hat: the largest per-side approach w/D the law (with its core) was
            calibrated to [-]: a state beyond it is outside the calibrated range.
        power_w_hat: the largest w/D the power laws were fitted to [-] (the FEM's squeeze
            and indent); the core, fitted to plane-strain squeezes, carries the line
            contact on to ``calibrated_w_hat``, so a crossing (point contact) deeper than
            this is extrapolated.
        source: where the parameters come from.
    """

    k_line: float
    p_line: float
    k_point: float
    p_point: float
    k_width: float = 1.0
    p_width: float = 0.6
    c_lc: float = 0.64
    p_lc: float = 0.6
    k_pmax_line: float = 1.3
    p_pmax_line: float = 0.6
    k_pmax_point: float = 1.2
    p_pmax_point: float = 0.5
    k_patch: float = 0.71
    p_patch: float = 0.5
    k_area: float = 1.0
    p_area: float = 1.2
    onset_band: float = TABLE_BAND
    angle_line_deg: float = 15.0
    angle_point_deg: float = 35.0
    rigid: bool = False
    core_fraction: float | None = None
    core_hard_relative: float | None = None
    core_stiffness: float | None = None
    calibrated_w_hat: float = 0.15
    power_w_hat: float = 0.15
    source: str = "parameters"

    def __post_init__(self) -> None:
        for name in ("k_line", "k_point"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v!r}")
        for name in ("p_line", "p_point"):
            v = getattr(self, name)
            # Energy ~ w^(p+1): C2 at first touch needs p >= 1 (the kernel's onset band
            # smooths the rest).
            if not (math.isfinite(v) and 1.0 <= v <= 6.0):
                raise ValueError(f"{name} must be in [1, 6], got {v!r}")
        if not (3 * (1.0 - U_MIN) / TABLE_INTERVALS <= self.onset_band <= 0.05):
            # The ramp (2 bands wide) must span several table intervals to be resolved.
            raise ValueError(f"onset_band must be in [1e-4, 0.05], got {self.onset_band!r}")
        if not (0.0 < self.angle_line_deg < self.angle_point_deg < 90.0):
            raise ValueError("need 0 < angle_line_deg < angle_point_deg < 90")

    # -- constructors ----------------------------------------------------------------------
    @classmethod
    def from_json(cls, path: str | Path | None = None) -> RadialComplianceLaw:
        """The calibrated law (default: the file shipped in ``tightknot/data``)."""
        if path is None:
            text = _LAW_FILE.read_text()
            where = "tightknot/data/contact_law.json"
        else:
            text = Path(path).read_text()
            where = str(path)
        d = json.loads(text)
        keys = {f for f in cls.__dataclass_fields__}
        kw = {k: float(v) for k, v in d.items() if k in keys and isinstance(v, (int, float))}
        if "w_hat_max" in d:
            kw["power_w_hat"] = float(d["w_hat_max"])
        if "k_patch" not in kw and "k_patch_axial" in d:
            kw["k_patch"] = float(d["k_patch_axial"])
            kw["p_patch"] = float(d["p_patch_axial"])
        date = d.get("provenance", {}).get("date", "?")
        return cls(**kw, source=f"FEM calibration {where} ({date})")

    @classmethod
    def hertz(cls) -> RadialComplianceLaw:
        """Small-strain elastic contact of cylinders as power laws: the plane-strain line
        contact (Johnson 1985 eqs. 4.45, 5.36, fitted over w/D in [1e-3, 0.15]) and Hertz
        crossed cylinders F = (4/3) E* sqrt(R) d^(3/2) (Johnson 1985 eq. 4.22; rigid
        indenter, E* = E/(1 - nu^2), nu = 1/2); values of the shipped calibration file."""
        d = json.loads(_LAW_FILE.read_text())
        h = d["hertz"]
        return cls(k_line=h["k_line"], p_line=h["p_line"], k_point=h["k_point"],
                   p_point=h["p_point"], k_width=h["k_width"], p_width=h["p_width"],
                   k_pmax_line=h["k_pmax_line"], p_pmax_line=h["p_pmax_line"],
                   k_pmax_point=h["k_pmax_point"], p_pmax_point=h["p_pmax_point"],
                   k_patch=h["k_patch"], p_patch=h["p_patch"],
                   source="small-strain Hertz (Johnson 1985)")

    def rigid_tube(self, stiffness: float = 1e3) -> RadialComplianceLaw:
        """A rigid-tube version: ``stiffness`` times stiffer, with a hard radius (the contact
        layer then keeps the rest radius instead of thinning it with stretch)."""
        return replace(self, k_line=self.k_line * stiffness, k_point=self.k_point * stiffness,
                       p_line=max(self.p_line, 1.0), p_point=max(self.p_point, 1.0),
                       onset_band=2e-3, rigid=True, core_fraction=None,
                       core_hard_relative=None, core_stiffness=None,
                       source=f"rigid tube ({stiffness:g} x {self.source})")

    def without_core(self) -> RadialComplianceLaw:
        """The power laws alone: the contact layer then takes its default barrier, which
        starts only where the power laws' calibration ends (pair overlap 0.3 R)."""
        return replace(self, core_fraction=None, core_hard_relative=None, core_stiffness=None,
                       source=f"{self.source} without its core")

    def as_dict(self) -> dict:
        """Parameters as a JSON-ready dict."""
        return asdict(self)

    # -- pair energies (SI), used by the kernels' constants and by tests -------------------
    def line_energy_coefficient(self, youngs_modulus: float, diameter: float) -> float:
        """K_line [J/m^(1+m)] of ``e_line(delta) = K delta^m``, m = p_line + 1."""
        m = self.p_line + 1.0
        return 2.0 * self.k_line * youngs_modulus * diameter**2 * (2 * diameter) ** (-m) / m

    def point_energy_coefficient(self, youngs_modulus: float, diameter: float) -> float:
        """K_point [J/m^m] of ``e_point(delta) = K delta^m``, m = p_point + 1."""
        m = self.p_point + 1.0
        return 2.0 * self.k_point * youngs_modulus * diameter**3 * (2 * diameter) ** (-m) / m

    def line_force_per_length(self, delta: np.ndarray, youngs_modulus: float,
                              diameter: float) -> np.ndarray:
        """Pair force per unit length [N/m] of identical parallel rods at overlap delta [m]."""
        w = np.maximum(np.asarray(delta, dtype=float), 0.0) / 2.0
        return self.k_line * youngs_modulus * diameter * (w / diameter) ** self.p_line

    def point_force(self, delta: np.ndarray, youngs_modulus: float,
                    diameter: float) -> np.ndarray:
        """Pair force [N] of identical crossing rods at overlap delta [m]."""
        w = np.maximum(np.asarray(delta, dtype=float), 0.0) / 2.0
        return self.k_point * youngs_modulus * diameter**2 * (w / diameter) ** self.p_point

    # -- section outputs (per side, from the calibrated fits) -----------------------------
    def half_width(self, w: np.ndarray, diameter: float) -> np.ndarray:
        """Line-contact half-width b [m] at per-side approach w [m]."""
        return self._power(self.k_width, self.p_width, w, diameter) * diameter

    def contact_fraction(self, w: np.ndarray, diameter: float) -> np.ndarray:
        """Fraction of the perimeter in contact on one side at approach w [m]."""
        return np.minimum(self._power(self.c_lc, self.p_lc, w, diameter), 0.5)

    def peak_pressure_line(self, w: np.ndarray, diameter: float) -> np.ndarray:
        """Peak line-contact pressure over E at approach w [m]."""
        return self._power(self.k_pmax_line, self.p_pmax_line, w, diameter)

    def peak_pressure_point(self, w: np.ndarray, diameter: float) -> np.ndarray:
        """Peak point-contact pressure over E at approach w [m]."""
        return self._power(self.k_pmax_point, self.p_pmax_point, w, diameter)

    def area_factor(self, w: np.ndarray, diameter: float) -> np.ndarray:
        """Section area factor 1 - k_area (w/D)^p_area under a squeeze w [m] per side."""
        return np.maximum(1.0 - self._power(self.k_area, self.p_area, w, diameter), 0.0)

    @staticmethod
    def _power(k: float, p: float, w: np.ndarray, diameter: float) -> np.ndarray:
        w = np.maximum(np.asarray(w, dtype=float), 0.0)
        return k * (w / diameter) ** p


def _ramp(y: np.ndarray, eps: float) -> np.ndarray:
    """C2 positive part with onset band [-eps, eps] (as contact_kernels.positive_part)."""
    out = np.where(y >= eps, y, 0.0)
    band = (y > -eps) & (y < eps)
    yy = y[band] + eps
    out[band] = yy**3 * (3 * eps - y[band]) / (16 * eps**3)
    return out


def abel_line_profile(m: float, u: np.ndarray) -> np.ndarray:
    """Phi_m(u) = int_u^1 (1 - v)^(m-1) / sqrt(v^2 - u^2) dv, the Abel inverse of a line
    energy K (R - d)^m (Bracewell 2000, "The Fourier transform", Abel pair): with
    v = u cosh t the integrand is smooth, integrated by 200-point Gauss-Legendre."""
    u = np.asarray(u, dtype=float)
    tmax = np.arccosh(1.0 / np.clip(u, 1e-12, 1.0))
    xg, wg = np.polynomial.legendre.leggauss(200)
    t = 0.5 * (xg[None, :] + 1.0) * tmax[:, None]
    f = np.clip(1.0 - u[:, None] * np.cosh(t), 0.0, None) ** (m - 1.0)
    return 0.5 * tmax * (f * wg[None, :]).sum(axis=1)


def _table_cache_dir() -> Path | None:
    """Folder of the on-disk kernel tables: $TIGHTKNOT_CACHE, else a ``tightknot`` folder in
    Warp's kernel cache ($WARP_CACHE_PATH, which the Makefile and tests set); None (no disk
    cache) when neither is set."""
    root = os.environ.get("TIGHTKNOT_CACHE")
    if root:
        return Path(root)
    warp_cache = os.environ.get("WARP_CACHE_PATH")
    return Path(warp_cache) / "tightknot" if warp_cache else None


def _table_key(kind: str, m: float, band: float) -> str:
    """Cache key: the arguments exactly (float.hex), the table size, and a hash of the code
    that computes the table (so a changed formula never reads an old file)."""
    code = inspect.getsource(_kernel_table) + inspect.getsource(abel_line_profile) + (
        inspect.getsource(_ramp))
    text = f"{kind}|{float(m).hex()}|{float(band).hex()}|{U_MIN!r}|{TABLE_INTERVALS}|{code}"
    return hashlib.sha256(text.encode()).hexdigest()[:24]


@functools.lru_cache(maxsize=16)
def kernel_table(kind: str, m: float, band: float = TABLE_BAND) -> np.ndarray:
    """The table of :func:`_kernel_table`, cached in memory and on disk (computing the line
    kernel's Abel integrals takes about a second, paid once per machine instead of once per
    process: sweep workers and CLI runs start faster). A cached file is used only if it
    loads as an array of the right shape with finite values; it is written atomically."""
    folder = _table_cache_dir()
    path = None if folder is None else folder / f"kernel_{kind}_{_table_key(kind, m, band)}.npy"
    if path is not None and path.is_file():
        try:
            table = np.load(path, allow_pickle=False)
            if table.shape == (TABLE_INTERVALS, 4) and np.isfinite(table).all():
                return table
        except (OSError, ValueError):
            pass  # unreadable or truncated: compute it again and replace it
    table = _kernel_table(kind, m, band)
    if path is not None:
        with contextlib.suppress(OSError):  # a read-only cache only costs the speed-up
            path.parent.mkdir(parents=True, exist_ok=True)
            with atomic_open(path, "wb") as handle:
                np.save(handle, table, allow_pickle=False)
    return table


def _kernel_table(kind: str, m: float, band: float = TABLE_BAND) -> np.ndarray:
    """Cubic-spline coefficients (TABLE_INTERVALS, 4) of the dimensionless kernel T(u):
    line: T = Phi_m(u) (kernel (K m/pi) R^(m-1) T(rho/R)); point: T = (1-u)^(m-1)/u (kernel
    K m/(2 pi) R^(m-2) T). T is taken at 1 - h(1 - u - b), h the C2 ramp of band b
    (``band``, default TABLE_BAND), so that the kernel is C2 at first touch and zero for
    u >= 1; beyond the band T(u + b) is used, i.e. the law at delta - b R. Cached per
    (kind, m, band): the returned array must not be modified.
    Row j holds (a, b, c, d) of T = a + b t + c t^2 + d t^3, t = u - u_j."""
    from scipy.interpolate import CubicSpline

    u = np.linspace(U_MIN, 1.0, TABLE_INTERVALS + 1)
    # The band lies inside the contact, [0, 2 band] in 1 - u: T(1) = 0 exactly, with zero
    # derivatives, so first touch is continuous (a centred band would give T(1) > 0: an
    # energy jump as a Gauss pair crosses u = 1, which stalls Newton).
    ue = 1.0 - _ramp(1.0 - u - band, band)
    if kind == "line":
        vals = abel_line_profile(m, ue)
    elif kind == "point":
        vals = np.where(ue < 1.0, np.clip(1.0 - ue, 0, None) ** (m - 1.0) / ue, 0.0)
    else:
        raise ValueError(f"kind must be 'line' or 'point', got {kind!r}")
    spl = CubicSpline(u, vals, bc_type=((1, float((vals[1] - vals[0]) / (u[1] - u[0]))),
                                        (1, 0.0)))
    c = spl.c  # (4, intervals), descending powers
    return np.ascontiguousarray(np.stack([c[3], c[2], c[1], c[0]], axis=1))
