"""Cost of a Newton iteration and of a full solve with self-contact, 1e2 to 1e5 vertices.

The scene: a long rod coiled into a tight helix whose neighbouring turns touch (pitch
``PITCH`` D0, so every turn presses on the next with a small overlap), both ends clamped.
The helix radius and the edge length are fixed, so the number of turns, and with it the
number of contact pairs, grows linearly with N.

Why the helix radius is one diameter (``RADIUS``). The contact graph of the coil is a grid
wrapped on a cylinder: W vertices around a turn, L = N / W turns along it. A sparse direct
solve of such a grid costs about N min(W, L)^2 (the separators are the shorter side), so
it is linear in N only once L >= W. At 1 D0 (W = 25) the 1e3-vertex coil already has 39
turns, so both ends of the size range are in the long regime (a wider coil mixes the two
regimes; ``--helix-radius 3`` runs the earlier scene, docs/design_notes.md). One Newton
iteration is split into its parts, each timed on its own (median of repeats) at the start
state:

- elastic: Warp evaluation of the DER energy, gradient and Hessian (into the fixed pattern);
- contact: detection (BVH, candidate pairs) and the pair kernel, plus the conversion of
  the contact Hessian's COO triplets onto the free dofs (the system's evaluation with and
  without its contact term, the difference);
- other: the rest of the system's evaluation (frame transport, gathering);
- solve: sparse factorization and solve;
- step bound and line search: the contact layer's no-passing-through bound and one
  energy-only evaluation (the fewest a Newton iteration takes).

Their sum is the per-iteration time whose ratio t(1e5)/t(1e3) the issue bounds (150).
The full solve is one implicit-Euler step from that start, solved to tolerance
(:func:`full_solve` says why not the static equilibrium): wall time, Newton iterations and
mean time per iteration.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from tightknot.contact.layer import ContactLayer
from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material
from tightknot.rods.state import State
from tightknot.solvers.linear import factorize
from tightknot.solvers.newton import NewtonOptions
from tightknot.solvers.system import RodSystem

DEFAULT_SIZES = (100, 1000, 10000, 100000)
#: Rod diameter D0 [m], helix radius over D0, edge length over D0, pitch over D0.
DIAMETER = 1e-3
RADIUS = 1.0
EDGE = 0.25  # the contact layer resolves contact with edges below 0.3 D0 (contact.py)
PITCH = 0.99  # turns overlap by ~1 % of D0: every turn is in contact with the next
#: Time step of the full solve [s] (see full_solve). Bending waves of a turn scale with the
#: square of its length, so a tighter coil takes a shorter step: 1e-3 s in the 3 D0 coil,
#: 3e-4 s in this one.
STEP_DT = 3e-4
#: Largest size of the full solve by default, and its Newton budget (the step converges
#: well within it at 1e4 vertices).
SOLVE_MAX = 10000
SOLVE_ITERATIONS = 30
#: The issue's targets.
TARGET_RATIO_1E5_1E3 = 150.0


def vertices_per_turn(helix_radius: float = RADIUS) -> float:
    """Vertices in one turn of the coil of helix radius ``helix_radius`` D0."""
    return math.hypot(2 * math.pi * helix_radius, PITCH) / EDGE


def coiled_rod(n: int, helix_radius: float = RADIUS) -> np.ndarray:
    """A helix of n vertices [m] and radius ``helix_radius`` D0, turns touching (module
    docstring)."""
    if not (math.isfinite(helix_radius) and helix_radius >= 0.75):
        # A tighter coil bends the rod beyond kappa D0 = 4/3, its inner fibre within a quarter
        # of a diameter of the helix axis: outside what this benchmark is meant to load.
        raise ValueError(f"helix_radius must be >= 0.75 (in D0), got {helix_radius!r}")
    d = DIAMETER
    r, pitch = helix_radius * d, PITCH * d
    turn = math.hypot(2 * math.pi * r, pitch)  # rod length per turn
    phi = 2 * math.pi * EDGE * d / turn * np.arange(n)
    return np.c_[r * np.cos(phi), r * np.sin(phi), pitch * phi / (2 * math.pi)]


def coiled_system(n: int, device: str = "cpu", helix_radius: float = RADIUS
                  ) -> tuple[RodSystem, ContactLayer]:
    """The clamped coil of n vertices with its contact layer, at its start."""
    b = RodBuilder()
    b.add_rod(coiled_rod(n, helix_radius), diameter=DIAMETER, material=Material())
    model = b.finalize(device)
    bcs = BoundaryConditions(model).clamp(0, "start").clamp(0, "end")
    system = RodSystem(model, State.initial(model), bcs)
    contact = ContactLayer(model)
    system.add_term(contact)
    system.set_load(1.0)
    return system, contact


def _median(fn, repeats: int) -> float:  # noqa: ANN001
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


def iteration_parts(n: int, repeats: int = 3, device: str = "cpu",
                    helix_radius: float = RADIUS) -> dict:
    """Median times [s] of the parts of one Newton iteration at the coil's start."""
    system, contact = coiled_system(n, device, helix_radius)
    st = system.state
    u = system.free_vector()
    _, g, h = system.evaluate(u, True, True)  # warm-up (allocations, buffer growth)
    pairs = int(len(contact.last_pairs))
    active = int(np.count_nonzero(contact.last_overlap > 0.0))

    def elastic() -> None:
        system._hess.zero_()
        system.forces.evaluate(st.x, st.theta, st.m_ref, system.rest, True, system._hess)

    def without_contact() -> None:
        # The system's evaluation with its contact term taken out: the difference to the
        # whole evaluation is what contact costs inside it (detection, pair kernel, and the
        # contact Hessian's conversion onto the free dofs).
        terms = system.extra_terms
        system.extra_terms = []
        try:
            system.evaluate(u, True, True)
        finally:
            system.extra_terms = terms

    d = -g
    parts = {
        "elastic_s": _median(elastic, repeats),
        "evaluate_s": _median(lambda: system.evaluate(u, True, True), repeats),
        "evaluate_without_contact_s": _median(without_contact, repeats),
        "solve_s": _median(lambda: factorize(h).solve(-g), repeats),
        "step_bound_s": _median(lambda: system.max_step(u, 1e-6 * d), repeats),
        "energy_s": _median(lambda: system.evaluate(u, False, False), repeats),
    }
    parts["contact_s"] = max(parts["evaluate_s"] - parts["evaluate_without_contact_s"], 0.0)
    parts["other_s"] = max(parts["evaluate_without_contact_s"] - parts["elastic_s"], 0.0)
    iteration = (parts["evaluate_s"] + parts["solve_s"] + parts["step_bound_s"]
                 + parts["energy_s"])
    return {"vertices": n, "contact_pairs": pairs, "contact_pairs_overlapping": active,
            "dofs": int(system.pattern.n), "newton_iteration_s": iteration, **parts}


