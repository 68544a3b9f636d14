"""How many section modes a squeeze needs: the section between two plates against the FEM.

Runs the FEM's plane-strain squeeze (``tightknot.fem.scenes.squeeze``, coarse, medium and fine
meshes, per-side approach up to 0.15 D0) and :class:`tightknot.contact.section_squeeze.
SectionSqueeze` with modes up to N at the same approaches, and prints, per N, the range over
the approaches w >= ``--w-min`` of the force, the contact fraction and the peak pressure
against the fine mesh, beside the FEM's own coarse-to-fine spread (docs/sectioned_level.md).

Usage::

    python bench/section_squeeze.py [--modes 4 8 12 16 24 32] [--w-min 0.026] [--json F]
"""

from __future__ import annotations

import argparse
import json
import time

from tightknot.contact.section_squeeze import SectionSqueeze
from tightknot.fem.scenes import squeeze

KEYS = {"force": "force_per_length_over_e_d0", "fraction": "contact_fraction_side",
        "pressure": "peak_pressure_mid_over_e"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, nargs="+", default=[4, 8, 12, 16, 24, 32])
    ap.add_argument("--w-min", type=float, default=0.026, help="smallest approach compared [D0]")
    ap.add_argument("--json", help="write the rows to this file")
    args = ap.parse_args()
    fem, times = {}, {}
    for mesh in ("coarse", "medium", "fine"):
        t = time.perf_counter()
        run = squeeze.run(mesh=mesh, max_approach_over_d0=0.3, steps=12, convergence=False)
        fem[mesh] = [s for s in run["steps"] if s["w_over_d0"] >= args.w_min - 1e-4]
        times[mesh] = time.perf_counter() - t
    fine = fem["fine"]
    ws = [s["w_over_d0"] for s in fine]

    def spread(key: str, rel: bool) -> float:
        return max(abs(c[key] / f[key] - 1.0) if rel else abs(c[key] - f[key])
                   for c, f in zip(fem["coarse"], fine, strict=True))

    print(f"FEM plane-strain squeeze, w/D0 = {ws[0]:.4f} .. {ws[-1]:.4f} ({len(ws)} levels); "
          f"wall time coarse/medium/fine {times['coarse']:.1f}/{times['medium']:.1f}/"
          f"{times['fine']:.1f} s")
    print(f"FEM coarse-to-fine spread: force {100 * spread(KEYS['force'], True):.1f} %, "
          f"contact fraction {spread(KEYS['fraction'], False):.3f}, peak pressure "
          f"{100 * spread(KEYS['pressure'], True):.1f} %")
    print("| N | dofs per edge (a_n, b_n) | F / F_FEM | L_c - L_c,FEM | p_max / p_max,FEM | "
          "time per level [ms] |")
    print("|---|---|---|---|---|---|")
    rows = []
    for n in args.modes:
        t = time.perf_counter()
        states = SectionSqueeze(n).path(ws)
        ms = 1e3 * (time.perf_counter() - t) / len(ws)
        f = [s.force_per_length_over_e_d0 / r[KEYS["force"]] for s, r in zip(states, fine,
                                                                           strict=True)]
        c = [s.contact_fraction_side - r[KEYS["fraction"]] for s, r in zip(states, fine,
                                                                          strict=True)]
        p = [s.peak_pressure_over_e / r[KEYS["pressure"]] for s, r in zip(states, fine,
                                                                         strict=True)]
        rows.append({"max_mode": n, "force_ratio": [min(f), max(f)],
                     "fraction_diff": [min(c), max(c)], "pressure_ratio": [min(p), max(p)],
                     "ms_per_level": ms})
        print(f"| {n} | {2 * (n - 1)} | {min(f):.3f} .. {max(f):.3f} | {min(c):+.3f} .. "
              f"{max(c):+.3f} | {min(p):.2f} .. {max(p):.2f} | {ms:.1f} |")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"w_over_d0": ws, "fem": fem, "rows": rows, "fem_wall_time_s": times},
                      fh, indent=1)


if __name__ == "__main__":
    main()
