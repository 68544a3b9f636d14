"""Tie the study's closed trefoil and measure it next to the ideal knot.

Run: python examples/closed_trefoil.py [out.rrd]
"""

import sys

from tightknot.knots.scenes import closed_trefoil
from tightknot.study.run import run_knot
from tightknot.viz.rerun_log import make_logger


def main(rrd: str | None = None) -> dict:
    scene = closed_trefoil(l0_over_d0=16.37, nodes=80)  # the study's rod, coarse
    with make_logger(rrd) as log:
        run = run_knot(scene, log if rrd else None, "closed", [0], tighten_steps=40)
    s = run.summary
    print(f"knot {s['knot_type']}  converged={s['converged']}  stretch={s['stretch']:.4f}"
          f"  L/D={s['L_over_D']:.2f}  min gap={s['min_gap_over_D0']:.3f} D0"
          f"  min A/A0={s['min_area_ratio']:.3f}")
    return s


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
