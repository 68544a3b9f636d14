"""Measure the CC0 ideal trefoil as the study measured its knots (your own micro-CT
centerline goes the same way: tightknot.knots.centerline_io.read_centerline).

Run: python examples/analyze_ideal.py
"""

from tightknot.knots.ideal import load_ideal_trefoil
from tightknot.knots.measure import analyze_centerline


def main() -> dict:
    points = load_ideal_trefoil(diameter=1.0)
    rep = analyze_centerline(points, diameter=1.0, closed=True)
    print(f"knot {rep['knot_type']}  L/D={rep['L_over_D']:.4f}"
          f"  max kappa*D={rep['kappa_D0_max']:.3f}  spikes={rep['n_curvature_spikes']}"
          f"  double contact={rep['double_contact_fraction']:.3f}")
    return rep


if __name__ == "__main__":
    main()
