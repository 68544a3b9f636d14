"""The kept union's compiled index work against the numpy forms it replaced, bit for bit."""

from __future__ import annotations

import numpy as np

from tightknot.solvers.kept_union import merge_sorted, place_blocks


def test_merge_sorted_is_the_sorted_union_with_each_old_entrys_place() -> None:
    rng = np.random.default_rng(4)
    size = 97
    lin = np.unique(rng.integers(0, size * size, 3000))
    pick = rng.random(lin.size) < 0.3
    old, added = lin[~pick], lin[pick]
    grown, old_to_new, rows = merge_sorted(old, added, size, np.dtype(np.int32))
    assert np.array_equal(grown, lin)
    assert np.array_equal(grown[old_to_new], old)
    assert rows.dtype == np.int32 and np.array_equal(rows, lin % size)
    # nothing added, or nothing kept
    assert np.array_equal(merge_sorted(old, added[:0], size, np.dtype(np.int64))[0], old)
    g, o2n, _ = merge_sorted(old[:0], added, size, np.dtype(np.int64))
    assert np.array_equal(g, added) and o2n.size == 0


def test_place_blocks_adds_what_the_dense_block_table_added() -> None:
    # The numpy form: a zero block per kept pair, own blocks placed at their pairs, a
    # shadow pair copying its source, then data[slots] += blocks[valid].
    rng = np.random.default_rng(5)
    kept, b, n_data = 40, 5, 4000
    valid = rng.random(kept * b * b) < 0.6
    slots = rng.permutation(n_data)[:valid.sum()]
    own = rng.normal(size=(25, b, b))
    at = rng.permutation(kept)[:25]
    source = np.full(kept, -1)
    source[at] = np.arange(25)
    shadow, shadow_src = np.array([at[0] ^ 1]), np.array([at[0]])
    source[shadow] = source[shadow_src]
    base = rng.normal(size=n_data)
    base[slots[:7]] = -0.0  # a stored -0.0 plus a zero block turns +0.0, as before

    table = np.zeros((kept, b, b))
    table[at] = own
    table[shadow] = table[shadow_src]
    expected = base.copy()
    expected[slots] += table.ravel()[valid]
    data = base.copy()
    place_blocks(data, valid, slots, source, own)
    assert np.array_equal(data.view(np.int64), expected.view(np.int64))
