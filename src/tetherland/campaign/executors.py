"""Where campaign runs execute: in-process, a local process pool, Dask or Ray.

Each executor maps a picklable function over jobs and yields results as they finish.
The function is a pure function of its job, so results do not depend on the engine.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Protocol

from tetherland.errors import ConfigError

ENGINES = ("local", "dask", "ray")


class Executor(Protocol):
    """Runs ``fn(job)`` for every job and yields the results as they complete."""

    def map_unordered(self, fn: Callable[[Any], Any], jobs: Iterable[Any]) -> Iterator[Any]: ...

    def close(self) -> None: ...


class InlineExecutor:
    """Runs jobs one after the other in this process (1 worker; easy to debug)."""

    def map_unordered(self, fn: Callable[[Any], Any], jobs: Iterable[Any]) -> Iterator[Any]:
        for job in jobs:
            yield fn(job)

    def close(self) -> None:
        return None


class LocalPoolExecutor:
    """A pool of worker processes on this machine (spawned, so no state is inherited)."""

    def __init__(self, workers: int):
        self.workers = workers
        self._pool = ProcessPoolExecutor(
            max_workers=workers, mp_context=multiprocessing.get_context("spawn")
        )

    def map_unordered(self, fn: Callable[[Any], Any], jobs: Iterable[Any]) -> Iterator[Any]:
        jobs = iter(jobs)
        pending = set()
        # keep a bounded number in flight, so an interrupt abandons little work
        for job in jobs:
            pending.add(self._pool.submit(fn, job))
            if len(pending) >= 2 * self.workers:
                break
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                yield fut.result()
                for job in jobs:
                    pending.add(self._pool.submit(fn, job))
                    break

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


class DaskExecutor:
    """Dask distributed: a scheduler at ``address``, or a local cluster of ``workers``."""

    def __init__(self, workers: int, address: str | None = None):
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:  # pragma: no cover - depends on the environment
            raise ConfigError(
                "--engine dask needs dask[distributed]: pip install 'tetherland[dask]'"
            ) from None
        self._cluster = None
        if address:
            self._client = Client(address)
        else:
            self._cluster = LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
            )
            self._client = Client(self._cluster)

    def map_unordered(self, fn: Callable[[Any], Any], jobs: Iterable[Any]) -> Iterator[Any]:
        from dask.distributed import as_completed

        futures = [self._client.submit(fn, job, pure=False) for job in jobs]
        for fut in as_completed(futures):
            yield fut.result()

    def close(self) -> None:
        self._client.close()
        if self._cluster is not None:
            self._cluster.close()


class RayExecutor:
    """Ray: a cluster at ``address``, or a local Ray instance with ``workers`` CPUs."""

    def __init__(self, workers: int, address: str | None = None):
        try:
            import ray
        except ImportError:  # pragma: no cover - depends on the environment
            raise ConfigError("--engine ray needs ray: pip install 'tetherland[ray]'") from None
        self._ray = ray
        if address:
            ray.init(address=address, ignore_reinit_error=True, log_to_driver=False)
        else:
            ray.init(
                num_cpus=workers,
                include_dashboard=False,
                ignore_reinit_error=True,
                log_to_driver=False,
            )

    def map_unordered(self, fn: Callable[[Any], Any], jobs: Iterable[Any]) -> Iterator[Any]:
        ray = self._ray
        remote = ray.remote(num_cpus=1)(fn)
        pending = [remote.remote(job) for job in jobs]
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            yield ray.get(done[0])

    def close(self) -> None:
        self._ray.shutdown()


def make_executor(engine: str, workers: int, address: str | None = None) -> Executor:
    """Build the executor for ``--engine`` (``local`` with one worker runs in-process)."""
    if workers < 1:
        raise ConfigError(f"--workers must be >= 1 (got {workers})")
    if engine == "local":
        if address:
            raise ConfigError("--address is only for --engine dask or ray")
        return InlineExecutor() if workers == 1 else LocalPoolExecutor(workers)
    if engine == "dask":
        return DaskExecutor(workers, address)
    if engine == "ray":
        return RayExecutor(workers, address)
    raise ConfigError(f"--engine: unknown engine {engine!r} (allowed: {', '.join(ENGINES)})")
