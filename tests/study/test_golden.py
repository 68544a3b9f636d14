"""Golden regression: the canonical runs' curvature profiles against tests/golden/.

Regenerated only by ``python -m tightknot.study.golden --write``. The open knots are pulled
by a fixed force (one equilibrium), but a knot in an open rod can slide along it at almost
no cost, so where it settles along the rod moves with round-off of the path (by up to one
edge, 0.15 D0, between solver versions here). Profiles are therefore compared as functions
of s centred on the knot (interpolated onto the golden grid), not vertex by vertex:
re-sampling a spike of the open 185 mm knot one edge off moved kappa D0 by 0.026 at most
(RMS 0.013), so 0.04 (max) and 0.02 (RMS) separate that from a physics change (a change of
law or discretisation moved kappa D0 by 0.05 to 0.3). The open scenes are also symmetric under
the half turn that swaps the rod's two ends, and a knot that settles half an edge off the middle
has two equilibria, mirror images under that turn: which one a run reaches is round-off too (a
change of numpy/scipy build landed the 185 mm knot on the golden's mirror image, equal to it
reversed end for end to 1e-12). An open profile is therefore compared with the golden and with
the golden read from the other end, and the nearer one counts. A closed knot slides along
its rod too (a near-zero mode with shallow minima a fraction of an edge apart: a change of
the step bound moved the 100-vertex trefoil by 0.2 edges and its kappa D0 by up to 0.06 at
single vertices, its stretch by 3e-6), but no round-off has moved it between runs, so its
profile is compared vertex by vertex: a change of path must be looked at and the golden
regenerated with the reason. Headline numbers: 1e-3 in stretch and 0.05 in Lambda_OC and
L/D (solver tolerance moves them by 1e-4).
"""

import json
from pathlib import Path

import numpy as np
import pytest

from tightknot.study.golden import CANONICAL, TARGET_LAMBDA, profile, run_canonical

GOLDEN = Path(__file__).resolve().parents[1] / "golden"


@pytest.mark.parametrize("name", list(CANONICAL))
def test_profile_matches_golden(name: str) -> None:
    gold = json.loads((GOLDEN / f"{name}.json").read_text())
    now = profile(run_canonical(name))
    s0, k0 = np.asarray(gold["s"]), np.asarray(gold["kappa"])
    s1, k1 = np.asarray(now["s"]), np.asarray(now["kappa"])
    assert len(k1) == len(k0)
    if "lambda_oc" in gold:
        inside = np.abs(s0) <= gold["lambda_oc"]  # the knot and a knot length of tail
        # The golden as measured, and read from the other end (its mirror image, see above).
        diff = min((np.interp(s0[inside], s1, k1) - k0[inside],
                    np.interp(s0[inside], -s1[::-1], k1[::-1]) - k0[inside]),
                   key=lambda d: float(np.max(np.abs(d))))
        assert np.max(np.abs(diff)) <= 0.04
        assert np.sqrt(np.mean(diff**2)) <= 0.02
        assert now["lambda_oc"] == pytest.approx(gold["lambda_oc"], abs=0.05)
        # The canonical forces bring the knots near the study's Lambda_OC. Lambda_OC is read
        # off the contact set, whose two ends move by whole vertices (an edge is 0.15 D0 at
        # 100 and 150 vertices), so a fixed force lands within 0.2 plus one edge at each end
        # (measured: 10.01 at 7.43 N, 15.03 at 1.8 N). The issue's own check, a pull to
        # Lambda_OC within 0.2, is tie_to_lambda's (test_tie).
        edge = now["s"][1] - now["s"][0]
        assert now["lambda_oc"] == pytest.approx(TARGET_LAMBDA[name], abs=0.2 + 2.0 * edge)
    else:
        assert np.allclose(s1, s0, atol=1e-6)
        assert np.max(np.abs(k1 - k0)) <= 2e-3  # vertex by vertex (see above)
    assert now["stretch"] == pytest.approx(gold["stretch"], abs=1e-3)
    assert now["L_over_D"] == pytest.approx(gold["L_over_D"], abs=0.05)
