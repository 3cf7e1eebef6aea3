"""Where campaign runs execute: in-process, a local process pool, Dask or Ray.

Each executor maps a picklable function over jobs and yields results as they finish.
The function is a pure function of its job, so results do not depend on the engine.
"""

from __future__ import annotations

import multiprocessing
import socket
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Protocol
from urllib.parse import urlsplit

from tetherland.errors import ConfigError

ENGINES = ("local", "dask", "ray")
CONNECT_TIMEOUT = 10.0
"""Longest wait for a cluster address to answer before the campaign gives up [s]."""
_DEFAULT_PORTS = {"dask": 8786, "ray": 6379}


def check_reachable(engine: str, address: str, timeout: float = CONNECT_TIMEOUT) -> None:
    """Fail fast, on one line, when nothing listens at a cluster ``address``.

    Dask and Ray both retry an unreachable address for minutes; a TCP connect with a
    timeout tells within ``timeout`` seconds. ``address`` is ``host:port`` or a URL
    (``tcp://host:port``, ``ray://host:port``); Ray's ``auto`` is left to Ray.

    Raises
    ------
    ConfigError
        Naming ``--address``, the address and why it cannot be reached.
    """
    if engine == "ray" and address == "auto":
        return
    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    try:
        host, port = parts.hostname, parts.port or _DEFAULT_PORTS[engine]
    except ValueError:
        raise ConfigError(f"--address {address!r}: expected host:port") from None
    if not host:
        raise ConfigError(f"--address {address!r}: expected host:port")
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as err:
        reason = "timed out" if isinstance(err, TimeoutError) else (err.strerror or str(err))
        raise ConfigError(
            f"--address {address}: no {engine} scheduler reachable at {host}:{port} ({reason})"
        ) from None


Lost = Callable[[Any, BaseException], Any]
"""``lost(job, error)``: the result to yield for a job whose worker the engine lost for good."""


class Executor(Protocol):
    """Runs ``fn(job)`` for every job and yields the results as they complete.

    A job whose execution fails outside ``fn`` (its worker was killed, the engine gave up)
    yields ``lost(job, error)``; without ``lost`` the error is raised.
    """

    def map_unordered(
        self, fn: Callable[[Any], Any], jobs: Iterable[Any], lost: Lost | None = None
    ) -> Iterator[Any]: ...

    def close(self) -> None: ...


class InlineExecutor:
    """Runs jobs one after the other in this process (1 worker; easy to debug)."""

    def map_unordered(
        self, fn: Callable[[Any], Any], jobs: Iterable[Any], lost: Lost | None = None
    ) -> Iterator[Any]:
        for job in jobs:  # in-process: nothing can be lost but this process
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

    def map_unordered(
        self, fn: Callable[[Any], Any], jobs: Iterable[Any], lost: Lost | None = None
    ) -> Iterator[Any]:
        jobs = iter(jobs)
        pending: dict[Any, Any] = {}
        # keep a bounded number in flight, so an interrupt abandons little work
        for job in jobs:
            pending[self._pool.submit(fn, job)] = job
            if len(pending) >= 2 * self.workers:
                break
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                job = pending.pop(fut)
                try:
                    result = fut.result()
                except Exception as err:
                    if lost is None:
                        raise
                    result = lost(job, err)
                yield result
                for job in jobs:
                    pending[self._pool.submit(fn, job)] = job
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
            check_reachable("dask", address)
            try:
                self._client = Client(address, timeout=f"{CONNECT_TIMEOUT}s")
            except (OSError, TimeoutError) as err:
                raise ConfigError(f"--address {address}: cannot connect to Dask ({err})") from None
        else:
            self._cluster = LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
            )
            self._client = Client(self._cluster)

    def map_unordered(
        self, fn: Callable[[Any], Any], jobs: Iterable[Any], lost: Lost | None = None
    ) -> Iterator[Any]:
        """Dask reruns the tasks of a worker that dies on the others (up to its
        ``allowed-failures``); a task it gives up on yields ``lost(job, error)`` instead
        of stopping the campaign (re-raised when ``lost`` is None)."""
        from dask.distributed import as_completed

        futures = {self._client.submit(fn, job, pure=False): job for job in jobs}
        for fut in as_completed(futures):
            try:
                result = fut.result()
            except Exception as err:
                if lost is None:
                    raise
                result = lost(futures[fut], err)
            yield result

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
            check_reachable("ray", address)
            ray.init(address=address, ignore_reinit_error=True, log_to_driver=False)
        else:
            ray.init(
                num_cpus=workers,
                include_dashboard=False,
                ignore_reinit_error=True,
                log_to_driver=False,
            )

    def map_unordered(
        self, fn: Callable[[Any], Any], jobs: Iterable[Any], lost: Lost | None = None
    ) -> Iterator[Any]:
        ray = self._ray
        remote = ray.remote(num_cpus=1)(fn)
        refs = {remote.remote(job): job for job in jobs}
        pending = list(refs)
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            try:
                result = ray.get(done[0])
            except Exception as err:
                if lost is None:
                    raise
                result = lost(refs[done[0]], err)
            yield result

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
