"""Where independent tasks run: this process, a LocalCluster of worker processes, or a
running Dask cluster (dask.distributed).

The engine knows nothing of what it runs: ``map(fn, items, shared=...)`` calls
``fn(shared, item)`` for every item and returns the results in the items' order, so a
result never depends on how many workers there are or which finished first. ``shared``
(a scene, an FMU's bytes, a contact) and ``fn`` reach each worker once, not once per
task. Items go in batches (fewer tasks for short runs); the items of a task whose worker
died (a crashing FMU) run again one by one, alone, so that only an item that crashes by
itself fails. Progress:
a tqdm bar over the items as their tasks finish (on a terminal; ``progress=False``
silences it).

Worker processes: one thread each (the FMUs and the solvers are single-threaded Python;
a process per core avoids the GIL), BLAS single-threaded (dask.distributed's nanny sets
OMP/OPENBLAS/MKL_NUM_THREADS=1 before a worker starts). ``once(key, factory)`` keeps a
per-process value (an extracted FMU, a parsed scene) for every task of that process;
leaving the engine's with-block releases them on every worker and here.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from .._validate import InputError

# Per-process values of ``once`` (in a worker: for every task it runs), and how to clean
# each up (``release``).
_ONCE: dict[str, Any] = {}
_CLEANUP: dict[str, Callable[[Any], None]] = {}
# seconds to wait for a running scheduler to answer (dask's default is 30 s)
CONNECT_TIMEOUT = 10.0


def once(key: str, factory: Callable[[], Any], cleanup: Callable[[Any], None] | None = None) -> Any:
    """The value of ``factory()`` made once per process under ``key``; ``cleanup(value)``
    runs when it is released."""
    if key not in _ONCE:
        _ONCE[key] = factory()
        if cleanup is not None:
            _CLEANUP[key] = cleanup
    return _ONCE[key]


def release(prefix: str = "") -> int:
    """Clean up and forget this process's ``once`` values whose keys start with
    ``prefix`` (an extracted FMU's folder is removed); the number released."""
    keys = [k for k in _ONCE if k.startswith(prefix)]
    for k in keys:
        value = _ONCE.pop(k)
        cleanup = _CLEANUP.pop(k, None)
        if cleanup is not None:
            cleanup(value)
    return len(keys)


class _Failed:
    """A task's exception, returned in place of its result (its batch goes on)."""

    def __init__(self, exc: BaseException) -> None:
        self.exc = exc


class _Box:
    """A value passed as one object (Dask would look into lists, tuples and dicts)."""

    def __init__(self, value: Any) -> None:
        self.value = value


def _hold(box: _Box) -> _Box:
    return box


def _call_batch(batch: list[Any], fn: _Box, shared: _Box) -> list[Any]:
    fn, shared = fn.value, shared.value
    out = []
    for item in batch:
        try:
            out.append(fn(shared, item))
        except Exception as e:
            out.append(_Failed(e))
    return out


def batches(n: int, workers: int, size: int | None = None) -> list[slice]:
    """Consecutive slices of n items: ``size`` each, or by default about four per
    worker (fewer, larger tasks keep the engine's per-task cost small against short
    runs; four per worker still balance uneven ones)."""
    if size is None:
        size = max(1, -(-n // (4 * max(1, workers))))
    return [slice(i, min(i + size, n)) for i in range(0, n, size)]


class Engine:
    """A context manager that runs tasks.

    workers: 0 runs every task in this process, in order (no Dask); N >= 1 starts a
    LocalCluster of N worker processes (default: one per CPU). scheduler: the address
    of a running scheduler (``tcp://host:8786``); its workers must import contact_fmu.
    """

    def __init__(
        self, workers: int | None = None, scheduler: str | None = None, progress: bool = True
    ) -> None:
        if workers is not None and scheduler is not None:
            raise InputError("workers", workers, "left out when a scheduler is given")
        if workers is not None and (isinstance(workers, bool) or workers < 0):
            raise InputError("workers", workers, "an integer >= 0 (0: in this process)")
        if scheduler is not None and not (isinstance(scheduler, str) and scheduler.strip()):
            raise InputError("scheduler", scheduler, "an address such as tcp://host:8786")
        self.workers = (os.cpu_count() or 1) if workers is None and scheduler is None else workers
        self.scheduler = scheduler
        self.progress = progress
        self.client = None
        self._cluster = None

    @property
    def serial(self) -> bool:
        return self.scheduler is None and self.workers == 0

    def describe(self) -> str:
        if self.serial:
            return "serial, in this process"
        if self.scheduler is not None:
            n = len(self.client.scheduler_info()["workers"]) if self.client else "?"
            return f"Dask scheduler {self.scheduler} ({n} workers)"
        return f"LocalCluster of {self.workers} worker processes"

    def __enter__(self) -> Engine:
        """Start (or connect to) the cluster; an unreachable scheduler is an InputError
        naming its address, after CONNECT_TIMEOUT."""
        if self.serial or self.client is not None:
            return self
        from dask.distributed import Client, LocalCluster

        if self.scheduler is not None:
            try:
                self.client = Client(self.scheduler, timeout=CONNECT_TIMEOUT)
            except (OSError, TimeoutError, ValueError) as e:  # refused, unknown host, timeout
                why = str(e).splitlines()[0] if str(e) else type(e).__name__
                raise InputError(
                    "scheduler",
                    self.scheduler,
                    f"the address of a running Dask scheduler (tcp://host:8786); no answer "
                    f"within {CONNECT_TIMEOUT:g} s: {why}",
                ) from None
        else:
            self._cluster = LocalCluster(
                n_workers=self.workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=":0",  # None still serves HTTP on 8787 (taken: a warning)
                silence_logs=logging.ERROR,
            )
            self.client = Client(self._cluster)
        return self

    def __exit__(self, *exc: object) -> None:
        """Release every worker's ``once`` values (extracted FMUs: a long-lived cluster
        keeps no copies) and this process's, then close the client (and the cluster)."""
        if self.client is not None:
            try:
                self.client.run(release)
            except Exception:  # noqa: S110 - a worker gone already has nothing to clean
                pass
            self.client.close()
        release()
        if self._cluster is not None:
            self._cluster.close()
        self.client = self._cluster = None

    def _bar(self, total: int, desc: str):
        from tqdm import tqdm

        return tqdm(total=total, desc=desc, unit="task", disable=not self.progress or None)

    def map(
        self,
        fn: Callable[[Any, Any], Any],
        items: Sequence[Any],
        shared: Any = None,
        desc: str = "tasks",
        on_error: Callable[[Any, BaseException], Any] | None = None,
        batch: int | None = None,
    ) -> list[Any]:
        """[fn(shared, item) for item in items], in the items' order; on workers, items
        go in consecutive batches (``batches``: ``batch`` items per task; the items of a
        task whose worker died run again one by one, alone). An item that raises (or
        kills its worker by itself) gives on_error(item, exception) when given, else the
        exception is raised (the remaining tasks are cancelled)."""
        items = list(items)
        with self._bar(len(items), desc) as bar:
            if self.serial:
                out = []
                for it in items:
                    try:
                        out.append(fn(shared, it))
                    except Exception as e:
                        if on_error is None:
                            raise
                        out.append(on_error(it, e))
                    bar.update()
                return out
            return self._distributed(fn, items, shared, on_error, bar, batch)

    def n_workers(self) -> int:
        if self.client is None:
            return 1
        return max(1, len(self.client.scheduler_info()["workers"]))

    def _distributed(self, fn, items, shared, on_error, bar, batch) -> list[Any]:
        from dask.distributed import as_completed, wait

        if self.client is None:
            raise RuntimeError("Engine.map outside its with-block")
        parts = batches(len(items), self.n_workers(), batch)
        # fn and shared as results of tasks that hold them (sent to the scheduler once,
        # fetched once by each worker): a worker that dies takes no only copy with it,
        # the scheduler makes it again (scattered data would be lost with it)
        fn_f = self.client.submit(_hold, _Box(fn), pure=False)
        shared_f = self.client.submit(_hold, _Box(shared), pure=False)
        futures = self.client.map(
            _call_batch, [items[s] for s in parts], fn=fn_f, shared=shared_f, pure=False
        )
        where = {f.key: s for f, s in zip(futures, parts, strict=True)}
        out: list[Any] = [None] * len(items)
        suspects: list[int] = []  # items of tasks whose worker died

        def settle(i: int, r: Any) -> None:
            if isinstance(r, _Failed):
                if on_error is None:
                    raise r.exc
                r = on_error(items[i], r.exc)
            out[i] = r

        try:
            for f in as_completed(futures):
                s = where[f.key]
                if f.status == "finished":
                    for i, r in zip(range(s.start, s.stop), f.result(), strict=True):
                        settle(i, r)
                    bar.update(s.stop - s.start)
                else:  # the task failed as a whole: its worker died (or its result broke)
                    suspects += range(s.start, s.stop)
                f.release()
            # A worker's death fails every task it held, not only the one that killed it
            # (an FMU that crashes its process): each such item again, alone on the
            # cluster, so that only an item that kills its worker by itself fails.
            for i in suspects:
                g = self.client.submit(_call_batch, [items[i]], fn=fn_f, shared=shared_f,
                                       pure=False)  # fmt: skip
                futures.append(g)
                wait([g])
                settle(i, g.result()[0] if g.status == "finished" else _Failed(g.exception()))
                g.release()
                bar.update()
        finally:
            self.client.cancel([f for f in futures if not f.done()])
            del fn_f, shared_f
        return out

    def mapper(
        self, desc: str, batch: int | None = None
    ) -> Callable[[Callable[[Any], Any], Iterable[Any]], list[Any]]:
        """A plain map(fn, items) -> list for code that knows no engine (the numerics'
        hooks): fn is sent once, the results come in the items' order."""

        def run(fn: Callable[[Any], Any], items: Iterable[Any]) -> list[Any]:
            return self.map(_apply, list(items), shared=fn, desc=desc, batch=batch)

        return run


def _apply(fn: Callable[[Any], Any], item: Any) -> Any:
    return fn(item)
