"""How far the sectioned level's partition of unity over a partner's edges is from one at
the samples in contact (docs/sectioned_level.md, "The partner's partition of unity on a
bent partner").

    python bench/partition_sum.py [--knots closed 125 185] [--json out.json]

The contact energy of a sample of edge A sums one pass per partner edge B, each weighed by
B's partition weight. The level's first weight, B's hat omega(v) of the sample's projection
v on B's line (:func:`tightknot.contact.sectioned_reference.partition_weight`), sums to one
along a straight partner only: on a bent one the projections onto two consecutive edges
shift by about rho kappa / 2 each (rho the sample's distance from the partner's axis, kappa
its curvature), towards each other on the concave side and apart on the convex one. The
weight the level uses now (:func:`tightknot.contact.sectioned_reference.partition`) is
the difference of two steps in the signed distances from planes through B's vertices
normal to its chords, which consecutive edges share, so that the weights telescope to one
on any polyline. Part 1 evaluates both sums at points 0.97 R from a polyline bent at
kappa R (12 edges per D0, the cross-check's resolution); part 2 reads the level's sum at
every sample in contact of the study's knots tied at the sectioned level
(:meth:`tightknot.contact.sectioned.SectionedLayer.weight_sums`), with the mean weighed
by each sample's penetration (below one only where the exclusion ramp of a rod's own
contacts or an open end's fade lowers it).
"""

from __future__ import annotations

import argparse
import math
import time
from typing import Any

import numpy as np

from tightknot.contact.sectioned_reference import partition, partition_weight


def bent_partner(kappa_r: float, side: int, samples: int = 25,
                 edges_per_d0: int = 12) -> dict[str, tuple[float, float]]:
    """The least and largest sum over a partner polyline's edges of the projection hats
    (``hats``) and of the chord partition (``chords``), at points 0.97 R from the polyline
    of curvature ``kappa_r`` / R, on its concave (``side`` +1) or convex (-1) side, along
    one edge (D0 = 1)."""
    r, h = 0.5, 1.0 / edges_per_d0
    k = np.arange(-20, 21)
    if kappa_r == 0.0:
        pts = np.c_[k * h, np.zeros(k.size), np.zeros(k.size)]
    else:
        rc = r / kappa_r  # the partner axis's bend radius, its centre at (0, rc)
        pts = np.c_[rc * np.sin(k * h / rc), rc - rc * np.cos(k * h / rc), np.zeros(k.size)]
    hats, chords = [], []
    for s in np.linspace(0.0, h, samples):
        if kappa_r == 0.0:
            p = np.array([s, side * 0.97 * r, 0.0])
        else:
            a = s / rc
            inward = np.array([-math.sin(a), math.cos(a), 0.0])
            p = (np.array([rc * math.sin(a), rc - rc * math.cos(a), 0.0])
                 + side * 0.97 * r * inward)
        hat, chord = 0.0, 0.0
        for j in range(1, pts.shape[0] - 2):
            a0, a1 = pts[j], pts[j + 1]
            e = a1 - a0
            v = float((p - a0) @ e / (e @ e))
            if -0.5 <= v <= 1.5:
                hat += float(partition_weight(np.array(v), False, False)[0])
            chord += partition(p, pts[j - 1], a0, a1, pts[j + 2], False, False)[0]
        hats.append(hat)
        chords.append(chord)
    return {"hats": (min(hats), max(hats)), "chords": (min(chords), max(chords))}


def knot_sums(which: str, nodes_closed: int = 100, nodes_open: int = 150) -> dict[str, Any]:
    """The sums of the hats at the samples in contact of one of the study's knots at the
    sectioned level (its default load path)."""
    from tightknot.contact.sectioned import SectionedLayer
    from tightknot.knots.scenes import closed_trefoil, open_trefoil
    from tightknot.loading.pull import tie_to_lambda
    from tightknot.loading.tie import tie

    start = time.perf_counter()
    if which == "closed":
        res = tie(closed_trefoil(16.37, nodes=nodes_closed, contact="sectioned"),
                  tighten_steps=20).run()
    else:
        length, target = {"125": (0.125, 10.1), "185": (0.185, 15.0)}[which]
        res = tie_to_lambda(open_trefoil(length, nodes=nodes_open, contact="sectioned"),
                            target).run()
    system = res.system
    layer = next(t for t in system.extra_terms if isinstance(t, SectionedLayer))
    st = system.state
    x = layer.boundary_centres(st.x, system.rest)
    sums, pens = layer.weight_sums(x, st.extra, st.frames, system.rest)
    return {"knot": which, "converged": bool(res.converged), "samples_in_contact": int(sums.size),
            "percentiles_5_25_50_75_95": np.percentile(sums, [5, 25, 50, 75, 95]).tolist(),
            "min": float(sums.min()), "max": float(sums.max()),
            "penetration_weighted_mean": float(np.sum(sums * pens) / np.sum(pens)),
            "wall_time_s": time.perf_counter() - start}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--knots", nargs="*", default=["closed", "125", "185"],
                    choices=["closed", "125", "185"])
    ap.add_argument("--json", metavar="F", help="write the results here")
    args = ap.parse_args(argv)
    out: dict[str, Any] = {"bent_partner": [], "knots": []}
    print("kappa R | weight | concave side: least .. largest sum | convex side")
    for kr in (0.0, 0.1, 1.0 / 3.0, 0.67):
        cc, cv = bent_partner(kr, +1), bent_partner(kr, -1)
        out["bent_partner"].append({"kappa_r": kr, "concave": cc, "convex": cv})
        for kind in ("hats", "chords"):
            print(f"{kr:7.3f} | {kind:6s} | {cc[kind][0]:.3f} .. {cc[kind][1]:.3f} | "
                  f"{cv[kind][0]:.3f} .. {cv[kind][1]:.3f}")
    for which in args.knots:
        row = knot_sums(which)
        out["knots"].append(row)
        p = row["percentiles_5_25_50_75_95"]
        print(f"{which}: {row['samples_in_contact']} samples in contact, sums 5/25/50/75/95 % "
              f"{p[0]:.2f} / {p[1]:.2f} / {p[2]:.2f} / {p[3]:.2f} / {p[4]:.2f} (least "
              f"{row['min']:.2f}, largest {row['max']:.2f}), weighed by penetration "
              f"{row['penetration_weighted_mean']:.2f}; {row['wall_time_s']:.0f} s")
    if args.json:
        from tightknot.atomic import write_json_atomic

        write_json_atomic(args.json, out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
