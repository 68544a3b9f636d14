"""dismech-newton (DER on Warp/Newton) for the open-trefoil pull scene: what runs and what does not.

Standalone, run by the Python of a separate environment holding ``dismech-newton`` (see
README.md), never importing tightknot::

    /tmp/dmvenv/bin/python bench/peers/dismech_pull.py SCENE.npz RESULT.npz

What it does, in order, recording each outcome in the result's ``stats``:
1. ``import dismech_newton`` as released. On Python 3.10 to 3.13, 0.1.0.post4 fails here:
   ``contact.py`` annotates a method ``-> Slots | None`` where ``Slots`` is a ``wp.struct``
   instance, and Python evaluates that annotation when it defines the class (``Struct | None``
   is a TypeError). Nothing else is attempted on the as-released path.
2. The same unchanged source compiled with postponed annotations (PEP 563, the compile flag
   of ``from __future__ import annotations``; Python 3.14 defers annotations by default,
   PEP 649): an import hook compiles the package's files with that flag, its code and files
   untouched. Then a smoke test: a short straight rod of the scene's material, one end
   clamped, stepped a few times on the CPU. Measured with 0.1.0.post4, newton 1.6.1, warp
   1.19.0: the import succeeds, the solver's construction fails: Warp evaluates the string
   annotations of the kernels that ``element.element_kernels(View, ...)`` defines, and
   ``View`` (a parameter of that factory) is not visible to a string annotation (NameError).
   The package thus needs Python >= 3.14 (PEP 649: annotations deferred but evaluated in
   their scope), which this machine lacks (pyenv up to 3.13, Debian 12 ships 3.11). Newton's
   ``Rod`` also refuses nu = 0.5 (it requires -1 < nu < 0.5): the smoke test passes the
   shear modulus instead.
3. The scene itself is NOT driven: tying the knot needs the rest length shrunk from the
   start curve's length to L0 while the solver runs, and dismech-newton bakes the rest
   lengths into its per-edge rest strains and per-triplet stiffness parameters at build
   time (``add_rod``), with no public way to change them; doing it through its private
   arrays would be writing a new solver path, not running the peer. The row reports that.

The result's ``stats`` carries ``error`` (why there is no comparison row) and what worked.
"""

from __future__ import annotations
import __future__

import importlib.abc
import importlib.machinery
import json
import os
import sys
import time
import traceback

import numpy as np


def _error_line(err: BaseException) -> str:
    """``Type: message (file:line)`` of the innermost frame."""
    tb = traceback.extract_tb(err.__traceback__)
    where = f" ({os.path.basename(tb[-1].filename)}:{tb[-1].lineno}: {tb[-1].line})" if tb else ""
    return f"{type(err).__name__}: {err}{where}"


class _PostponedAnnotationsLoader(importlib.machinery.SourceFileLoader):
    """Compiles a module's unchanged source with PEP 563's flag (annotations kept as strings)."""

    def source_to_code(self, data, path, *, _optimize=-1):  # noqa: ANN001, ANN202
        return compile(data, path, "exec", flags=__future__.annotations.compiler_flag,
                       dont_inherit=True, optimize=_optimize)

    def path_stats(self, path):  # noqa: ANN001, ANN202
        # No bytecode cache: a cached .pyc compiled without the flag would be used instead.
        raise OSError("bytecode cache bypassed")


class _Finder(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):  # noqa: ANN001, ANN202
        if name != "dismech_newton" and not name.startswith("dismech_newton."):
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is not None and spec.origin and spec.origin.endswith(".py"):
            spec.loader = _PostponedAnnotationsLoader(name, spec.origin)
        return spec


