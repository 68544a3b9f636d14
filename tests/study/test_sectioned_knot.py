"""A knot tied at the sectioned contact level end to end: the closed trefoil (60 vertices)
converges, keeps its type, and its summary reads width, pressure and area off the sections;
its load path at the compliant level ends at the equilibrium of the full sectioned path; an
open knot's target length is sought again with the sections; the level's bad input."""

import dataclasses

import numpy as np
import pytest

from tightknot.contact.law import RadialComplianceLaw
from tightknot.contact.report import contact_report
from tightknot.contact.sectioned import SectionedLayer, SectionSettings
from tightknot.knots.scenes import closed_trefoil, open_trefoil
from tightknot.loading.batch import tie_batch
from tightknot.loading.pull import knot_length, tie_to_lambda
from tightknot.loading.tie import path_scene, resolved_path, tie
from tightknot.study.run import WEIGHT_SUM_TOLERANCE, calibration_range, run_knot


@pytest.fixture(scope="module")
def sectioned_run():
    scene = closed_trefoil(16.37, nodes=60, contact=SectionSettings())
    return scene, run_knot(scene, tighten_steps=20)


def test_the_closed_trefoil_ties_at_the_sectioned_level(sectioned_run) -> None:
    scene, run = sectioned_run
    s = run.summary
    assert isinstance(scene.contact, SectionedLayer)
    assert s["converged"], s["failure"]
    assert s["knot_type"] == "3_1"
    assert s["section_path"] == "final"  # a closed knot's load path at the compliant level
    # the sections carry the contact: some of their perimeter touches (measured 0.14 at
    # 60 and 100 vertices), none wholly
    assert 0.02 < s["max_contact_width_fraction"] < 1.0
    assert 0.0 < s["max_pressure_over_E"] < 2.0
    # the modes keep the area: A/A0 is the stretch's, lambda^-1 at nu = 1/2
    x = run.result.system.state.x
    ev = scene.model.edge_vertex
    lam = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1) / run.result.system.rest
    assert s["min_area_ratio"] == pytest.approx(1.0 / lam.max(), rel=0.02)
    # the range check speaks of the sections' calibration
    cal = scene.contact.calibration
    assert s["calibrated_w_over_D0"] == cal.calibrated_w_hat
    assert s["crossing_calibrated_w_over_D0"] == cal.crossing_w_hat
    assert run.result.system.state.extra.size == scene.contact.dof_count > 0
    # the trefoil's strands touch on each other's bends, where the weights blending a
    # partner's edges sum to one as on a straight partner (they telescope over its
    # chords; the projection hats they replaced summed to 1.37 here on average,
    # docs/sectioned_level.md); the summary reports the mean and has no warning of it
    assert s["contact_weight_sum_mean"] == pytest.approx(1.0, abs=1e-3)
    assert abs(s["contact_weight_sum_mean"] - 1.0) <= WEIGHT_SUM_TOLERANCE
    assert not any("do not sum to one" in w for w in s["warnings"])
    assert not s["outside_calibrated_range"]  # nothing else of this knot leaves it


def test_a_sectioned_level_takes_no_radial_compliance_law() -> None:
    with pytest.raises(ValueError, match="sectioned.*no radial-compliance law"):
        closed_trefoil(16.37, nodes=60, contact="sectioned",
                       law=RadialComplianceLaw.from_json())


def test_the_batch_refuses_the_sectioned_level() -> None:
    scenes = [closed_trefoil(16.37, nodes=60, contact="sectioned") for _ in range(2)]
    with pytest.raises(ValueError, match="sectioned"):
        tie_batch(scenes)


def _measures(scene, res) -> dict:
    st = res.system.state
    x = st.x
    rep = scene.contact.section_report(x, st.extra, st.frames, res.system.rest)
    length = float(np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1).sum())
    return {"stretch": length / scene.rest_length,
            "lc": float(rep["contact_width_fraction"].max()),
            "area": float(rep["area_ratio"].min()),
            "energy": float(res.system.last_split.total)}


