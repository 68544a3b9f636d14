"""The FEM's plane-strain disk confirms the closed-form stiffness of the section's modes."""

import pytest

pytest.importorskip("felupe")

from tightknot.fem.section_modes import disk_mode_stiffness  # noqa: E402


@pytest.fixture(scope="module")
def coarse() -> dict[int, dict]:
    return {n: disk_mode_stiffness(n, [0.01, 0.2], mesh="coarse") for n in (2, 3, 4)}


def test_small_modes_have_the_closed_form_stiffness(coarse: dict[int, dict]) -> None:
    # At a = 0.01 R the solid is linear; the coarse disk (64 boundary nodes) is stiffer or
    # softer than the closed form by its discretisation error: 0.5, 1.1, 2.0 % for
    # n = 2, 3, 4, halved on the medium mesh. 3 % holds the coarse mesh's error for n <= 4.
    for n, result in coarse.items():
        assert result["levels"][0]["stiffness_over_linear"] == pytest.approx(1.0, abs=0.03), n


def test_the_disk_converges_to_the_closed_form() -> None:
    medium = disk_mode_stiffness(3, [0.01], mesh="medium")["levels"][0]
    coarse3 = disk_mode_stiffness(3, [0.01], mesh="coarse")["levels"][0]
    assert abs(medium["stiffness_over_linear"] - 1.0) < abs(coarse3["stiffness_over_linear"]
                                                            - 1.0)


def test_finite_modes_keep_the_area_and_stiffen_little(coarse: dict[int, dict]) -> None:
    for n, result in coarse.items():
        deep = result["levels"][-1]
        assert deep["amplitude_over_r"] == pytest.approx(0.2, rel=1e-6)
        # K = 5000 mu: the area changes by about p / K, below 1e-4 at these tractions
        assert deep["area_ratio"] == pytest.approx(1.0, abs=1e-4)
        # measured -0.1 to +3.1 % at a = 0.2 R on the coarse mesh; a sign error or a
        # factor in the load would show as tens of per cent
        assert 0.98 < deep["stiffness_over_linear"] < 1.06, n


def test_bad_input_names_the_parameter() -> None:
    with pytest.raises(ValueError, match="amplitudes_over_r"):
        disk_mode_stiffness(2, [0.2, 0.1])
    with pytest.raises(ValueError, match="mesh"):
        disk_mode_stiffness(2, [0.1], mesh="huge")
    with pytest.raises(ValueError, match="mode number"):
        disk_mode_stiffness(1, [0.1])


@pytest.fixture(scope="module")
def decay() -> dict[int, dict]:
    from tightknot.fem.section_modes import rod_mode_decay

    return {n: rod_mode_decay(n, mesh="coarse") for n in (2, 4)}  # about 6 s each


def test_a_gradient_energy_carries_a_mode_along_the_rod_as_the_solid_does(
        decay: dict[int, dict]) -> None:
    for n, result in decay.items():
        # One fitted stiffness g_n reproduces the solid's whole profile a_n(z): measured
        # 1.5 % (n = 2) and 2.3 % (n = 4) rms of the peak; a model without the gradient
        # term (a local response, zero beyond the patch) misses by 28 % (n = 2).
        assert result["fit_rms_over_peak"] < 0.05, n
        # a patch of 0.25 D0 carries less than the uniform load's 0.01 R
        assert 0.0 < result["centre_amplitude_over_r"] < 0.0105, n


def test_flattening_spreads_farther_than_a_dent(decay: dict[int, dict]) -> None:
    # the ovalisation (n = 2) decays over a longer length than the four-lobed mode
    assert decay[2]["decay_length_over_d0"] > 1.5 * decay[4]["decay_length_over_d0"]