def full_solve(n: int, dt: float = STEP_DT, residual_tol: float = 1e-6,
               max_iterations: int = SOLVE_ITERATIONS, device: str = "cpu",
               helix_radius: float = RADIUS) -> dict:
    """One implicit-Euler step of ``dt`` [s] of the clamped coil from rest, solved to
    ``residual_tol`` in units of EI/D0^2 (forces) and EI/D0 (moments): the overlapping
    turns push each other apart.

    Why a time step and not the static equilibrium: a coil of a straight rod with pressed
    turns between clamps is frustrated (its turns can separate only by rearranging the
    whole coil), and the static Newton solve from it does not converge; the time step is
    the well-posed solve a dynamic simulation
    makes at every step. The tolerance is relative to the rod's section, not its length:
    the system's own scale EI/L^2 shrinks as 1/N^2 and would ask for forces below
    round-off at 1e5 vertices.
    """
    from tightknot.solvers.dynamic import implicit_euler_step

    system, contact = coiled_system(n, device, helix_radius)
    length = system.model.rest_length()
    tol = residual_tol * (length / DIAMETER) ** 2
    t0 = time.perf_counter()
    step = implicit_euler_step(system, dt, NewtonOptions(residual_tol=tol,
                                                         max_iterations=max_iterations))
    wall = time.perf_counter() - t0
    res = step.newton
    return {"solve_s": wall, "dt_s": dt, "iterations": res.iterations,
            "converged": res.converged, "reason": res.reason,
            "per_iteration_s": wall / max(res.iterations, 1),
            "contact_pairs_after": int(np.count_nonzero(contact.last_overlap > 0))}


def run(sizes: tuple[int, ...] = DEFAULT_SIZES, solve_max: int = SOLVE_MAX, repeats: int = 3,
        device: str = "cpu", helix_radius: float = RADIUS) -> dict:
    """All rows and the ratios (where the sizes include 1e3 with 1e4 or 1e5); the full
    solve runs for sizes up to ``solve_max`` vertices."""
    if not sizes or any(int(n) != n or n < 16 for n in sizes):
        raise ValueError(f"sizes must be whole numbers >= 16 vertices, got {sizes!r}")
    rows = []
    for n in sizes:
        row = iteration_parts(int(n), repeats, device, helix_radius)
        row["turns"] = n / vertices_per_turn(helix_radius)
        if n <= solve_max:
            row["full_solve"] = full_solve(int(n), device=device, helix_radius=helix_radius)
        rows.append(row)
    result: dict = {"scene": {"diameter_m": DIAMETER, "helix_radius_over_D0": helix_radius,
                              "vertices_per_turn": vertices_per_turn(helix_radius),
                              "edge_over_D0": EDGE, "pitch_over_D0": PITCH,
                              "ends": "both clamped"},
                    "rows": rows}
    by_n = {r["vertices"]: r for r in rows}
    if 1000 in by_n and 100000 in by_n:
        result["ratio_1e5_over_1e3"] = (by_n[100000]["newton_iteration_s"]
                                        / by_n[1000]["newton_iteration_s"])
    if 1000 in by_n and 10000 in by_n:
        result["contact_ratio_1e4_over_1e3"] = (by_n[10000]["contact_s"]
                                                / by_n[1000]["contact_s"])
        result["iteration_ratio_1e4_over_1e3"] = (by_n[10000]["newton_iteration_s"]
                                                  / by_n[1000]["newton_iteration_s"])
    result["solve_max_vertices"] = solve_max
    result["targets"] = {"ratio_1e5_over_1e3_max": TARGET_RATIO_1E5_1E3,
                         "contact_ratio_1e4_over_1e3_linear": 10.0}
    return result