def test_the_final_path_reaches_the_full_paths_equilibrium() -> None:
    """section_path "final" (the load path at the compliant level, the sections solved
    under the last load) and "full" (every step with the sections) end at the same knot."""
    runs = {}
    for path in ("final", "full"):
        scene = closed_trefoil(16.37, nodes=60, contact="sectioned")
        # solved well past the default 1e-6: the closed knot's slide along its rod is a
        # near-zero mode, along which a loose solve stops wherever round-off leaves it
        # (at 1e-6 the full path's stretch moved by 6e-5 with the order of a sum)
        res = tie(scene, tighten_steps=20, section_path=path, residual_tol=1e-8).run()
        assert res.converged, res.failure
        assert res.knot_types[-1] == "3_1"
        runs[path] = (scene, res)
    final, full = (_measures(*runs[p]) for p in ("final", "full"))
    # The same knot, up to where along that near-zero mode each path stops: the 60
    # vertices' contacts make it a row of shallow minima (the two paths' ends are both
    # minima, energies 2.2e-5 apart relative, stretch 4.4e-5; docs/sectioned_level.md,
    # "The kept pattern and PARDISO's inertia"). The sampled maxima move between them:
    # L_c counts boundary samples in contact, one sample a 1/M share of the perimeter
    # (measured one sample apart, 0.1532 and 0.1375; M = 64), and the least area follows
    # the most stretched edge (2.2e-4 apart).
    samples = runs["final"][0].contact.section.samples
    assert final["energy"] == pytest.approx(full["energy"], rel=1e-4)
    assert final["stretch"] == pytest.approx(full["stretch"], rel=1e-4)
    assert abs(final["lc"] - full["lc"]) <= 1.1 / samples  # one sample, +10 % arc spread
    assert final["area"] == pytest.approx(full["area"], abs=5e-4)
    res_final = runs["final"][1]
    assert list(res_final.phases) == ["tighten", "section"]
    assert "section" not in runs["full"][1].phases
    assert res_final.section_path == "final" and runs["full"][1].section_path == "full"
    # the sectioned level's Newton iterations: one solve against every load step's
    # (measured 140 in all, 267)
    assert res_final.phases["section"].newton_iterations < \
        runs["full"][1].phases["tighten"].newton_iterations / 2
    assert res_final.system.state.extra.size == runs["final"][0].contact.dof_count


@pytest.mark.parametrize(("path", "target", "before"),
                         [("final", 12.0, {"tighten", "pull"}), ("pull", 12.0, {"tighten"}),
                          ("auto", 10.4, {"tighten"}), ("auto", 12.0, {"tighten", "pull"})])
def test_an_open_knot_is_sought_with_its_sections(path: str, target: float,
                                                  before: set[str]) -> None:
    """tie_to_lambda on the paths that hand an open knot over to its sections (125 mm rod
    at 100 vertices, tightened to Lambda_OC 10.71 at the compliant level). "final" to 12:
    the force sought at the compliant level, the sections' equilibrium under it (12.16),
    then the force sought again with them (11.99). "pull" to 12: the sections' equilibrium
    at the tightened knot, then the force sought with them (12.05); "auto" so too where
    the knot is pulled tighter (to 10.4: 10.48), but as "final" where it is loosened (to
    12). From the handover on, every equilibrium carries the sections."""
    scene = open_trefoil(0.125, nodes=100, contact="sectioned")
    calls: list[tuple[str, int]] = []
    res = tie_to_lambda(scene, target, section_path=path, hook=lambda phase, system, rec:
                        calls.append((phase, system.state.extra.size))).run()
    assert res.converged, res.failure
    assert set(res.knot_types) == {"3_1"}
    assert knot_length(scene, res.system) == pytest.approx(target, abs=0.1)
    assert res.section_path == ("final" if "pull" in before else "pull")
    phases = [c[0] for c in calls]
    first = phases.index("section")
    assert set(phases[:first]) == before and phases.count("section") == 1
    assert "pull" in phases[first:]
    assert all(size == 0 for _, size in calls[:first])
    assert all(size == scene.contact.dof_count for _, size in calls[first:])


def test_a_pull_that_loosens_the_knot_runs_before_its_sections() -> None:
    """On the "auto" path a pull by a force below the tightened knot's (125 mm rod at 100
    vertices by 1 N: measured Lambda_OC 14.20) runs at the compliant level and the sections
    join at its end, as on the "final" path: the same equilibrium, bit for bit."""
    out = {}
    for path in ("auto", "final"):
        scene = open_trefoil(0.125, nodes=100, contact="sectioned")
        res = tie(scene, pull_force=1.0, section_path=path).run()
        assert res.converged, res.failure
        assert list(res.phases) == ["tighten", "pull", "section"]
        assert res.section_path == "final"
        assert res.system.state.extra.size == scene.contact.dof_count
        out[path] = (res.system.state.x, res.system.state.extra, res.newton_iterations)
    assert np.array_equal(out["auto"][0], out["final"][0])
    assert np.array_equal(out["auto"][1], out["final"][1])
    assert out["auto"][2] == out["final"][2]


