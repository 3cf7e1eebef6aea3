"""Where campaign runs execute: in-process, a local process pool, Dask or Ray.

Each executor maps a picklable function over jobs and yields results as they finish.
The function is a pure function of its job, so results do not depend on the engine.
"""

from __future__ import annotations

import multiprocessing
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Protocol
from urllib.parse import urlsplit

from tetherland.errors import ConfigError

ENGINES = ("local", "dask", "ray")
CONNECT_TIMEOUT = 10.0
"""Longest wait for a cluster address to accept a TCP connection [s]."""
HANDSHAKE_TIMEOUT = 15.0
"""Longest wait for a throwaway client to connect to the cluster (protocol, authentication)
[s]; with :data:`CONNECT_TIMEOUT` a bad address fails within 30 s."""
DEFAULT_RETRIES = 2
"""Times a run whose worker was lost is run again before it is recorded as lost."""
PARENT_POLL = 0.2
"""How often a pool worker checks that the campaign's main process still lives [s]."""
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


_HANDSHAKES = {
    "dask": "from dask.distributed import Client\n"
    "Client({address!r}, timeout='{own:g}s').close()\n",
    "ray": "import ray\nray.init(address={address!r}, log_to_driver=False)\nray.shutdown()\n",
}


def check_handshake(engine: str, address: str, timeout: float = HANDSHAKE_TIMEOUT) -> None:
    """Fail within ``timeout`` seconds, on one line, when a client cannot join the cluster.

    An address can accept TCP connections and still never let a client in: another
    service, a proxy that answers nothing or garbage, or a Ray cluster with token
    authentication and no (or the wrong) token here. Dask's and Ray's clients then wait
    or retry for minutes; a throwaway client in a subprocess with a hard deadline tells.

    Raises
    ------
    ConfigError
        Naming ``--address`` and the cause (the client's last error line, or no answer).
    """
    if engine == "ray" and address == "auto":
        return
    # Dask's own timeout first, when it keeps to it: its message names the cause
    code = _HANDSHAKES[engine].format(address=address, own=0.7 * timeout)
    proc = subprocess.Popen(
        [sys.executable, "-c", code],
        stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
        text=True, start_new_session=True,
    )  # fmt: skip
    try:
        _, stderr = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        kind = "scheduler" if engine == "dask" else "cluster"
        raise ConfigError(
            f"--address {address}: accepts connections but no {engine} client got in within "
            f"{timeout:g} s (not a {engine} {kind}, or it refuses this client: for a Ray "
            "cluster with token authentication set RAY_AUTH_TOKEN, see "
            "docs/howto/cluster_campaigns.md)"
        ) from None
    if proc.returncode != 0:
        lines = [line.strip() for line in stderr.splitlines() if line.strip()]
        cause = lines[-1] if lines else f"exit code {proc.returncode}"
        raise ConfigError(f"--address {address}: the {engine} client cannot connect: {cause}")


_PR_SET_PDEATHSIG = 1