def plot(result: dict, path: Path) -> None:
    """Log-log plot of the per-iteration parts and the full solve against N (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tightknot.atomic import atomic_open

    rows = result["rows"]
    n = np.array([r["vertices"] for r in rows], dtype=float)
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    for key, label in (("newton_iteration_s", "Newton iteration (sum)"),
                       ("elastic_s", "elastic assembly"),
                       ("contact_s", "contact (detection + assembly)"),
                       ("solve_s", "linear solve")):
        ax.loglog(n, [r[key] for r in rows], "o-", label=label)
    if all("full_solve" in r for r in rows):
        ax.loglog(n, [r["full_solve"]["solve_s"] for r in rows], "s--", label="full solve")
    ref = rows[0]["newton_iteration_s"] * n / n[0]
    ax.loglog(n, ref, "k:", label="linear in N")
    ax.set_xlabel("vertices N")
    ax.set_ylabel("time [s]")
    ax.set_title("Coiled rod with self-contact: cost versus size")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    with atomic_open(path, "wb") as handle:
        fig.savefig(handle, format="png", dpi=120)
    plt.close(fig)


# -- command line (``tightknot bench scaling``) ----------------------------------------------
_EXAMPLES = """examples:
  tightknot bench scaling --json scaling.json     # also writes scaling.png
  tightknot bench scaling --sizes 100 1000 --solve-max 0
  tightknot bench scaling --solve-max 100000         # full solves up to 1e5 (minutes)
  tightknot bench scaling --helix-radius 3           # the coil used before 2026-12-01
"""


def register(subparsers) -> None:  # noqa: ANN001 (argparse's private subparsers type)
    """Add ``tightknot bench scaling``."""
    import argparse

    p = subparsers.add_parser(
        "scaling", help="Newton iteration and full solve with self-contact, 1e2..1e5 vertices",
        description="A tight helix whose turns touch (contact pairs grow with N), both ends "
        "clamped: per-iteration time split into elastic, contact and linear solve, and the "
        "full Newton solve, for each size. Writes a log-log PNG next to the JSON.",
        epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", metavar="FILE", help="write the result as JSON (+ FILE.png)")
    p.add_argument("--sizes", type=int, nargs="+", help="vertex counts (default 1e2..1e5)")
    p.add_argument("--solve-max", type=int, default=SOLVE_MAX,
                   help=f"full solve up to this many vertices (default {SOLVE_MAX}; 0: none)")
    p.add_argument("--helix-radius", type=float, default=RADIUS, metavar="R",
                   help=f"helix radius of the coil in D0 (default {RADIUS:g}; >= 0.75; 3 was "
                   "the default before 2026-12-01, see the module docstring)")
    p.add_argument("--device", default=None, help="Warp device (default cpu)")
    p.set_defaults(handler=_command)


def _command(args) -> int:  # noqa: ANN001
    from tightknot.atomic import writable_file, write_json_atomic
    from tightknot.warp_setup import resolve_device

    out = writable_file(args.json)
    sizes = tuple(args.sizes) if args.sizes else DEFAULT_SIZES
    if any(n < 16 for n in sizes):
        raise ValueError("--sizes must be >= 16 vertices each")
    result = run(sizes, solve_max=args.solve_max, device=resolve_device(args.device),
                 helix_radius=args.helix_radius)
    for r in result["rows"]:
        line = (f"{r['vertices']:>7d} vertices, {r['contact_pairs_overlapping']:>6d} contacts: "
                f"iteration {r['newton_iteration_s'] * 1e3:9.2f} ms (elastic "
                f"{r['elastic_s'] * 1e3:.2f}, contact {r['contact_s'] * 1e3:.2f}, solve "
                f"{r['solve_s'] * 1e3:.2f}, other {r['other_s'] * 1e3:.2f} ms)")
        if "full_solve" in r:
            fs = r["full_solve"]
            line += (f"; full solve {fs['solve_s']:.2f} s, {fs['iterations']} iterations"
                     f"{'' if fs['converged'] else ' (NOT converged: ' + fs['reason'] + ')'}")
        print(line)
    for key in ("ratio_1e5_over_1e3", "iteration_ratio_1e4_over_1e3",
                "contact_ratio_1e4_over_1e3"):
        if key in result:
            print(f"{key}: {result[key]:.2f}")
    if out is not None:
        write_json_atomic(out, result)
        plot(result, out.with_suffix(".png"))
    return 0