@pytest.mark.slow
def test_the_pull_path_reaches_the_full_paths_knot() -> None:
    """The 125 mm knot (150 vertices) pulled by 9.4144 N, tightened at the compliant level
    ("pull") or with its sections ("full"): the same knot (measured Lambda_OC 10.0637
    against 10.0716, max L_c 0.8422 against 0.8425, min A/A0 0.6751 against 0.6780; the
    full path's own search to Lambda_OC 10.1 ended at 10.0595 for this force, so the
    tolerances, 0.03 in Lambda_OC, 0.01 in L_c and A/A0, are the full path's spread)."""
    out = {}
    for path in ("pull", "full"):
        scene = open_trefoil(0.125, nodes=150, contact="sectioned")
        res = tie(scene, pull_force=9.4144, section_path=path).run()
        assert res.converged, res.failure
        assert set(res.knot_types) == {"3_1"}
        assert list(res.phases) == (["tighten", "section", "pull"] if path == "pull"
                                    else ["tighten", "pull"])
        assert res.section_path == path
        assert res.system.state.extra.size == scene.contact.dof_count
        st = res.system.state
        rep = scene.contact.section_report(st.x, st.extra, st.frames, res.system.rest)
        out[path] = (knot_length(scene, res.system), rep["contact_width_fraction"].max(),
                     rep["area_ratio"].min())
    assert out["pull"][0] == pytest.approx(out["full"][0], abs=0.03)
    assert out["pull"][1] == pytest.approx(out["full"][1], abs=0.01)
    assert out["pull"][2] == pytest.approx(out["full"][2], abs=0.01)


def test_a_bad_section_path_is_refused() -> None:
    scene = closed_trefoil(16.37, nodes=60, contact="sectioned")
    with pytest.raises(ValueError, match="section_path must be one of auto, final, full, pull"):
        tie(scene, section_path="half")


def test_auto_pulls_an_open_knot_with_its_sections() -> None:
    """section_path "auto" (the default): a closed knot's load path runs at the compliant
    level, an open knot is tightened there and pulled with its sections (a pulled knot
    can have two equilibria, and the way there picks one: docs/sectioned_level.md)."""
    closed = closed_trefoil(16.37, nodes=60, contact="sectioned")
    opened = open_trefoil(0.125, nodes=100, contact="sectioned")
    via = path_scene(closed)
    assert via is not closed and not isinstance(via.contact, SectionedLayer)
    assert via.model is closed.model
    assert resolved_path(closed) == "final" and resolved_path(closed, "pull") == "final"
    assert resolved_path(opened) == "pull"
    assert not isinstance(path_scene(opened).contact, SectionedLayer)
    assert path_scene(opened, "full") is opened
    assert path_scene(closed, "full") is closed


def test_sections_thinner_than_the_fem_judged_are_said(sectioned_run) -> None:
    """A sectioned run whose sections' area falls below the smallest A/A0 the FEM
    judged (0.66, the rigid wrap's deepest level within the approach limit,
    tests/fem/test_section_area_range.py) says so in its summary's warnings; the tied
    trefoil (A/A0 0.92) does not."""
    scene, run = sectioned_run
    cal = scene.contact.calibration
    assert 0.43 < cal.judged_area_ratio < 0.92
    st = run.result.system.state
    rep = contact_report(scene.contact, st.x, run.result.system.rest, st)
    ok = calibration_range(scene, rep, st.x, run.result.system.rest)
    assert not any("area" in w for w in ok["warnings"])
    thin = dataclasses.replace(rep, area_ratio=np.minimum(rep.area_ratio, 0.43))
    out = calibration_range(scene, thin, st.x, run.result.system.rest)
    assert out["outside_calibrated_range"]
    assert any(f"A/A0 = 0.43, below the {cal.judged_area_ratio:.3g}" in w
               for w in out["warnings"])


def test_contacts_whose_weights_stray_from_one_are_said(sectioned_run) -> None:
    """The partition weights telescope to one on any partner (the tied trefoil: 1.000);
    where a summary's mean strays by more than WEIGHT_SUM_TOLERANCE (contacts on the inside
    of a partner bent tighter than the partition is exact for, rho kappa above about 0.7,
    or many inside an exclusion ramp), it says so and marks the run outside its
    calibrated range."""
    scene, run = sectioned_run
    st = run.result.system.state
    rest = run.result.system.rest
    rep = contact_report(scene.contact, st.x, rest, st)
    ok = calibration_range(scene, rep, st.x, rest)
    assert not any("sum to one" in w for w in ok["warnings"])
    for mean in (1.0 + 1.5 * WEIGHT_SUM_TOLERANCE, 1.0 - 1.5 * WEIGHT_SUM_TOLERANCE):
        out = calibration_range(scene, dataclasses.replace(rep, weight_sum_mean=mean), st.x,
                                rest)
        assert out["outside_calibrated_range"]
        assert any(f"weigh {mean:.3g} times" in w and "sum to one" in w
                   for w in out["warnings"])


