"""The contact kernels' spline tables are cached on disk: the file holds exactly the
computed table, and a damaged file is recomputed and replaced, never used."""

from pathlib import Path

import numpy as np
import pytest

from tightknot.contact import law as contact_law
from tightknot.contact.law import _kernel_table, kernel_table


def test_table_is_cached_on_disk_and_bit_identical(tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TIGHTKNOT_CACHE", str(tmp_path))
    kernel_table.cache_clear()
    first = kernel_table("point", 2.6, 1e-4)
    files = list(tmp_path.glob("kernel_point_*.npy"))
    assert len(files) == 1
    fresh = _kernel_table("point", 2.6, 1e-4)
    assert np.array_equal(np.load(files[0]), fresh) and np.array_equal(first, fresh)
    # Another process (a cleared memory cache) reads the file: the same table.
    kernel_table.cache_clear()
    assert np.array_equal(kernel_table("point", 2.6, 1e-4), fresh)
    # Other arguments are another file (the key holds them exactly).
    kernel_table("point", 2.6000000000000001 + 1e-12, 1e-4)
    assert len(list(tmp_path.glob("kernel_point_*.npy"))) == 2
    kernel_table.cache_clear()


def test_a_damaged_cache_file_is_recomputed(tmp_path: Path,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TIGHTKNOT_CACHE", str(tmp_path))
    kernel_table.cache_clear()
    kernel_table("point", 2.4, 1e-4)
    (path,) = tmp_path.glob("kernel_point_*.npy")
    path.write_bytes(b"not a table")
    kernel_table.cache_clear()
    assert np.array_equal(kernel_table("point", 2.4, 1e-4), _kernel_table("point", 2.4, 1e-4))
    assert np.array_equal(np.load(path), _kernel_table("point", 2.4, 1e-4))  # replaced
    kernel_table.cache_clear()
    assert contact_law._table_cache_dir() == tmp_path
