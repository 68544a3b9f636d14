"""Reused device arrays and recorded kernel launches for the per-iteration hot path.

A Newton iteration of a small rod makes about 19 Warp launches and needs about 25 device
arrays. Creating an array from NumPy or packing a launch's arguments costs Python time,
not arithmetic, many times what a copy into an existing array or a replayed ``wp.Launch``
costs (docs/design_notes.md, staging). These helpers keep the same arrays and launches
alive from one evaluation to the next. The numbers
reaching the kernels are the same, so the results are bit for bit those of fresh arrays.

Aliasing rule: a staged array holds the data of its last :meth:`Staging.put`. Callers pass
it straight to launches and never keep it past the evaluation that filled it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import warp as wp


class Staging:
    """One device array, refilled from host data of a fixed length.

    Args:
        dtype: Warp dtype of the array (``wp.float64``, ``wp.vec3d``, ...).
        device: Warp device.
    """

    def __init__(self, dtype: Any, device: str) -> None:
        self.dtype = dtype
        self.device = device
        self._array: wp.array | None = None
        self._view: np.ndarray | None = None  # the array's memory, on the CPU only

    def put(self, a: np.ndarray) -> wp.array:
        """The device array holding ``a`` (reallocated only when the length changes)."""
        arr = self._array
        host = np.asarray(a)
        if arr is None or arr.shape[0] != host.shape[0]:
            arr = wp.array(np.ascontiguousarray(host, dtype=np.float64)
                           if _is_float(self.dtype) else np.ascontiguousarray(host),
                           dtype=self.dtype, device=self.device)
            self._array = arr
            self._view = arr.numpy() if arr.device.is_cpu else None
            return arr
        if self._view is not None:
            self._view[...] = host
        else:
            arr.assign(np.ascontiguousarray(host, dtype=self._view_dtype()))
        return arr

    def _view_dtype(self) -> Any:
        return np.float64 if _is_float(self.dtype) else np.int32


def _is_float(dtype: Any) -> bool:
    return dtype in (wp.float64, wp.vec2d, wp.vec3d)


class Output:
    """A device array of at least a given length, grown by powers of two, for kernel
    outputs whose length changes (one entry per candidate pair).

    Args:
        dtype: Warp dtype.
        device: Warp device.
    """

    def __init__(self, dtype: Any, device: str) -> None:
        self.dtype = dtype
        self.device = device
        self._array: wp.array | None = None
        self._view: np.ndarray | None = None

    def get(self, n: int, zero: bool = False) -> wp.array:
        """The array (length >= max(n, 1)); its first n entries zeroed when ``zero``."""
        arr = self._array
        if arr is None or arr.shape[0] < max(n, 1):
            size = 1 << max(int(n) - 1, 0).bit_length()
            arr = wp.zeros(max(size, 1), dtype=self.dtype, device=self.device)
            self._array = arr
            self._view = arr.numpy() if arr.device.is_cpu else None
            return arr
        if zero and n > 0:
            if self._view is not None:
                self._view[:n] = 0
            else:
                arr.zero_()
        return arr

    def numpy(self, n: int) -> np.ndarray:
        """A host copy of the first n entries."""
        if self._array is None:
            raise RuntimeError("Output.numpy before Output.get")
        if self._view is not None:
            return self._view[:n].copy()
        return self._array.numpy()[:n].copy()


class Launches:
    """Recorded launches, replayed while a kernel is called with the same arrays (the same
    objects) and scalars; the launch dimension may change between calls."""

    def __init__(self) -> None:
        self._cache: dict[Any, tuple[list[Any], Any, int]] = {}

    def launch(self, kernel: Any, dim: int, device: str, inputs: list[Any],
               outputs: list[Any], variant: Any = None) -> None:
        """As ``wp.launch(kernel, dim=dim, device=device, inputs=..., outputs=...)``.
        ``variant`` keeps one recorded launch per value (calls that alternate between
        argument sets, e.g. with and without a Hessian, each keep theirs)."""
        args = [*inputs, *outputs]
        key = (kernel, variant)
        entry = self._cache.get(key)
        if entry is not None and _same(entry[0], args):
            cmd = entry[1]
            if entry[2] != dim:
                cmd.set_dim(dim)
                self._cache[key] = (entry[0], cmd, dim)
            cmd.launch()
            return
        cmd = wp.launch(kernel, dim=dim, device=device, inputs=inputs, outputs=outputs,
                        record_cmd=True)
        # The argument list is kept: it holds references to the arrays, so none of them
        # is freed (and its address reused) while the recorded launch points at it.
        self._cache[key] = (args, cmd, dim)
        cmd.launch()


def _same(old: list[Any], new: list[Any]) -> bool:
    if len(old) != len(new):
        return False
    for a, b in zip(old, new, strict=True):
        if a is b:
            continue
        if isinstance(a, wp.array) or isinstance(b, wp.array):
            return False
        if type(a) is not type(b) or a != b:
            return False
    return True
