"""The Warp CUDA path against the CPU: the same model evaluated and solved on both devices.

Skipped where Warp sees no CUDA device (CI and this project's CPU machines). On a lent GPU,
``bench/gpu/run.sh`` runs these (``pytest -m cuda``) before the GPU benchmarks.

Tolerances: float64 everywhere; a GPU sums the per-pair and per-stencil contributions with
atomics in another order than the CPU, so single evaluations agree to round-off (1e-10 of the
largest entry, far above 1e-16 per addition times a few hundred terms per entry, far below
any physical difference), and whole solves, whose Newton paths then differ by round-off
from the first iteration on, reach the same equilibrium to the solver's tolerance (residual
1e-6 of EI/L^2: positions to about 1e-6 D0; 1e-5 is asked of the measured invariants).
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from tightknot.warp_setup import init_warp

#: The device compared with the CPU; TIGHTKNOT_TEST_DEVICE=cpu runs these checks on the
#: CPU against itself (a check of the tests, where no GPU is at hand).
CUDA = os.environ.get("TIGHTKNOT_TEST_DEVICE", "cuda:0")


def _available(device: str) -> bool:
    import warp as wp

    init_warp()
    return any(d.alias == device for d in wp.get_devices())


pytestmark = [pytest.mark.cuda,
              pytest.mark.skipif(not _available(CUDA), reason=f"no Warp device {CUDA}")]


def _squeezed_system(device: str):
    """The closed trefoil's start curve shrunk by 7 %: about a hundred pairs in contact."""
    from tightknot.knots.scenes import closed_trefoil, gauge
    from tightknot.rods.state import State
    from tightknot.solvers.system import RodSystem

    scene = closed_trefoil(l0_over_d0=16.37, nodes=100, device=device)
    x = scene.model.vertex_initial_position * 0.93
    system = RodSystem(scene.model, State.initial(scene.model, positions=x), gauge(scene))
    system.add_term(scene.contact)
    system.set_load(0.0)
    return system, scene


def test_one_evaluation_agrees_with_the_cpu() -> None:
    cpu, _ = _squeezed_system("cpu")
    gpu, _ = _squeezed_system(CUDA)
    e0, g0, h0 = cpu.evaluate(cpu.free_vector(), True, True)
    e1, g1, h1 = gpu.evaluate(gpu.free_vector(), True, True)
    assert cpu.last_split.extra["contact"] > 0.0  # the contact kernels did run
    assert e1 == pytest.approx(e0, rel=1e-12)
    assert np.abs(g1 - g0).max() <= 1e-10 * np.abs(g0).max()
    assert abs(h1 - h0).max() <= 1e-10 * abs(h0).max()
    u, du = cpu.free_vector(), -1e-3 * g0 / np.abs(g0).max()
    assert gpu.max_step(u, du) == pytest.approx(cpu.max_step(u, du), rel=1e-12)


def test_the_sectioned_level_evaluates_as_on_the_cpu() -> None:
    # the sectioned level's kernels (node-pair blocks added with atomics) on both devices,
    # sections deformed at random on the squeezed trefoil
    from tightknot.contact.sectioned import SectionSettings
    from tightknot.knots.scenes import closed_trefoil, gauge
    from tightknot.rods.state import State
    from tightknot.solvers.system import RodSystem

    out = []
    for dev in ("cpu", CUDA):
        scene = closed_trefoil(l0_over_d0=16.37, nodes=100, device=dev,
                               contact=SectionSettings())
        x = scene.model.vertex_initial_position * 0.93
        system = RodSystem(scene.model, State.initial(scene.model, positions=x), gauge(scene))
        system.add_term(scene.contact)
        system.set_load(0.0)
        rng = np.random.default_rng(0)
        system.state.extra = 1e-5 * rng.standard_normal(system.state.extra.size)
        out.append((*system.evaluate(system.free_vector(), True, True),
                    system.last_split.extra["contact"]))
    (e0, g0, h0, c0), (e1, g1, h1, _) = out
    assert c0 > 0.0
    assert e1 == pytest.approx(e0, rel=1e-12)
    assert np.abs(g1 - g0).max() <= 1e-10 * np.abs(g0).max()
    assert abs(h1 - h0).max() <= 1e-10 * abs(h0).max()


def _invariants(x: np.ndarray, scene) -> tuple[float, float, float]:
    from tightknot.knots.measure import analyze_centerline

    rep = analyze_centerline(x, scene.diameter, closed=True, rest_length=scene.rest_length)
    gap = scene.contact.min_distance(x)[0] / scene.diameter
    return rep["stretch_L_over_L0"], rep["kappa_D0_max"], gap


def test_a_closed_knot_ties_to_the_same_equilibrium() -> None:
    from tightknot.knots.scenes import closed_trefoil
    from tightknot.loading.tie import tie

    runs = {}
    for dev in ("cpu", CUDA):
        scene = closed_trefoil(l0_over_d0=16.37, nodes=60, device=dev)
        res = tie(scene, tighten_steps=10).run()
        assert res.converged, f"{dev}: {res.failure}"
        assert set(res.knot_types) == {"3_1"}
        runs[dev] = _invariants(res.system.state.x, scene)
    np.testing.assert_allclose(runs[CUDA], runs["cpu"], rtol=0, atol=1e-5)


def test_a_batch_on_the_gpu_agrees_with_one_by_one_on_the_cpu() -> None:
    from tightknot.knots.scenes import closed_trefoil
    from tightknot.loading.batch import tie_batch
    from tightknot.loading.tie import tie

    ratios = (17.0, 18.5)
    batch = tie_batch([closed_trefoil(l0_over_d0=r, nodes=60, device=CUDA) for r in ratios],
                      tighten_steps=10)
    assert batch.converged, batch.failure
    for k, r in enumerate(ratios):
        scene = closed_trefoil(l0_over_d0=r, nodes=60)
        single = tie(scene, tighten_steps=10).run()
        assert single.converged, single.failure
        np.testing.assert_allclose(_invariants(batch.positions[k], scene),
                                   _invariants(single.system.state.x, scene), rtol=0,
                                   atol=1e-5)
