"""One knot run's summary: what it reports about its own validity."""


def test_a_summary_says_when_it_leaves_the_calibrated_range() -> None:
    # A rod of nu = 0.3 under a law calibrated on an incompressible solid: the summary
    # carries the field and the warning; the tight 125 mm knot reports its deepest squeeze
    # against the law's calibrated approach.
    from tightknot.knots.scenes import closed_trefoil
    from tightknot.rods.material import Material
    from tightknot.study.run import run_knot

    run = run_knot(closed_trefoil(nodes=60, material=Material(1.25e6, 0.3, 1160.0)),
                   tighten_steps=20)
    s = run.summary
    assert s["outside_calibrated_range"] and any("Poisson ratio 0.3" in w for w in s["warnings"])
    assert 0.0 < s["max_approach_w_over_D0"] < s["calibrated_w_over_D0"]
    default = run_knot(closed_trefoil(nodes=60), tighten_steps=20).summary
    assert not default["outside_calibrated_range"] and default["warnings"] == []
