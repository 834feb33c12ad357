"""Running many independent simulations: in this process, on a local process pool, or on an
existing Dask distributed cluster.

Each point travels as its ``RunSettings`` (a few numbers) and comes back as its window
``Metrics`` (a few numbers); no arrays cross a process boundary. A worker process imports the
kernel once and keeps it: numba compiles it once per machine and loads it from its on-disk cache
once per worker process, never once per point. Results come back as they finish, tagged with the
point's position, so the caller can store each one at once; every point computes the same bits
wherever it runs, provided the workers run the same drill_sim on the same kind of CPU.
"""

from __future__ import annotations

import multiprocessing
import os
import re
import signal
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import TypeVar

from .. import __version__
from .single import point_metrics

P, R = TypeVar("P"), TypeVar("R")      # a point (RunSettings by default), its result (Metrics)
INSTALL_HINT = ('pip install "dask[distributed]" (or the map-cluster extra: '
                'pip install "drill_sim[map-cluster]")')


class ClusterError(RuntimeError):
    """The Dask cluster cannot be used: distributed missing, scheduler unreachable, no workers,
    or workers without the same drill_sim."""


def available_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:        # not on Linux
        return os.cpu_count() or 1


def compute(points: Sequence[P], *, workers: int = 1,
            scheduler: str | None = None,
            fn: Callable[[P], R] = point_metrics) -> Iterator[tuple[int, R]]:
    """``(position, metrics)`` of every point of ``points``, in the order they finish.

    ``scheduler``: the address of a Dask scheduler (``tcp://host:8786``) to send them to;
    otherwise ``workers`` processes of this machine (1: this process). Closing the iterator
    early (or an exception in the caller) cancels the points not yet started. ``fn``: what is
    computed of each point (a module-level function, so that it travels: ``drill_sim tune``'s
    trials go the same ways as a map's points).
    """
    if not points:
        return
    if scheduler is not None:
        yield from _on_dask(points, scheduler, fn)
    elif workers <= 1 or len(points) == 1:
        for i, settings in enumerate(points):
            yield i, fn(settings)
    else:
        yield from _on_pool(points, min(workers, len(points)), fn)


def _worker_init() -> None:
    """A pool worker leaves Ctrl-C to the parent, which cancels the map and stops the pool."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _pool_context() -> multiprocessing.context.BaseContext:
    """``forkserver`` where there is one (workers fork from a server that has imported the
    simulator once), else ``spawn``; never a plain fork of a parent that may hold threads."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["drill_sim.study.single"])
        return ctx
    return multiprocessing.get_context("spawn")


def _on_pool(points: Sequence[P], workers: int,
             fn: Callable[[P], R]) -> Iterator[tuple[int, R]]:
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=_pool_context(),
                               initializer=_worker_init)
    try:
        futures = {pool.submit(fn, p): i for i, p in enumerate(points)}
        for future in as_completed(futures):
            yield futures[future], future.result()
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def worker_version() -> str:
    """drill_sim's version where this runs (asked of every Dask worker before a map)."""
    return __version__


def require_distributed() -> None:
    """ClusterError, saying how to install it, when Dask's distributed cannot be imported."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise ClusterError(f"a Dask cluster needs Dask's distributed package, which is not "
                           f"installed: {INSTALL_HINT}") from None


_ADDRESS = re.compile(r"^(?:(?:tcp|tls|ws|wss|ucx|inproc)://)?[A-Za-z0-9._\-\[\]:]+:[0-9]{1,5}$")


def check_address(address: str) -> str:
    """A Dask scheduler's address as ``dask scheduler`` prints it (``tcp://host:8786``, or
    ``host:8786``), or ClusterError at once: a malformed one left the Dask client to time out
    40 s later, in its cleanup, with a traceback."""
    if not _ADDRESS.match(address):
        raise ClusterError(f"{address!r} is not a Dask scheduler address: expected "
                           "protocol://host:port as 'dask scheduler' prints it, such as "
                           "tcp://10.0.0.5:8786 (or host:port)")
    return address


def _on_dask(points: Sequence[P], address: str,
             fn: Callable[[P], R]) -> Iterator[tuple[int, R]]:
    check_address(address)
    require_distributed()
    from distributed import Client
    from distributed import as_completed as dask_completed
    try:
        client = Client(address, timeout=20, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise ClusterError(f"cannot reach a Dask scheduler at {address}: {exc}; expected the "
                           f"address 'dask scheduler' prints, such as tcp://host:8786") from None
    futures = []
    try:
        _check_workers(client, address)
        futures = client.map(fn, list(points), pure=False)
        position = {f.key: i for i, f in enumerate(futures)}
        for future, metrics in dask_completed(futures, loop=client.loop, with_results=True):
            yield position[future.key], metrics
    finally:
        if futures:
            client.cancel(futures)
        client.close()


def _check_workers(client, address: str) -> None:
    """Refuse a cluster without workers, or whose workers lack this drill_sim version."""
    try:
        versions = client.run(worker_version)
    except Exception as exc:      # unpickling fails on a worker without drill_sim
        raise ClusterError(f"the workers of the Dask cluster at {address} cannot run drill_sim "
                           f"({type(exc).__name__}: {exc}); expected drill_sim {__version__} "
                           "installed beside every 'dask worker'") from None
    if not versions:
        raise ClusterError(f"the Dask scheduler at {address} has no workers; start some with "
                           f"'dask worker {address}' on machines with drill_sim installed")
    other = {w: v for w, v in versions.items() if v != __version__}
    if other:
        worker, version = next(iter(other.items()))
        raise ClusterError(f"the Dask worker {worker} runs drill_sim {version}, this is "
                           f"{__version__}; expected the same version on every worker")
