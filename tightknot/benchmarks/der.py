"""Cost of one Newton iteration of the DER core (assembly plus sparse direct solve).

A clamped helix with a tip load (every stencil bent, stretched and twisted) of N vertices;
one iteration = Warp evaluation of energy, gradient and Hessian, plus the factorization
and solve. Also the start-up: Warp kernel compilation with an empty cache and with a warm
one, each measured in a fresh subprocess.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material
from tightknot.rods.state import State
from tightknot.solvers.system import RodSystem

DEFAULT_SIZES = (100, 1000, 10000, 100000)


def helix(n: int, turns_per_vertex: float = 0.01, radius: float = 0.02,
          pitch: float = 0.01) -> np.ndarray:
    """A helix of n vertices [m] (0.01 turn per edge: every joint bent)."""
    phi = 2 * np.pi * turns_per_vertex * np.arange(n)
    return np.c_[radius * np.cos(phi), radius * np.sin(phi), pitch * phi / (2 * np.pi)]


def iteration_time(n: int, repeats: int = 5, device: str = "cpu") -> dict:
    """Median times [s] of assembly, solve and one whole Newton iteration for n vertices."""
    b = RodBuilder()
    b.add_rod(helix(n), diameter=0.002, material=Material())
    model = b.finalize(device)
    bcs = BoundaryConditions(model).clamp(0, "start").force(0, -1, [0.0, 0.0, -1e-3])
    system = RodSystem(model, State.initial(model), bcs)
    system.set_load(1.0)
    system.evaluate(system.free_vector())  # warm-up (kernel load, allocations)
    a, s = newton_iteration_parts(system, repeats)
    return {"vertices": n, "newton_iteration_s": a + s, "assembly_s": a, "solve_s": s}


def newton_iteration_parts(system: RodSystem, repeats: int) -> tuple[float, float]:
    """Median times [s] of the two parts of one Newton iteration at the system's state,
    as :func:`tightknot.solvers.newton.newton` does them: the evaluation with
    Hessian, and the factorization + solve."""
    u = system.free_vector()
    ta, ts = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        _, g, h = system.evaluate(u, True, True)
        t1 = time.perf_counter()
        system.linear.shifted_direction(h, g, 0.0, np.ones(g.size))
        t2 = time.perf_counter()
        ta.append(t1 - t0)
        ts.append(t2 - t1)
    return float(np.median(ta)), float(np.median(ts))


_STARTUP = (
    "import time; t=time.perf_counter();"
    "import numpy as np;"
    "from tightknot.verification.cases import neo_hookean_stretch;"
    "from tightknot.rods.builder import RodBuilder;"
    "from tightknot.contact.layer import ContactLayer;"
    "neo_hookean_stretch();"
    "s=np.linspace(0,0.1,11); b=RodBuilder(twist=False);"
    "b.add_rod(np.c_[s,0*s,0*s],0.01); b.add_rod(np.c_[0*s+0.05,s-0.05,0*s+0.009],0.01);"
    "m=b.finalize(); ContactLayer(m).evaluate(m.vertex_initial_position,"
    "m.edge_rest_length,True,True);"
    "print(time.perf_counter()-t)"
)


def startup_time(cache_dir: str | None) -> float:
    """Seconds to import tightknot, load (or compile) all its kernel modules (elastic and
    contact) and solve a tiny case, in a fresh Python process; ``cache_dir`` is the Warp
    kernel cache to use."""
    env = dict(os.environ)
    if cache_dir is not None:
        env["WARP_CACHE_PATH"] = cache_dir
    out = subprocess.run([sys.executable, "-c", _STARTUP], env=env, check=True,
                         capture_output=True, text=True)
    return float(out.stdout.strip().splitlines()[-1])


def run(sizes: tuple[int, ...] = DEFAULT_SIZES, startup: bool = True,
        device: str = "cpu") -> dict:
    """All rows, the scaling ratio and (optionally) cold/warm start-up times."""
    rows = [iteration_time(n, device=device) for n in sizes]
    result: dict = {"rows": rows}
    by_n = {r["vertices"]: r["newton_iteration_s"] for r in rows}
    if 1000 in by_n and 100000 in by_n:
        result["ratio_1e5_over_1e3"] = by_n[100000] / by_n[1000]
    if startup:
        with tempfile.TemporaryDirectory() as cold:
            result["startup_cold_cache_s"] = startup_time(cold)
            result["startup_warm_cache_s"] = startup_time(cold)
    result["targets"] = {
        "ratio_1e5_over_1e3_max": 150.0,
        "newton_iteration_1e3_max_s": 5e-3,
        "startup_cold_cache_max_s": 30.0,
        "startup_warm_cache_max_s": 1.0,
    }
    return result


# -- command line (``tightknot bench der``) --------------------------------------------------
_EXAMPLES = """examples:
  tightknot bench der --json der.json
  tightknot bench der --sizes 100 1000 --no-startup
"""


def register(subparsers) -> None:  # noqa: ANN001 (argparse's private subparsers type)
    """Add ``tightknot bench der``."""
    import argparse

    p = subparsers.add_parser(
        "der", help="Newton-iteration cost of the DER core versus size (1e2..1e5)",
        description="Cost of one Newton iteration (assembly + sparse solve) of a clamped "
        "helix with N vertices, and the Warp start-up with a cold and a warm kernel cache.",
        epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", metavar="FILE", help="write the result as JSON")
    p.add_argument("--sizes", type=int, nargs="+", help="vertex counts (default 1e2..1e5)")
    p.add_argument("--no-startup", action="store_true", help="skip the start-up timing")
    p.add_argument("--device", default=None, help="Warp device (default cpu)")
    p.set_defaults(handler=_command)


def _command(args) -> int:  # noqa: ANN001
    from tightknot.atomic import writable_file, write_json_atomic
    from tightknot.warp_setup import resolve_device

    out = writable_file(args.json)
    device = resolve_device(args.device)
    sizes = tuple(args.sizes) if args.sizes else DEFAULT_SIZES
    if any(n < 3 for n in sizes):
        raise ValueError("--sizes must be >= 3 vertices each")
    result = run(sizes, startup=not args.no_startup, device=device)
    for r in result["rows"]:
        print(f"{r['vertices']:>8d} vertices: iteration {r['newton_iteration_s'] * 1e3:9.3f} ms"
              f"  (assembly {r['assembly_s'] * 1e3:8.3f} ms, solve {r['solve_s'] * 1e3:8.3f} ms)")
    for key in ("ratio_1e5_over_1e3", "startup_cold_cache_s", "startup_warm_cache_s"):
        if key in result:
            print(f"{key}: {result[key]:.3f}")
    if out is not None:
        write_json_atomic(out, result)
    return 0
