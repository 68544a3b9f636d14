"""The FEM judges the section modes: a section between two plates (tightknot.contact.
section_squeeze) against the FEM's plane-strain squeeze of the same section (coarse mesh).

Measured (docs/sectioned_level.md; bench/section_squeeze.py), at plate approaches
w >= 0.0167 D0 the force per length of N = 16 is within 1.5 % of the coarse and of the fine
mesh; N = 8 is within 3.3 % from w = 0.026 D0 but 7.7 % stiff at 0.0167 D0, where the patch is
too narrow for its shortest wavelength (pi D0 / 8). The FEM's own coarse-to-fine spread there
is at most 1.1 % in force and 0.008 in the contact fraction. The contact fraction of one side
(2 b over the perimeter) falls short by truncation of the Fourier series, by at most 0.053 at
N = 8 and 0.028 at N = 16 (w = 0.15 D0).
"""

import pytest

pytest.importorskip("felupe")

from tightknot.contact.section_squeeze import SectionSqueeze  # noqa: E402
from tightknot.fem.scenes import squeeze  # noqa: E402


@pytest.fixture(scope="module")
def fem_steps() -> list[dict]:
    run = squeeze.run(mesh="coarse", max_approach_over_d0=0.3, steps=12, convergence=False)
    return [s for s in run["steps"] if s["w_over_d0"] >= 0.0167 - 1e-4]


@pytest.mark.parametrize("max_mode, w_min, force_tol, width_tol",
                         [(8, 0.026, 0.045, 0.1), (16, 0.0167, 0.025, 0.05)])
def test_section_modes_carry_the_squeeze_of_the_fem(fem_steps: list[dict], max_mode: int,
                                                    w_min: float, force_tol: float,
                                                    width_tol: float) -> None:
    # Tolerances: the measured miss against this (coarse) mesh plus a margin of one percent,
    # the FEM's coarse-to-fine spread; 0.1 in the contact fraction is the target.
    steps = [s for s in fem_steps if s["w_over_d0"] >= w_min - 1e-4]
    states = SectionSqueeze(max_mode).path([s["w_over_d0"] for s in steps])
    assert len(states) >= 7
    for st, fem in zip(states, steps, strict=True):
        f_fem = fem["force_per_length_over_e_d0"]
        assert st.force_per_length_over_e_d0 == pytest.approx(f_fem, rel=force_tol), st.w_over_d0
        assert abs(st.contact_fraction_side - fem["contact_fraction_side"]) <= width_tol


def test_the_contact_width_converges_with_the_modes(fem_steps: list[dict]) -> None:
    # The shortfall of the width is the series' truncation: more modes, a wider patch.
    w = fem_steps[-1]["w_over_d0"]
    widths = [SectionSqueeze(n).solve(w)[0].contact_fraction_side for n in (8, 16, 32)]
    assert widths[0] < widths[1] < widths[2] < fem_steps[-1]["contact_fraction_side"] + 0.01