def _smoke(dm, scene: dict) -> dict:  # noqa: ANN001
    """A straight 20-edge rod of the scene's material, first edge clamped, 5 implicit steps."""
    import newton

    d0 = float(scene["diameter"])
    pts = np.c_[np.linspace(0.0, 0.05, 21), np.zeros(21), np.zeros(21)]
    builder = newton.ModelBuilder(gravity=(0.0, 0.0, -9.81))
    e_mod, nu = float(scene["youngs_modulus"]), float(scene["poisson_ratio"])
    try:
        rod = newton.Rod(pts, radius=d0 / 2, youngs_modulus=e_mod, poissons_ratio=nu)
        refused = None
    except ValueError as err:
        # Newton's Rod refuses nu = 0.5 (-1 < nu < 0.5); the same material by its shear
        # modulus G = E / (2 (1 + nu)).
        refused = _error_line(err)
        rod = newton.Rod(pts, radius=d0 / 2, youngs_modulus=e_mod,
                         shear_modulus=e_mod / (2.0 * (1.0 + nu)))
    cfg = newton.ModelBuilder.ShapeConfig(density=float(scene["density"]), mu=0.0)
    bodies = dm.DiSMechSolver.add_rod(builder, rod, cfg=cfg)
    dm.DiSMechSolver.fix_segment(builder, bodies[0])
    model = builder.finalize(device="cpu")
    solver = dm.DiSMechSolver(model, friction=0.0)
    s0, s1 = model.state(), model.state()
    t = time.perf_counter()
    for _ in range(5):
        solver.step(s0, s1, None, None, 1e-3)
        s0, s1 = s1, s0
    tip = s0.particle_q.numpy()[-1]
    return {"poisson_ratio_refused": refused, "smoke_steps": 5,
            "smoke_wall_s": time.perf_counter() - t, "smoke_tip_m": [float(v) for v in tip],
            "smoke_finite": bool(np.isfinite(tip).all())}


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 2:
        print("usage: dismech_pull.py SCENE.npz RESULT.npz", file=sys.stderr)
        return 2
    with np.load(argv[0]) as z:
        scene = {k: z[k] for k in z.files}
    stats: dict = {"code": "dismech-newton", "converged": False, "python": sys.version.split()[0]}
    try:
        from importlib.metadata import version

        stats["version"] = version("dismech-newton")
    except Exception as err:  # noqa: BLE001
        stats["error"] = f"dismech-newton is not installed in {sys.executable}: {err}"
    if "error" not in stats:
        try:
            import dismech_newton  # noqa: F401

            stats["import_as_released"] = "ok"
        except Exception as err:  # noqa: BLE001
            stats["import_as_released"] = _error_line(err)
            for name in [m for m in sys.modules if m.startswith("dismech_newton")]:
                del sys.modules[name]
    if "error" not in stats:
        try:
            if stats["import_as_released"] != "ok":
                sys.meta_path.insert(0, _Finder())
            import dismech_newton as dm

            stats["import_pep563"] = "ok"
            stats.update(_smoke(dm, scene))
        except Exception as err:  # noqa: BLE001
            stats.setdefault("import_pep563", "ok" if "dismech_newton" in sys.modules
                             else _error_line(err))
            stats["smoke"] = _error_line(err)
        smoke = ("ran" if stats.get("smoke_finite") else
                 f"failed ({stats.get('smoke', 'non-finite positions')})")
        why = ""
        if "NameError" in stats.get("smoke", "") and "View" in stats.get("smoke", ""):
            why = (": Warp evaluates the string annotations of kernels that name a kernel "
                   "factory's parameter (element.py: 'v: View'), which a string cannot see, "
                   "so the package needs Python >= 3.14's deferred annotations (PEP 649)")
        stats["error"] = (
            f"not run: as released it does not import on Python {stats['python']} "
            f"({stats['import_as_released']}); its unchanged source compiled with postponed "
            f"annotations (PEP 563) imports ({stats['import_pep563']}) and a 5-step clamped-rod "
            f"smoke test {smoke}{why}; the tie path needs the rest length shrunk during the "
            "run, which dismech-newton bakes into per-edge/per-triplet arrays at build time "
            "(no public API)")
    tmp = argv[1] + ".tmp.npz"
    np.savez(tmp, stats=json.dumps(stats))
    os.replace(tmp, argv[1])
    print(json.dumps(stats))
    return 0


if __name__ == "__main__":
    sys.exit(main())
