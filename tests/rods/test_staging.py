"""Reused device arrays and recorded launches (tightknot.rods.staging).

The hot path reuses arrays and replays launches; these tests check the rules that keep it
equal to fresh arrays: data are copied in, lengths reallocate, zeroing covers what it must,
and a replayed launch sees the arrays' new contents but never a stale array.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from tests.contact.test_contact import D, two_rods
from tightknot.contact.layer import ContactLayer
from tightknot.rods import elastic_kernels as ek
from tightknot.rods.staging import Launches, Output, Staging
from tightknot.warp_setup import init_warp

init_warp()


def test_staging_copies_into_one_array_and_reallocates_on_a_new_length() -> None:
    s = Staging(wp.vec3d, "cpu")
    a = np.arange(12.0).reshape(4, 3)
    first = s.put(a)
    a[0, 0] = -1.0  # the staged copy must not follow the host array
    assert first.numpy()[0, 0] == 0.0
    second = s.put(2.0 * a)
    assert second is first
    np.testing.assert_array_equal(second.numpy(), 2.0 * a)
    third = s.put(np.ones((5, 3)))
    assert third is not first and third.shape == (5,)


def test_output_grows_by_powers_of_two_and_zeroes_the_asked_prefix() -> None:
    o = Output(wp.float64, "cpu")
    arr = o.get(5)
    assert arr.shape[0] == 8
    arr.numpy()[:] = 7.0
    again = o.get(6, zero=True)
    assert again is arr
    np.testing.assert_array_equal(arr.numpy()[:6], 0.0)
    np.testing.assert_array_equal(arr.numpy()[6:], 7.0)  # beyond the prefix: untouched
    host = o.numpy(3)
    host[:] = 1.0  # a copy: writing it leaves the device array alone
    assert arr.numpy()[0] == 0.0
    assert o.get(9).shape[0] == 16


def _frames(launches: Launches | None, ev: wp.array, x: wp.array, d1: wp.array,
            t: wp.array) -> tuple[np.ndarray, np.ndarray]:
    n = ev.shape[0]
    d1_out = wp.empty(n, dtype=wp.vec3d)
    t_out = wp.empty(n, dtype=wp.vec3d)
    if launches is None:
        wp.launch(ek.transport_frames_kernel, dim=n, inputs=[ev, x, d1, t],
                  outputs=[d1_out, t_out])
    else:
        launches.launch(ek.transport_frames_kernel, n, "cpu", [ev, x, d1, t], [d1_out, t_out])
    return d1_out.numpy(), t_out.numpy()


def test_a_replayed_launch_sees_new_contents_and_a_new_array_is_recorded_again() -> None:
    rng = np.random.default_rng(3)
    n = 6
    ev = wp.array(np.c_[np.arange(n), np.arange(1, n + 1)].astype(np.int32), dtype=wp.vec2i)
    x_host = np.cumsum(rng.normal(size=(n + 1, 3)), axis=0)
    t0 = x_host[1:] - x_host[:-1]
    t0 /= np.linalg.norm(t0, axis=1)[:, None]
    d1_host = np.cross(t0, [0.3, 0.4, 0.87])
    d1_host /= np.linalg.norm(d1_host, axis=1)[:, None]
    d1 = wp.array(d1_host, dtype=wp.vec3d)
    t = wp.array(t0, dtype=wp.vec3d)
    sx = Staging(wp.vec3d, "cpu")
    launches = Launches()
    # Outputs are fresh arrays here, so each call records anew; inputs reused: replayed
    # calls below use one output pair.
    d1_out = wp.empty(n, dtype=wp.vec3d)
    t_out = wp.empty(n, dtype=wp.vec3d)
    for k in range(3):
        moved = x_host + 0.05 * k * rng.normal(size=x_host.shape)
        wx = sx.put(moved)
        launches.launch(ek.transport_frames_kernel, n, "cpu", [ev, wx, d1, t], [d1_out, t_out])
        ref_d1, ref_t = _frames(None, ev, wp.array(moved, dtype=wp.vec3d), d1, t)
        np.testing.assert_array_equal(d1_out.numpy(), ref_d1)
        np.testing.assert_array_equal(t_out.numpy(), ref_t)
    assert len(launches._cache) == 1  # one recording, replayed
    # Another input array (same values, another object): recorded again, right result.
    other = wp.array(x_host, dtype=wp.vec3d)
    launches.launch(ek.transport_frames_kernel, n, "cpu", [ev, other, d1, t], [d1_out, t_out])
    ref_d1, _ = _frames(None, ev, other, d1, t)
    np.testing.assert_array_equal(d1_out.numpy(), ref_d1)
    # A smaller launch dimension on the replay touches only that prefix.
    d1_out.zero_()
    launches.launch(ek.transport_frames_kernel, 2, "cpu", [ev, other, d1, t], [d1_out, t_out])
    np.testing.assert_array_equal(d1_out.numpy()[:2], ref_d1[:2])
    np.testing.assert_array_equal(d1_out.numpy()[2:], 0.0)


def test_a_contact_layer_called_again_equals_a_fresh_one() -> None:
    # The layer's reused arrays must carry nothing from one call into the next: after an
    # evaluation at other positions (another contact set), the same positions give the
    # same numbers as a new layer, bit for bit.
    model = two_rods(60.0, 0.8 * D, n=41)
    x = model.vertex_initial_position.copy()
    fresh = ContactLayer(model).evaluate(x, model.edge_rest_length)
    layer = ContactLayer(model)
    n = len(x) // 2
    for shift in (0.05 * D, 10.0 * D):  # deeper in contact, then apart
        other = x.copy()
        other[n:, 2] -= shift
        layer.evaluate(other, model.edge_rest_length)
        layer.max_step(other, 0.01 * D * np.ones_like(other), model.edge_rest_length)
    again = layer.evaluate(x, model.edge_rest_length)
    assert fresh[0] == again[0] and fresh[0] > 0.0
    np.testing.assert_array_equal(fresh[1], again[1])
    for a, b in zip(fresh[2], again[2], strict=True):
        np.testing.assert_array_equal(a, b)


def test_the_device_branches_copy_and_zero_as_the_host_ones() -> None:
    # On a GPU the arrays have no host view: put() assigns, get(zero=True) zeroes the whole
    # array, numpy() copies back. Run those branches on CPU arrays by dropping the view.
    s = Staging(wp.vec3d, "cpu")
    s.put(np.zeros((3, 3)))
    s._view = None
    a = np.arange(9.0).reshape(3, 3)
    np.testing.assert_array_equal(s.put(a).numpy(), a)
    o = Output(wp.float64, "cpu")
    arr = o.get(3)
    arr.assign(np.array([1.0, 2.0, 3.0, 4.0]))
    o._view = None
    assert o.get(3, zero=True) is arr
    np.testing.assert_array_equal(o.numpy(3), 0.0)