def _watch_parent(parent: int) -> None:
    """Pool worker initializer: die with the campaign's main process, leave Ctrl-C to it.

    On Linux the kernel kills the worker when the thread that started it ends
    (``prctl(PR_SET_PDEATHSIG, SIGKILL)``; the pool starts its workers from the thread
    that submits, the main thread of a campaign). Elsewhere, and as a second line, a thread
    polls the parent's id every :data:`PARENT_POLL` seconds (it runs only between
    Python bytecodes, so a long solver call delays it). SIGINT (a terminal's Ctrl-C
    reaches the whole process group) is ignored: the main process stops the pool itself.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        import ctypes

        try:
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - no prctl in this libc
            pass
    if os.getppid() != parent:  # the parent died before the line above
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_POLL)
        os._exit(1)

    threading.Thread(target=watch, name="tetherland-parent-watch", daemon=True).start()


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

    def close(self) -> None:
        """Release the workers once every job is done."""
        ...

    def terminate(self) -> None:
        """Stop at once (an interrupt): running jobs are abandoned, workers stopped."""
        ...


class InlineExecutor:
    """Runs jobs one after the other in this process (1 worker; easy to debug)."""

    def map_unordered(
        self, fn: Callable[[Any], Any], jobs: Iterable[Any], lost: Lost | None = None
    ) -> Iterator[Any]:
        for job in jobs:  # in-process: nothing can be lost but this process
            yield fn(job)

    def close(self) -> None:
        return None

    def terminate(self) -> None:
        return None


class _Tracked:
    """Runs ``fn`` on a job in a pool worker, first noting which job this worker runs (a
    file named after its process id in ``registry``), so that the run of a worker that
    dies is known."""

    def __init__(self, fn: Callable[[Any], Any], registry: str):
        self.fn, self.registry = fn, registry

    def __call__(self, item: tuple[int, Any]) -> Any:
        key, job = item
        with open(os.path.join(self.registry, str(os.getpid())), "w") as fh:
            fh.write(str(key))
        return self.fn(job)


class LocalPoolExecutor:
    """A pool of worker processes on this machine (spawned, so no state is inherited).

    A worker that dies (killed, out of memory, a crash) breaks Python's pool: every run
    in flight fails with ``BrokenProcessPool``. The pool is then rebuilt and those runs
    are submitted again. Only the run of the worker that died counts an attempt (the
    others were collateral); it is run again at most ``retries`` times, then yields
    ``lost(job, error)``. Every job yields exactly one result. Workers exit with the main
    process (:func:`_watch_parent`).
    """

    def __init__(self, workers: int, retries: int = DEFAULT_RETRIES):
        if retries < 0:
            raise ConfigError(f"--retries must be >= 0 (got {retries})")
        self.workers = workers
        self.retries = retries
        self.restarts = 0
        """Pools rebuilt after a lost worker."""
        self._registry = tempfile.mkdtemp(prefix="tetherland-pool-")
        self._pool = self._new_pool()

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            max_workers=self.workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_watch_parent,
            initargs=(os.getpid(),),
        )

    def _dead_runs(self, processes: dict[int, Any]) -> set[int] | None:
        """Keys of the runs whose workers died by themselves (not stopped by the broken
        pool's SIGTERM); None when no worker can be blamed."""
        keys = set()
        for pid, process in processes.items():
            if process.exitcode in (None, -signal.SIGTERM):
                continue
            try:
                with open(os.path.join(self._registry, str(pid))) as fh:
                    keys.add(int(fh.read()))
            except (OSError, ValueError):
                return None
        return keys or None

    def map_unordered(
        self, fn: Callable[[Any], Any], jobs: Iterable[Any], lost: Lost | None = None
    ) -> Iterator[Any]:
        tracked = _Tracked(fn, self._registry)
        keyed = enumerate(jobs)
        again: deque[tuple[int, Any, int]] = deque()  # (key, job, attempts) to run again
        pending: dict[Future, tuple[int, Any, int]] = {}

        def refill() -> bool:
            """Keep a bounded number in flight, so an interrupt abandons little work.
            True when the pool broke meanwhile (a worker died since the last wait): the
            item goes back to the front, the pool is rebuilt below."""
            while len(pending) < 2 * self.workers:
                item = again.popleft() if again else next(((k, j, 0) for k, j in keyed), None)
                if item is None:
                    return False
                try:
                    pending[self._pool.submit(tracked, item[:2])] = item
                except BrokenProcessPool:
                    again.appendleft(item)
                    return True
            return False

        broken = refill()
        while pending or broken:
            done, _ = wait(pending, return_when=FIRST_COMPLETED) if pending else (set(), None)
            if not broken and not any(isinstance(f.exception(), BrokenProcessPool) for f in done):
                for fut in done:
                    key, job, attempts = pending.pop(fut)
                    if fut.exception() is None:
                        yield fut.result()
                    elif lost is None:
                        raise fut.exception()  # type: ignore[misc]
                    else:  # fn raised, or its job or result could not be sent
                        yield lost(job, fut.exception())  # type: ignore[arg-type]
                broken = refill()
                continue
            # a worker died: every run in flight fails; collect them, rebuild the pool
            processes = dict(getattr(self._pool, "_processes", None) or {})
            wait(pending)
            self._pool.shutdown(wait=True, cancel_futures=True)  # joins the workers
            culprits = self._dead_runs(processes)
            for fut, (key, job, attempts) in list(pending.items()):
                del pending[fut]
                error = fut.exception()
                if error is None:
                    yield fut.result()
                    continue
                charged = culprits is None or key in culprits
                if not charged or attempts < self.retries:
                    again.append((key, job, attempts + charged))
                elif lost is None:
                    raise error
                else:
                    yield lost(job, error)
            self._pool = self._new_pool()
            self.restarts += 1
            broken = refill()

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)
        shutil.rmtree(self._registry, ignore_errors=True)

    def terminate(self) -> None:
        """Kill the workers now (an interrupt must not wait for the runs in flight)."""
        processes = list((getattr(self._pool, "_processes", None) or {}).values())
        self._pool.shutdown(wait=False, cancel_futures=True)
        for p in processes:
            p.terminate()
        for p in processes:
            p.join(timeout=1.0)
            if p.is_alive():
                p.kill()
        shutil.rmtree(self._registry, ignore_errors=True)


