"""Executors that run sweep cases: ``concurrent.futures`` style (``submit`` -> Future).

* ``serial``: in this process, one case after another (debugging, the benchmark).
* ``process`` (default): local worker processes (:class:`ProcessPoolExecutor`) started with
  the ``spawn`` method: Warp initialises its runtime and kernel modules per process, and a
  forked child would inherit a half-initialised Warp (and any threads) from the parent. Each
  worker gets the parent's ``WARP_CACHE_PATH`` explicitly, so the kernels compiled once are
  loaded from the cache, not compiled again per worker.
* ``dask``: a Dask distributed client (optional extra: ``pip install
  tightknot[distributed]``): a scheduler address for a cluster, or a local cluster of
  worker processes; Dask is imported only here.

Every executor returns futures whose result is the case record of
:func:`tightknot.sweep.execute.run_case`.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from typing import Any

EXECUTORS = ("process", "serial", "dask")

#: Where the worker processes find the Warp kernel cache (resolved in the parent).
_CACHE_ENV = "WARP_CACHE_PATH"


class SerialExecutor(Executor):
    """Runs each submitted call at once, in this process; returns a finished Future."""

    def __init__(self) -> None:
        self._shutdown = False

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        """Call ``fn(*args, **kwargs)`` now; its result (or exception) is in the Future."""
        if self._shutdown:
            raise RuntimeError("cannot submit after shutdown")
        fut: Future = Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except BaseException as err:  # noqa: BLE001 (delivered through the Future)
            fut.set_exception(err)
        return fut

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Refuse further submissions (nothing runs in the background)."""
        self._shutdown = True


def _init_worker(cache_path: str | None) -> None:
    # Runs first in every spawned worker, before any tightknot import loads Warp.
    if cache_path:
        os.environ[_CACHE_ENV] = cache_path


def process_executor(workers: int | None = None) -> ProcessPoolExecutor:
    """A pool of ``workers`` spawned processes (default: the CPU count) sharing this
    process's Warp kernel cache."""
    if workers is not None and workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    return ProcessPoolExecutor(max_workers=workers,
                               mp_context=multiprocessing.get_context("spawn"),
                               initializer=_init_worker,
                               initargs=(os.environ.get(_CACHE_ENV),))


class DaskExecutor(Executor):
    """``concurrent.futures`` facade over a Dask distributed client.

    Args:
        client: an existing ``distributed.Client`` (kept open on shutdown), or None to
            connect to ``address`` or, without one, to start a local cluster of
            ``workers`` single-threaded worker processes (closed on shutdown).
        address: scheduler address ("tcp://host:8786") of a running cluster.
        workers: workers of the local cluster (default: the CPU count).
    """

    def __init__(self, client: Any | None = None, address: str | None = None,
                 workers: int | None = None) -> None:
        try:
            import distributed
        except ImportError as err:
            raise ValueError("the dask executor needs Dask distributed: pip install "
                             f"tightknot[distributed] ({err})") from None
        if workers is not None and workers < 1:
            raise ValueError(f"workers must be >= 1, got {workers}")
        self._owned = client is None
        if client is None:
            if address is not None:
                client = distributed.Client(address)
            else:
                # One thread per worker: a case is single-threaded Python + Warp, and
                # processes keep the Warp runtimes apart. Workers inherit this
                # environment (WARP_CACHE_PATH); Dask spawns them by default.
                n = workers or os.cpu_count() or 1
                client = distributed.Client(n_workers=n, threads_per_worker=1,
                                            processes=True, dashboard_address=None)
        self.client = client
        self._executor = client.get_executor(pure=False)

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        """Submit to the cluster; a ``concurrent.futures.Future``."""
        return self._executor.submit(fn, *args, **kwargs)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Stop the facade; close the client (and its local cluster) if it was made here."""
        # Dask's facade cancels the unfinished futures when it does not wait for them.
        self._executor.shutdown(wait=wait and not cancel_futures)
        if self._owned:
            self.client.close()


def make_executor(kind: str = "process", workers: int | None = None,
                  address: str | None = None) -> Executor:
    """An executor by name (:data:`EXECUTORS`); ``address`` is for ``dask`` only."""
    if kind not in EXECUTORS:
        raise ValueError(f"executor must be one of {EXECUTORS}, got {kind!r}")
    if address is not None and kind != "dask":
        raise ValueError("a scheduler address is for the dask executor only")
    if kind == "serial":
        return SerialExecutor()
    if kind == "process":
        return process_executor(workers)
    return DaskExecutor(address=address, workers=workers)
