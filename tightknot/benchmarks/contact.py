"""What self-contact adds to a Newton iteration (the contact issue's speed target).

Scene: the study's tight open trefoil (125 mm, 300 vertices, pulled by 7.43 N to Lambda_OC
about 10.1). From that equilibrium the pull is raised by 10 % (``REPULL``), and the first
Newton iteration of that load step (a real step: the residual of the new load, the
equilibrium's contacts) is timed piece by piece, each the minimum over repeats (the machines
are shared: the minimum is the least disturbed run):

- ``elastic_s``: stretch, bend and twist energy, gradient and Hessian (Warp);
- ``contact_s``: the contact layer's detection (BVH broad phase, candidate pairs) and its
  energy, gradient and Hessian added into the system's CSC data, plus the combination with
  the elastic part into one matrix: the whole system evaluation minus ``elastic_s``;
- ``step_bound_s``: the continuous collision bound of that step (no passing through);
- ``solve_s``: sparse LU and solve of the Hessian with contact couplings;
- ``solve_no_contact_s``: the same for the elastic Hessian alone.

The target reads: contact detection plus contact assembly add at most 50 % to a Newton
iteration, i.e. ``(contact_s + step_bound_s) / (elastic_s + solve_s) <= 0.5``; the
fill-in that contact couplings bring into the factorization is reported apart, as
``solve_s / solve_no_contact_s`` (it is the linear solver's cost, not the layer's).

The same load step is then solved to equilibrium with the layer's calls timed
(``in_solve``): the time inside the contact layer (evaluation and step bound, every call
of the Newton iterations and their line searches) over the rest of the solve, a check of
the piecewise ratio on a whole solve (line searches evaluate energies without Hessians, so
the two differ).

"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np

#: The tight open knot of the study: rest length [m], pulling force [N], vertices.
SCENE = {"rest_length_m": 0.125, "pull_force_N": 7.43, "vertices": 300}

#: The timed load step raises the pull from F to REPULL F.
REPULL = 1.10


def _best(f: Callable[[], Any], repeats: int) -> float:
    f()
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return float(best)


def _pull_system(scene: Any, state: Any, force: float, contact: bool) -> Any:
    """The scene's pull system at ``state``: the force ramps from ``force`` to
    REPULL ``force`` [N] on the load parameter (as tie()'s pull phase does)."""
    from tightknot.knots.scenes import end_vertex, gauge
    from tightknot.solvers.system import RodSystem

    bcs = gauge(scene, positions=state.x)
    shrink = 1.0 / scene.start_length_ratio  # tie()'s rest length L0 (its tighten phase)
    bcs.rest_length_scale((shrink, shrink))
    axis = scene.pull_axis
    bcs.force(0, end_vertex(scene), lambda t: force * REPULL**t * axis)
    system = RodSystem(scene.model, state.copy(), bcs)
    if contact:
        system.add_term(scene.contact)
    return system


class _Timed:
    """Wraps the contact layer's per-iteration methods with a stopwatch [s]."""

    NAMES = ("evaluate", "evaluate_into", "max_step")

    def __init__(self, layer: Any) -> None:
        self.layer = layer
        self.seconds = 0.0
        self.calls = 0
        for name in self.NAMES:
            setattr(layer, name, self._wrap(getattr(layer, name)))

    def _wrap(self, f: Callable) -> Callable:
        def timed(*args: Any, **kwargs: Any) -> Any:
            t0 = time.perf_counter()
            try:
                return f(*args, **kwargs)
            finally:
                self.seconds += time.perf_counter() - t0
                self.calls += 1
        return timed

    def remove(self) -> None:
        for name in self.NAMES:
            delattr(self.layer, name)  # back to the class's methods


def run(vertices: int = 300, repeats: int = 30, device: str = "cpu") -> dict:
    """Tie the tight open trefoil with ``vertices`` vertices, time the parts of the first
    Newton iteration of a 10 % higher pull, then that load step's whole solve (seconds)."""
    from tightknot.knots.open_measures import lambda_oc
    from tightknot.knots.scenes import open_trefoil
    from tightknot.loading.tie import tie
    from tightknot.solvers.continuation import ContinuationOptions, continuation
    from tightknot.solvers.linear import factorize

    if vertices < 60:
        raise ValueError(f"vertices must be >= 60 (a trefoil of 125 mm), got {vertices}")
    scene = open_trefoil(SCENE["rest_length_m"], nodes=vertices, device=device)
    t0 = time.perf_counter()
    res = tie(scene, pull_force=SCENE["pull_force_N"], tighten_steps=20, pull_steps=20).run()
    tie_s = time.perf_counter() - t0
    if not res.converged:
        raise RuntimeError(f"the benchmark scene did not converge: {res.failure}")
    st = res.system.state
    force = SCENE["pull_force_N"]
    full = _pull_system(scene, st, force, True)
    bare = _pull_system(scene, st, force, False)
    for s_ in (full, bare):
        s_.set_load(1.0)  # the new load at the old equilibrium: a real first step
    u = full.free_vector()
    _, g, h_full = full.evaluate(u)
    _, _, h_bare = bare.evaluate(u)
    du = factorize(h_full).solve(-g)
    dx = full.positions(u + du) - full.positions(u)
    elastic = _best(lambda: bare.evaluate(u), repeats)
    system = _best(lambda: full.evaluate(u), repeats)
    step = _best(lambda: full.max_step(u, du), repeats)
    solve = _best(lambda: factorize(h_full).solve(g), repeats)
    solve0 = _best(lambda: factorize(h_bare).solve(g), repeats)
    contact = max(system - elastic, 0.0)
    pairs = scene.contact.last_pairs.shape[0]
    active = int(np.count_nonzero(scene.contact.last_overlap > 0.0))
    overhead = (contact + step) / (elastic + solve)
    # The whole load step, the layer's calls timed.
    again = _pull_system(scene, st, force, True)
    timer = _Timed(scene.contact)
    try:
        t1 = time.perf_counter()
        sol = continuation(again, ContinuationOptions(steps=1)).run()
        solve_wall = time.perf_counter() - t1
    finally:
        timer.remove()
    rest_s = max(solve_wall - timer.seconds, 1e-12)
    return {
        "scene": dict(SCENE, vertices=vertices),
        "lambda_oc": lambda_oc(st.x, scene.diameter),
        "tie_s": tie_s,
        "timed_step": f"pull {force} N -> {REPULL * force:.4g} N, first Newton iteration",
        "step_max_vertex_move_over_D0": float(np.linalg.norm(dx, axis=1).max()
                                              / scene.diameter),
        "candidate_pairs": pairs,
        "interacting_pairs": active,
        "elastic_s": elastic,
        "contact_s": contact,
        "step_bound_s": step,
        "solve_s": solve,
        "solve_no_contact_s": solve0,
        "iteration_s": elastic + contact + step + solve,
        "contact_overhead": overhead,
        "target_overhead": 0.5,
        "passed": bool(overhead <= 0.5),
        "solve_fill_ratio": solve / solve0,
        "hessian_nnz": int(h_full.nnz),
        "hessian_nnz_no_contact": int(h_bare.nnz),
        "in_solve": {
            "converged": bool(sol.converged),
            "newton_iterations": int(sol.newton_iterations),
            "wall_s": solve_wall,
            "contact_layer_s": timer.seconds,
            "contact_layer_calls": timer.calls,
            "contact_overhead": timer.seconds / rest_s,
        },
    }


# -- command line (``tightknot bench contact``) ---------------------------------------------
_EXAMPLES = """examples:
  tightknot bench contact --json contact.json
  tightknot bench contact --vertices 600
"""


def register(subparsers: Any) -> None:
    """Add ``tightknot bench contact``."""
    p = subparsers.add_parser(
        "contact", help="what self-contact adds to a Newton iteration (tight open trefoil)",
        description=__doc__, epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", metavar="FILE", help="write the result as JSON")
    p.add_argument("--vertices", type=int, default=SCENE["vertices"],
                   help="vertices of the knot (default 300)")
    p.add_argument("--repeats", type=int, default=30, help="timing repeats (minimum kept)")
    p.add_argument("--device", default=None, help="Warp device (default cpu)")
    p.set_defaults(handler=_command)


def _command(args: argparse.Namespace) -> int:
    from tightknot.atomic import writable_file, write_json_atomic
    from tightknot.warp_setup import resolve_device

    out = writable_file(args.json)
    if args.repeats < 1:
        raise ValueError(f"--repeats must be >= 1, got {args.repeats}")
    r = run(args.vertices, args.repeats, resolve_device(args.device))
    print(f"tight open trefoil, {args.vertices} vertices, Lambda_OC {r['lambda_oc']:.2f}: "
          f"{r['candidate_pairs']} candidate pairs, {r['interacting_pairs']} interacting")
    for k in ("elastic_s", "contact_s", "step_bound_s", "solve_s", "solve_no_contact_s",
              "iteration_s"):
        print(f"  {k:20s} {r[k] * 1e3:8.3f} ms")
    print(f"  contact overhead {r['contact_overhead']:.2f} (target <= 0.5): "
          f"{'met' if r['passed'] else 'MISSED'}; LU with/without contact "
          f"{r['solve_fill_ratio']:.1f}x")
    ins = r["in_solve"]
    print(f"  whole load step: {ins['newton_iterations']} Newton iterations in "
          f"{ins['wall_s']:.3f} s, {ins['contact_layer_s']:.3f} s in the contact layer "
          f"({ins['contact_layer_calls']} calls): overhead {ins['contact_overhead']:.2f}")
    if out is not None:
        write_json_atomic(out, r)
    return 0