class DaskExecutor:
    """Dask distributed: a scheduler at ``address``, or a local cluster of ``workers``."""

    def __init__(self, workers: int, address: str | None = None, retries: int = DEFAULT_RETRIES):
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:  # pragma: no cover - depends on the environment
            raise ConfigError(
                "--engine dask needs dask[distributed]: pip install 'tetherland[dask]'"
            ) from None
        self.retries = retries
        self.restarts = 0
        """Runs submitted again after Dask gave up on them."""
        self._cluster = None
        self._futures: dict[Any, tuple[Any, int]] = {}
        if address:
            check_reachable("dask", address)
            check_handshake("dask", address)
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
        ``allowed-failures``); a task it gives up on is submitted again up to ``retries``
        times, then yields ``lost(job, error)`` instead of stopping the campaign
        (re-raised when ``lost`` is None)."""
        from dask.distributed import as_completed

        self._futures = {self._client.submit(fn, job, pure=False): (job, 0) for job in jobs}
        running = as_completed(list(self._futures))
        for fut in running:
            job, attempts = self._futures.pop(fut)
            try:
                result = fut.result()
            except Exception as err:
                if attempts < self.retries:
                    again = self._client.submit(fn, job, pure=False)
                    self._futures[again] = (job, attempts + 1)
                    running.add(again)
                    self.restarts += 1
                    continue
                if lost is None:
                    raise
                result = lost(job, err)
            yield result

    def close(self) -> None:
        self._client.close()
        if self._cluster is not None:
            self._cluster.close()

    def terminate(self) -> None:
        """Cancel the runs in flight and close (a local cluster's workers are stopped)."""
        self._client.cancel(list(self._futures), force=True)
        self.close()


class RayExecutor:
    """Ray: a cluster at ``address``, or a local Ray instance with ``workers`` CPUs.

    Ray runs a task whose worker died again by itself, up to ``retries`` times.
    """

    def __init__(self, workers: int, address: str | None = None, retries: int = DEFAULT_RETRIES):
        try:
            import ray
        except ImportError:  # pragma: no cover - depends on the environment
            raise ConfigError("--engine ray needs ray: pip install 'tetherland[ray]'") from None
        self._ray = ray
        self.retries = retries
        self._refs: list[Any] = []
        if address:
            check_reachable("ray", address)
            check_handshake("ray", address)
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
        remote = ray.remote(num_cpus=1, max_retries=self.retries)(fn)
        refs = {remote.remote(job): job for job in jobs}
        pending = self._refs = list(refs)
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            self._refs = pending
            try:
                result = ray.get(done[0])
            except Exception as err:
                if lost is None:
                    raise
                result = lost(refs[done[0]], err)
            yield result

    def close(self) -> None:
        self._ray.shutdown()

    def terminate(self) -> None:
        """Cancel the runs in flight, then shut Ray down."""
        for ref in self._refs:
            self._ray.cancel(ref, force=True)
        self.close()


def make_executor(
    engine: str, workers: int, address: str | None = None, retries: int = DEFAULT_RETRIES
) -> Executor:
    """Build the executor for ``--engine`` (``local`` with one worker runs in-process).

    ``retries``: how often a run whose worker was lost is run again (local pool, Dask,
    Ray); the in-process engine has no worker to lose.
    """
    if workers < 1:
        raise ConfigError(f"--workers must be >= 1 (got {workers})")
    if retries < 0:
        raise ConfigError(f"--retries must be >= 0 (got {retries})")
    if engine == "local":
        if address:
            raise ConfigError("--address is only for --engine dask or ray")
        return InlineExecutor() if workers == 1 else LocalPoolExecutor(workers, retries)
    if engine == "dask":
        return DaskExecutor(workers, address, retries)
    if engine == "ray":
        return RayExecutor(workers, address, retries)
    raise ConfigError(f"--engine: unknown engine {engine!r} (allowed: {', '.join(ENGINES)})")
