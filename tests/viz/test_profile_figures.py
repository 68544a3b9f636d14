"""The FEM's and the rod model's profiles side by side (tightknot.viz.profile_figures), from a
small synthetic ``soft_scenes`` entry, and the crosscheck CLI's ``--figure`` bad input."""

import pytest

from tightknot.viz.profile_figures import plot_soft_profiles


def _profile(width):
    return [{"s_over_d0": 0.1 * k, "contact_fraction": w, "area_ratio": 1.0 - 0.1 * w,
             "peak_pressure_over_e": 0.5 * w} for k, w in enumerate(width)]


def _soft(level="sectioned"):
    fem_steps = [{"approach_over_d0": 0.0, "profile_a": _profile([0.0, 0.0])},
                 {"approach_over_d0": 0.05, "profile_a": _profile([0.3, 0.1, 0.0])},
                 {"approach_over_d0": 0.1, "profile_a": _profile([0.4, 0.2, 0.1, 0.0])}]
    rod_steps = [{"profile_a": _profile([0.0, 0.0])},
                 {"profile_a": _profile([0.2, 0.1, 0.0])},
                 {"profile_a": _profile([0.3, 0.2, 0.0, 0.0])}]
    # the comparison judged the two levels in contact
    comparison = {"levels": [{"load": 0.6, "approach_over_d0": 0.05},
                             {"load": 0.9, "approach_over_d0": 0.1}]}
    return {"fem": {"clasp": {"steps": fem_steps}},
            "levels": {level: {"scenes": {"clasp": {"rod_steps": rod_steps,
                                                    "comparison": comparison}}}}}


def test_the_profiles_are_drawn_for_the_compared_levels(tmp_path):
    out = tmp_path / "profiles.png"
    assert plot_soft_profiles(_soft(), "sectioned", out) == ["clasp"]
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["profiles.png"]  # no temporary left


def test_a_missing_level_or_no_profile_is_a_clear_error(tmp_path):
    with pytest.raises(ValueError, match="no contact level 'compliant'"):
        plot_soft_profiles(_soft(), "compliant", tmp_path / "a.png")
    soft = _soft()
    soft["levels"]["sectioned"]["scenes"]["clasp"]["comparison"]["levels"] = []
    with pytest.raises(ValueError, match="no compared level with profiles"):
        plot_soft_profiles(soft, "sectioned", tmp_path / "b.png")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("argv, message", [
    (["fem", "crosscheck", "--no-soft", "--figure", "{tmp}/p.png"], "cannot go with --no-soft"),
    (["fem", "crosscheck", "--figure", "{tmp}/p.pdf"], "must name a .png file"),
    (["fem", "crosscheck", "--figure", "{tmp}/missing/p.png"], "output folder does not exist"),
    (["fem", "indent", "--figure", "{tmp}/p.png"], "scene 'indent' has none"),
])
def test_cli_figure_bad_input_exits_2(tmp_path, capsys, argv, message):
    from tightknot.app.cli import main

    assert main([a.format(tmp=tmp_path) for a in argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not list(tmp_path.iterdir())
