"""Compiled index work of a system's kept Hessian union (:meth:`RodSystem._with_own_hessian`).

A system whose dof term adds node blocks (the sectioned level's contact, the bend shift's
pull-back) keeps the union of the rods' pattern and those blocks through a load step, as
sorted linear indices ``column * size + row``, with each block entry's slot in it. Two
steps of that bookkeeping run on every Newton evaluation and walk the whole union: placing
the blocks' values into the union's data, and merging the entries of new node pairs into
the union. Each is one pass here (numba); in whole-array numpy operations each takes
several passes over a million entries. Every slot of the union receives at most one block
entry, added to the rods' entry there, so the loops' order leaves the matrix unchanged to
the bit.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def _merge(old: np.ndarray, added: np.ndarray, size: int, rows: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray]:
    n, m = old.size, added.size
    grown = np.empty(n + m, dtype=np.int64)
    old_to_new = np.empty(n, dtype=np.int64)
    i = 0
    j = 0
    for k in range(n + m):
        if j < m and (i >= n or added[j] < old[i]):
            grown[k] = added[j]
            j += 1
        else:
            grown[k] = old[i]
            old_to_new[i] = k
            i += 1
        rows[k] = grown[k] % size
    return grown, old_to_new


def merge_sorted(old: np.ndarray, added: np.ndarray, size: int, dtype: np.dtype
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sorted union of the sorted, disjoint linear indices ``old`` and ``added`` (int64,
    ``column * size + row``): (the union, each old entry's place in it, the union's rows as
    ``dtype``, a CSC ``indices`` array)."""
    rows = np.empty(old.size + added.size, dtype=dtype)
    grown, old_to_new = _merge(np.ascontiguousarray(old, dtype=np.int64),
                               np.ascontiguousarray(added, dtype=np.int64), int(size), rows)
    return grown, old_to_new, rows


@numba.njit(cache=True)
def _place(data: np.ndarray, valid: np.ndarray, slots: np.ndarray, source: np.ndarray,
           blocks: np.ndarray) -> None:
    bb = blocks.shape[1]
    p = 0
    for k in range(source.size):
        i = source[k]
        for j in range(bb):
            if valid[k * bb + j]:
                data[slots[p]] += blocks[i, j] if i >= 0 else 0.0
                p += 1


def place_blocks(data: np.ndarray, valid: np.ndarray, slots: np.ndarray, source: np.ndarray,
                 blocks: np.ndarray) -> None:
    """Add node blocks into a kept union's ``data`` in place: for kept pair k, the entries
    of ``blocks[source[k]]`` (B, b, b) that ``valid`` (flat over the kept pairs' b x b
    entries) keeps, in order, at ``slots`` (one per kept entry, all distinct); a pair with
    ``source`` -1 adds zeros (a kept pair without a block this evaluation is a zero block:
    a stored -0.0 there becomes +0.0)."""
    b = blocks.shape[1]
    flat = np.ascontiguousarray(blocks.reshape(blocks.shape[0], b * b), dtype=np.float64)
    _place(data, np.ascontiguousarray(valid), np.ascontiguousarray(slots, dtype=np.int64),
           np.ascontiguousarray(source, dtype=np.int64), flat)