def _lost_solve(real, system, newton_options):
    """A failed solve that ends far from its start, as a leap into another basin leaves
    it: one Newton iteration from the start scaled by 1.01, reported unconverged."""
    system.state.x = system.state.x * 1.01
    r, _, _ = yield from real(system, dataclasses.replace(newton_options, max_iterations=1),
                              None, 0)
    return dataclasses.replace(r, converged=False, reason="max_iterations"), 1, "lost"


def _tied_final_with(monkeypatch, scene, solve):
    """``scene`` tied on the ``final`` path with the tie module's static solves replaced
    by ``solve``: converged, a trefoil."""
    import tightknot.loading.tie as tie_module

    monkeypatch.setattr(tie_module, "static_solve", solve)
    res = tie(scene, tighten_steps=20, section_path="final").run()
    assert res.converged, res.failure
    assert res.knot_types[-1] == "3_1"
    return res


def _closed_length(y: np.ndarray) -> float:
    """A closed centreline's length [m]."""
    return float(np.linalg.norm(np.roll(y, -1, axis=0) - y, axis=1).sum())


def test_the_first_section_solve_starts_with_gauss_newton_steps(monkeypatch) -> None:
    """section_finish's first solve takes Gauss-Newton steps until the residual is a
    fraction of its start, then exact Newton steps to the tolerance; its record holds both
    (iterations and residuals), and the layer's Hessian is exact again after it."""
    import tightknot.loading.tie as tie_module

    real = tie_module.static_solve
    scene = closed_trefoil(16.37, nodes=40, contact="sectioned")
    calls: list[tuple] = []

    def spy(system, newton_options, *args, **kwargs):
        calls.append((scene.contact.gauss_newton, newton_options.max_iterations,
                      newton_options.relative_tol))
        r = yield from real(system, newton_options, *args, **kwargs)
        calls[-1] += (r[0].iterations,)
        return r

    res = _tied_final_with(monkeypatch, scene, spy)
    first = [i for i, c in enumerate(calls) if c[0]]
    assert len(first) == 1, calls
    gn, exact = calls[first[0]], calls[first[0] + 1]
    assert gn[:3] == (True, tie_module.GAUSS_NEWTON_ITERATIONS,
                      tie_module.GAUSS_NEWTON_FRACTION)
    assert exact[:3] == (False, tie_module.DIRECT_SECTION_ITERATIONS, 0.0)
    assert not scene.contact.gauss_newton
    newton_rec = res.phases["section"].steps[0].newton
    assert newton_rec.iterations == gn[3] + exact[3] == len(newton_rec.history) - 1
    assert newton_rec.history[gn[3]] <= tie_module.GAUSS_NEWTON_FRACTION * newton_rec.history[0]


def test_a_failed_shifted_section_solve_grows_the_shift_from_its_start(monkeypatch) -> None:
    """With the bend shift, where Newton fails from the round sections (the shift moves a
    tight knot's inner sides toward their partners at once: the 125 mm open knot's first
    shifted solve failed, docs/sectioned_level.md), section_finish solves again from
    its start with the shift grown from a quarter, and reaches the equilibrium the direct
    solve finds; the layer keeps its whole shift."""
    import tightknot.loading.tie as tie_module

    def scene_of():
        return closed_trefoil(16.37, nodes=40, contact=SectionSettings(bend_shift=True))

    ref = tie(scene_of(), tighten_steps=20, section_path="final").run()
    assert ref.converged, ref.failure
    real = tie_module.static_solve
    scene = scene_of()
    seen: list[tuple[float, float]] = []

    def lost(system, newton_options, *args, **kwargs):
        if scene.contact.gauss_newton:  # the first solve's Gauss-Newton phase
            return (yield from real(system, newton_options, *args, **kwargs))
        seen.append((scene.contact.shift.scale, scene.contact.penalty_scale))
        if newton_options.max_iterations == tie_module.DIRECT_SECTION_ITERATIONS \
                and len(seen) == 1:
            return (yield from _lost_solve(real, system, newton_options))
        return (yield from real(system, newton_options, *args, **kwargs))

    res = _tied_final_with(monkeypatch, scene, lost)
    # the direct solve with the whole shift, then the shift's homotopy at the full penalty
    assert seen == [(1.0, 1.0)] + [(f, 1.0) for f in tie_module.SHIFT_HOMOTOPY]
    assert scene.contact.shift.scale == 1.0
    # the same knot (as below: a closed knot's equilibria differ by ~1e-4 in length)
    assert _closed_length(res.system.state.x) == pytest.approx(
        _closed_length(ref.system.state.x), rel=1e-4)


