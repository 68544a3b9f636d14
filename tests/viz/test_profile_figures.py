"""The FEM's and the rod model's profiles side by side (tightknot.viz.profile_figures), from a
small synthetic ``soft_scenes`` entry, and the crosscheck CLI's ``--figure`` bad input."""

import pytest

from tightknot.viz.profile_figures import plot_profiles, plot_soft_profiles


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
    (["fem", "crosscheck", "--no-soft", "--figure", "{tmp}/p.png"],
     "which only --contact sectioned reports"),
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


def _rigid():
    # a rigid scene's report entry: the FEM's and the rod's steps, the comparison's rows
    # with their profile judgement where both report profiles (the sectioned level)
    fem_steps = [{"approach_over_d0": 0.05, "tension_over_e_d0sq": 0.01,
                  "profile_a": _profile([0.3, 0.1, 0.0])},
                 {"approach_over_d0": 0.1, "tension_over_e_d0sq": 0.02,
                  "profile_a": _profile([0.4, 0.2, 0.0])}]
    rod_steps = [{"profile_a": _profile([0.2, 0.1, 0.0])},
                 {"profile_a": _profile([0.3, 0.2, 0.0])}]
    rows = [{"approach_over_d0": 0.05, "profile_a": {}}, {"approach_over_d0": 0.1}]
    return {"wrap": {"fem_steps": fem_steps, "rod_steps": rod_steps,
                     "comparison": {"levels": rows}}}


def test_the_rigid_scenes_are_drawn_beside_the_soft_ones(tmp_path):
    out = tmp_path / "all.png"
    assert plot_profiles(out, "sectioned", soft=_soft(), rigid=_rigid()) == ["wrap", "clasp"]
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # alone (--no-soft); a level judged without profiles is not drawn
    assert plot_profiles(tmp_path / "r.png", "sectioned", rigid=_rigid()) == ["wrap"]
    rigid = _rigid()
    rigid["wrap"]["comparison"]["levels"][0].pop("profile_a")
    with pytest.raises(ValueError, match="no compared level with profiles"):
        plot_profiles(tmp_path / "none.png", "compliant", rigid=rigid)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["all.png", "r.png"]
