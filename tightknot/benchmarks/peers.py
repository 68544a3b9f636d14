"""``tightknot bench peers``: the open-trefoil pull scene in tightknot and in other rod codes.

The scene (physics.md sec. 1, issue 7): E = 1.25 MPa, nu = 0.5, D0 = 8.5 mm, L0 = 185 mm,
frictionless, tied from tightknot's loose open trefoil by shrinking the rest length to L0
(the last end following the shrink along the pull axis), then the ends moved to the same
end-to-end distance X, and equilibrium. Every code starts from the same curve (tightknot's
start, resampled to the same vertex count) and every final centerline is measured here by
the same tightknot functions:

- ``min_gap_over_D0``: smallest non-local centerline distance (pairs farther apart along the
  rod than pi D0 / 2, :func:`tightknot.knots.curves.min_nonlocal_distance`) over D0; the
  nominal tubes overlap by ``penetration_over_D0 = max(0, 1 - min_gap_over_D0)``. In tightknot
  that overlap is the modelled flattening of the cross-sections (radial-compliance law); in
  PyElastica it is the penalty spring's overlap.
- ``knot_type``: Alexander polynomial of the centerline closed by a far-away arc.
- ``kappa_profile_rms_diff``: RMS over normalised arc length S/L of kappa D0 (Bergou vertex
  curvature) of the peer minus tightknot's, both interpolated on 1001 points.

The peers run in subprocesses from ``bench/peers/`` of a source checkout (they never import
tightknot; the scene travels as an ``.npz``): PyElastica in this interpreter (``pip install
tightknot[peers]``), dismech-newton in its own environment (``--dismech-python``). A peer
that is missing or fails gives a row with an ``error`` string; the benchmark still succeeds.

X defaults to 0.120 m: just above the end distance at which a pull of the tightened knot
loses it, so a tight knot near the tightest ideal open trefoil (Lambda_OC 12.4)
(docs/design_notes.md, peers).
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

#: The scene (physics.md sec. 1).
REST_LENGTH = 0.185
#: End-to-end distance X [m] every code is brought to (module docstring: how it was chosen).
END_DISTANCE = 0.120
#: Vertex count of every code (PyElastica's explicit steps cost O(n^2) per second simulated:
#: dt ~ dl^2 and an all-pairs contact loop; 101 vertices keep its run to minutes).
VERTICES = 101
#: Target of the issue: tightknot at least this many times faster than PyElastica.
SPEEDUP_TARGET = 100.0
#: Normalised arc-length samples of the curvature comparison.
PROFILE_SAMPLES = 1001

PEERS = ("pyelastica", "dismech-newton")
DEFAULT_DISMECH_PYTHON = "/tmp/dmvenv/bin/python"


def peers_dir() -> Path:
    """``bench/peers`` of the source checkout tightknot is installed from (editable)."""
    import tightknot

    return Path(tightknot.__file__).resolve().parents[1] / "bench" / "peers"


def start_curve(vertices: int, rest_length: float = REST_LENGTH) -> tuple[np.ndarray, float]:
    """tightknot's loose open-trefoil start [m], resampled (uniformly in arc length) to
    ``vertices``, and its D0 [m]. The scene is built at 300 vertices (its default), so the
    start curve is the same whatever the count."""
    from tightknot.knots import curves
    from tightknot.knots.scenes import open_trefoil

    scene = open_trefoil(rest_length, nodes=300)
    x = scene.model.vertex_initial_position
    return curves.resample_uniform(x, int(vertices), closed=False), scene.diameter


def measure(x: np.ndarray, diameter: float, rest_length: float,
            poisson_ratio: float = 0.5) -> dict:
    """Measurements of a final open-knot centerline ``x`` (N, 3) [m] of uniform rest edges
    (rest_length / (N - 1)): min gap, penetration, knot type, Lambda_OC, the kappa profile."""
    from tightknot.knots import curves, topology
    from tightknot.knots.curvature import bergou_curvature
    from tightknot.knots.open_measures import lambda_oc

    x = np.asarray(x, dtype=float)
    if not np.isfinite(x).all():
        return {"min_gap_over_D0": None, "penetration_over_D0": None,
                "knot_type": "undefined (non-finite positions)", "lambda_oc": None}
    gap, _, _ = curves.min_nonlocal_distance(x, False, curves.exclusion_arc_length(diameter))
    try:
        kt = topology.knot_type(topology.close_open_curve(x))
    except ValueError as err:  # TopologyError: no generic projection
        kt = f"undefined ({err})"
    # Deformed radii r0 lam^-nu (physics.md sec. 4), as tightknot's summaries measure Lambda_OC.
    lam = np.linalg.norm(np.diff(x, axis=0), axis=1) / (rest_length / (len(x) - 1))
    r_e = 0.5 * diameter * lam ** (-poisson_ratio)
    r_v = np.r_[r_e[0], 0.5 * (r_e[1:] + r_e[:-1]), r_e[-1]]
    lam_oc = lambda_oc(x, diameter, r_v)
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))]
    return {
        "min_gap_over_D0": float(gap / diameter),
        "penetration_over_D0": float(max(0.0, 1.0 - gap / diameter)),
        "knot_type": kt,
        "lambda_oc": None if math.isnan(lam_oc) else float(lam_oc),
        "end_distance_m": float(np.linalg.norm(x[-1] - x[0])),
        "length_over_L0": float(s[-1] / rest_length),
        "_profile": (s / s[-1], bergou_curvature(x, False) * diameter),
    }


def profile_rms_diff(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray],
                     samples: int = PROFILE_SAMPLES) -> float:
    """RMS of kappa D0 (a minus b) over normalised arc length in [0, 1] (linear interpolation
    of each vertex profile on ``samples`` points)."""
    u = np.linspace(0.0, 1.0, samples)
    return float(np.sqrt(np.mean((np.interp(u, *a) - np.interp(u, *b)) ** 2)))


def tightknot_row(vertices: int = VERTICES, end_distance: float = END_DISTANCE,
                  rest_length: float = REST_LENGTH) -> tuple[dict, np.ndarray]:
    """Tie the scene in tightknot (:func:`tightknot.loading.tie.tie` with ``end_distance``);
    the row and the final centerline [m]. Steps = Newton iterations (each a sparse solve)."""
    from tightknot.knots.scenes import open_trefoil
    from tightknot.loading.tie import tie

    w0, c0 = time.perf_counter(), time.process_time()
    scene = open_trefoil(rest_length, nodes=int(vertices))
    res = tie(scene, end_distance=end_distance, tighten_steps=20, pull_steps=20).run()
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    x = res.system.state.x.copy()
    row = {"code": "tightknot", "wall_time_s": wall, "cpu_time_s": cpu,
           "steps": int(res.newton_iterations), "vertices": int(vertices),
           "load_steps": sum(len(p.steps) for p in res.phases.values()),
           "converged": bool(res.converged), "status": res.failure or "equilibrium",
           "criterion": "Newton residual below 1e-6 (scaled) at every load step",
           "pull_force_N": float(res.pull_force_N)}
    if not res.converged:
        row["error"] = f"tightknot did not reach equilibrium: {res.failure}"
    row.update(measure(x, scene.diameter, rest_length))
    return row, x


def _scene_file(folder: Path, start: np.ndarray, diameter: float, end_distance: float,
                rest_length: float) -> Path:
    from tightknot.knots.scenes import STUDY_MATERIAL as mat

    path = folder / "scene.npz"
    np.savez(path, start=start, rest_length=rest_length, diameter=diameter,
             youngs_modulus=mat.youngs_modulus, poisson_ratio=mat.poisson_ratio,
             density=mat.density, end_distance=end_distance)
    return path


def _peer_row(code: str, python: str, script: Path, scene: Path, folder: Path,
              extra: list[str], timeout: float, diameter: float, rest_length: float) -> dict:
    """Run one peer driver in a subprocess; its row (with ``error`` when it failed)."""
    row: dict = {"code": code}
    if not script.is_file():
        row["error"] = f"peer driver not found: {script} (run from a source checkout)"
        return row
    if not Path(python).exists():
        row["error"] = f"no Python for {code} at {python} (see bench/peers/README.md)"
        return row
    out = folder / f"{code}.npz"
    cmd = [python, str(script), str(scene), str(out), *extra]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        row["error"] = f"{code} ran past the {timeout:g} s limit"
        return row
    if proc.returncode != 0 or not out.is_file():
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-3:]
        row["error"] = f"{code} failed (exit {proc.returncode}): " + " | ".join(tail)
        return row
    with np.load(out) as z:
        stats = json.loads(str(z["stats"]))
        final = z["final"] if "final" in z.files else None
    row.update({k: v for k, v in stats.items() if k != "code"})
    if final is None:
        row.setdefault("error", f"{code} returned no centerline")
        return row
    if not stats.get("converged", False):
        row.setdefault("note", f"not at equilibrium: {stats.get('status')}")
    row.update(measure(final, diameter, rest_length))
    return row


def run(peers: tuple[str, ...] = PEERS, vertices: int = VERTICES,
        end_distance: float = END_DISTANCE, rest_length: float = REST_LENGTH,
        pyelastica_args: list[str] | None = None, dismech_python: str | None = None,
        timeout: float = 1800.0) -> dict:
    """All rows and the speed-ups (peer wall time over tightknot's, measured in this run)."""
    tk, _ = tightknot_row(vertices, end_distance, rest_length)
    rows = [tk]
    start, d0 = start_curve(vertices, rest_length)
    with tempfile.TemporaryDirectory(prefix="tightknot-peers-") as tmp:
        folder = Path(tmp)
        scene = _scene_file(folder, start, d0, end_distance, rest_length)
        for code in peers:
            if code == "pyelastica" and importlib.util.find_spec("elastica") is None:
                rows.append({"code": code, "error": "pyelastica is not installed "
                             "(pip install -e .[peers], see bench/peers/README.md)"})
            elif code == "pyelastica":
                rows.append(_peer_row(code, sys.executable, peers_dir() / "pyelastica_pull.py",
                                      scene, folder, list(pyelastica_args or []), timeout, d0,
                                      rest_length))
            elif code == "dismech-newton":
                py = dismech_python or os.environ.get("TIGHTKNOT_DISMECH_PYTHON",
                                                      DEFAULT_DISMECH_PYTHON)
                rows.append(_peer_row(code, py, peers_dir() / "dismech_pull.py", scene,
                                      folder, [], timeout, d0, rest_length))
            else:
                raise ValueError(f"unknown peer {code!r}: choose from {', '.join(PEERS)}")
    ref = tk.get("_profile")
    speedup: dict = {}
    speedup_cpu: dict = {}
    lower_bound: dict = {}
    at_tolerance: dict = {}
    for r in rows:
        prof = r.pop("_profile", None)
        if r["code"] == "tightknot":
            r["kappa_profile_rms_diff"] = 0.0
        else:
            r["kappa_profile_rms_diff"] = (profile_rms_diff(prof, ref)
                                           if prof is not None and ref is not None else None)
            ok = "error" not in r and r.get("wall_time_s") and "error" not in tk
            speedup[r["code"]] = r["wall_time_s"] / tk["wall_time_s"] if ok else None
            cpu_ok = ok and r.get("cpu_time_s") and tk.get("cpu_time_s")
            speedup_cpu[r["code"]] = r["cpu_time_s"] / tk["cpu_time_s"] if cpu_ok else None
            # A peer stopped by its time limit before its criterion: its time is a lower bound.
            lower_bound[r["code"]] = bool(ok) and not r.get("converged", False)
            if ok and r.get("tolerance_first_met"):
                at_tolerance[r["code"]] = {
                    tol: {"wall": v["wall_time_s"] / tk["wall_time_s"],
                          "cpu": v["cpu_time_s"] / tk["cpu_time_s"], "steps": v["steps"]}
                    for tol, v in r["tolerance_first_met"].items()}
    # CPU-time ratios beside the wall-time ones: the machines are shared, and CPU time is
    # less disturbed by other jobs (both codes run single-threaded here).
    result = {"rows": rows, "speedup_vs": speedup, "speedup_cpu_vs": speedup_cpu,
              "speedup_is_lower_bound": lower_bound,
              "speedup_at_looser_tolerance_m_s": at_tolerance,
              "scene": {"rest_length_m": rest_length, "diameter_m": d0,
                        "youngs_modulus_Pa": 1.25e6, "poisson_ratio": 0.5,
                        "end_distance_m": end_distance, "vertices": int(vertices),
                        "friction": 0.0}}
    pe = next((r for r in rows if r["code"] == "pyelastica" and "error" not in r), None)
    if pe is not None:
        result["targets"] = {
            "speedup_vs_pyelastica_min": SPEEDUP_TARGET,
            "speedup_met": speedup["pyelastica"] >= SPEEDUP_TARGET,
            "penetration_not_larger": tk["penetration_over_D0"] <= pe["penetration_over_D0"],
            "knot_type_kept": tk["knot_type"] == "3_1",
            "pyelastica_knot_type_kept": pe["knot_type"] == "3_1",
        }
    return result


# -- command line (``tightknot bench peers``) ------------------------------------------------
_EXAMPLES = """examples:
  tightknot bench peers --json peers.json
  tightknot bench peers --peers pyelastica --pyelastica-arg=--t-max=2
  tightknot bench peers --peers            (tightknot's row alone)
install the peers: pip install -e .[peers]; dismech-newton: see bench/peers/README.md
"""


def register(subparsers) -> None:  # noqa: ANN001 (argparse's private subparsers type)
    """Add ``tightknot bench peers``."""
    import argparse

    p = subparsers.add_parser(
        "peers", help="the open-trefoil pull in tightknot, PyElastica and dismech-newton",
        description="The same open-trefoil pull scene in tightknot and in peer rod codes: "
        "wall time to equilibrium, steps, min gap / D0, knot type, curvature-profile "
        "difference from tightknot.",
        epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", metavar="FILE", help="write the result as JSON")
    p.add_argument("--peers", nargs="*", default=list(PEERS), metavar="PEER",
                   help=f"peers to run (default: {' '.join(PEERS)}; none: tightknot alone)")
    p.add_argument("--vertices", type=int, default=VERTICES,
                   help=f"vertices of every code (default {VERTICES}; the start curve "
                   "needs about >= 82)")
    p.add_argument("--end-distance", type=float, default=END_DISTANCE,
                   help=f"end-to-end distance X [m] (default {END_DISTANCE})")
    p.add_argument("--pyelastica-arg", action="append", default=[], metavar="ARG",
                   help="extra argument for bench/peers/pyelastica_pull.py (repeatable)")
    p.add_argument("--dismech-python", default=None, metavar="PATH",
                   help="Python of the dismech-newton environment "
                   f"(default $TIGHTKNOT_DISMECH_PYTHON or {DEFAULT_DISMECH_PYTHON})")
    p.add_argument("--timeout", type=float, default=1800.0,
                   help="seconds allowed to each peer (default 1800)")
    p.set_defaults(handler=_command)


def _command(args) -> int:  # noqa: ANN001
    from tightknot.atomic import writable_file, write_json_atomic

    out = writable_file(args.json)
    if args.vertices < 40:
        raise ValueError(f"--vertices must be >= 40 (an open trefoil's minimum), got "
                         f"{args.vertices}")
    if not (math.isfinite(args.end_distance) and 0.0 < args.end_distance < REST_LENGTH):
        raise ValueError(f"--end-distance must be in (0, {REST_LENGTH}) m, got "
                         f"{args.end_distance!r}")
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        raise ValueError(f"--timeout must be > 0 s, got {args.timeout!r}")
    bad = [p for p in args.peers if p not in PEERS]
    if bad:
        raise ValueError(f"--peers: unknown {', '.join(bad)} (choose from {', '.join(PEERS)})")
    result = run(tuple(args.peers), args.vertices, args.end_distance,
                 pyelastica_args=args.pyelastica_arg, dismech_python=args.dismech_python,
                 timeout=args.timeout)
    for r in result["rows"]:
        if "error" in r and r["code"] != "tightknot":
            print(f"{r['code']:>15s}: error: {r['error']}")
            continue
        gap = r.get("min_gap_over_D0")
        print(f"{r['code']:>15s}: {r['wall_time_s']:9.2f} s wall, {r['steps']:>8d} steps, "
              f"min gap/D0 {gap:.3f}, knot {r['knot_type']}, Lambda_OC {r.get('lambda_oc')}, "
              f"kappa RMS diff {r['kappa_profile_rms_diff']:.3f}, {r.get('status')}")
    for code, x in result["speedup_vs"].items():
        xc = result["speedup_cpu_vs"].get(code)
        bound = " (lower bound: the peer hit its time limit)" if result[
            "speedup_is_lower_bound"].get(code) else ""
        print(f"speed-up vs {code}: " + ("n/a" if x is None else
                                          f"{x:.1f}x wall, {xc or float('nan'):.1f}x CPU{bound}"))
        for tol, v in result["speedup_at_looser_tolerance_m_s"].get(code, {}).items():
            print(f"  stopping {code} at {tol} m/s: {v['wall']:.1f}x wall, {v['cpu']:.1f}x CPU "
                  f"({v['steps']} steps)")
    if out is not None:
        write_json_atomic(out, result)
    return 0