@pytest.mark.parametrize("homotopy_fails", [False, True])
def test_a_failed_section_solve_settles_again_from_its_start(monkeypatch,
                                                             homotopy_fails: bool) -> None:
    """Where Newton fails from the round sections (it can leap into a far basin:
    docs/sectioned_level.md), section_finish solves again from its start with the penalty
    grown from an eighth by doubling; where that fails too, it descends from its start by
    proximal steps alone. Either way it reaches the equilibrium the direct solve finds, and
    the layer keeps its own penalty."""
    import tightknot.loading.tie as tie_module

    ref = tie(closed_trefoil(16.37, nodes=40, contact="sectioned"), tighten_steps=20,
              section_path="final").run()
    assert ref.converged, ref.failure
    real = tie_module.static_solve
    scene = closed_trefoil(16.37, nodes=40, contact="sectioned")
    seen: list[float] = []

    def lost(system, newton_options, *args, **kwargs):
        if scene.contact.gauss_newton:  # the first solve's Gauss-Newton phase
            return (yield from real(system, newton_options, *args, **kwargs))
        scale = scene.contact.penalty_scale
        seen.append(scale)
        direct = (newton_options.max_iterations == tie_module.DIRECT_SECTION_ITERATIONS
                  and len(seen) == 1)
        if direct or (homotopy_fails and scale < 1.0 and len(seen) == 2):
            return (yield from _lost_solve(real, system, newton_options))
        return (yield from real(system, newton_options, *args, **kwargs))

    res = _tied_final_with(monkeypatch, scene, lost)
    # the direct solve at the full penalty, then the homotopy's (only its first where it
    # is made to fail; the proximal steps then run at the full penalty)
    assert seen[0] == 1.0
    assert seen[1:] == ([0.125] if homotopy_fails else list(tie_module.PENALTY_HOMOTOPY))
    assert scene.contact.penalty_scale == 1.0
    # the same knot, up to which of the shallow minima along its slide along the rod (a
    # near-zero mode, this file's final-versus-full test) each path stops in: the
    # homotopy's and the direct solve's ends of this 40-vertex knot are neighbouring
    # minima (measured 1.07e-4 apart in length, 3.8e-6 in energy, at residual 1e-6 and
    # 1e-8 alike), the proximal steps' the direct solve's own (1e-7 in length)
    assert _closed_length(res.system.state.x) == pytest.approx(
        _closed_length(ref.system.state.x), rel=2e-4)
    assert res.system.last_split.total == pytest.approx(ref.system.last_split.total,
                                                        rel=1e-5)


def test_a_fine_closed_trefoil_settles_in_its_first_section_solve(monkeypatch) -> None:
    """At the CLI's default 234 vertices the free closed knot's near-rigid modes
    (eigenvalues 1e-11 of its Hessian's diagonal) can make PARDISO count negative pivots of
    a positive definite Hessian; section_finish's first solve then shifts by
    DIRECT_SECTION_SHIFT_INERTIA (1e-10 of the diagonal) and converges without the
    homotopy (measured 16 iterations; with the default first rung, 1e-6, it stalled at a
    residual of 1e-3 and took the homotopy and proximal steps, 185 s)."""
    import tightknot.loading.tie as tie_module

    real = tie_module.static_solve
    scene = closed_trefoil(16.37, nodes=234, contact="sectioned")
    seen: list[tuple[float, int, bool]] = []

    def spy(system, newton_options, *args, **kwargs):
        out = yield from real(system, newton_options, *args, **kwargs)
        if not scene.contact.gauss_newton:
            seen.append((scene.contact.penalty_scale, newton_options.max_iterations,
                         out[0].converged))
        return out

    res = _tied_final_with(monkeypatch, scene, spy)
    assert res.converged
    assert seen == [(1.0, tie_module.DIRECT_SECTION_ITERATIONS, True)]
