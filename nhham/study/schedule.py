"""Where a study's chunks run: in this process, or on Dask (a local cluster or a remote one).

``scheduler``:

- ``"threads"`` (the default with more than one worker for ``linearize`` and
  ``simulate``): dask's local threaded scheduler (``dask.threaded``) with ``workers``
  threads of this process: the scene and model this process prepared are shared (no
  worker starts an interpreter or builds a model), and the compiled kernels, the
  integration loop and LAPACK release the GIL (bench/RESULTS.md). No
  ``dask.distributed`` cluster is made: its scheduler and worker event loops, in this
  process, would compete with the chunks for the GIL (measured: 0.71 of two cores on the
  bicycle's map against 0.79 without them);
- ``"processes"`` (the default for ``classify``, whose per-point work is sympy and holds
  the GIL): a local cluster of ``workers`` processes with one thread each; each worker
  parses the scene and builds its model once (warmed up while this process prepares);
- ``"synchronous"`` (the default with one worker): the chunks one after the other in
  this process, without Dask;
- an address (``"tcp://host:8786"``): the scheduler of a running cluster;
- in Python, a ``dask.distributed.Client`` (``client=``) is used as it is.

A :class:`Pool` is started before the study is prepared and told the scene at once
(:meth:`Pool.warm`), so each worker parses it and builds its model while this process
makes the study's own decisions; each chunk is then one task ``evaluate(study, region)``
with the :class:`~nhham.study.tasks.Study` (plain data) scattered to the workers once.
Results are handed to ``on_result`` in the order they finish, so the caller writes each
one as it comes.
"""

from __future__ import annotations

import logging
import os
import time
from functools import partial

from nhham.errors import BudgetExceeded, InputError, OptionalDependencyError
from nhham.study.tasks import evaluate, warm

__all__ = ["Pool", "SCHEDULERS", "default_workers"]

#: The local schedulers (anything else is an address of a cluster's scheduler).
SCHEDULERS = ("processes", "threads", "synchronous")


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


class Pool:
    """The workers of one study (see the module docstring); a context manager.

    Attributes
    ----------
    scheduler : str
        ``"synchronous"``, ``"processes"``, ``"threads"`` or the cluster's address.
    workers : int
    client : dask.distributed.Client or None
    """

    def __init__(self, scheduler: str, workers: int, client=None, owned=()):
        self.scheduler, self.workers, self.client = scheduler, workers, client
        self._owned = list(owned)
        self._warming: list = []

    @classmethod
    def start(cls, scheduler: str | None = None, workers: int | None = None,
              client=None, local: str = "threads") -> "Pool":
        """Start the workers (a local cluster is made here; an address is connected to);
        ``local``: the scheduler when none is named and there is more than one worker."""
        workers = default_workers() if workers is None else int(workers)
        if workers < 1:
            raise InputError(f"--workers: at least 1, got {workers}", key="--workers")
        if client is None and scheduler is None:
            scheduler = "synchronous" if workers == 1 else local
        if client is None and scheduler == "synchronous":
            return cls("synchronous", 1)
        if client is None and scheduler == "threads":
            return cls("threads", workers)
        scheduler = str(scheduler)
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise OptionalDependencyError(
                "a study on Dask needs dask.distributed; install the study extra: pip "
                "install 'nhham[study]' (or run with --workers 1)") from None
        if client is not None:
            return cls(str(client.scheduler.address), _count(client, workers), client)
        if scheduler == "processes":
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1,
                                   processes=True, dashboard_address=None,
                                   # the workers' heartbeats failing while the cluster
                                   # closes are logged as errors: not the user's concern
                                   silence_logs=logging.CRITICAL)
            client = Client(cluster)
            return cls(scheduler, workers, client, owned=(client, cluster))
        try:
            client = Client(scheduler, timeout="30s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(f"--scheduler: cannot reach {scheduler!r} ({exc}); give "
                             f"'processes', 'threads', 'synchronous' or the address of a "
                             f"running dask scheduler", key="--scheduler") from None
        return cls(scheduler, _count(client, workers), client, owned=(client,))

    def warm(self, scene_text: str, source: str, what: str) -> None:
        """Have every worker parse the scene and build its model now (not waited for)."""
        if self.client is None:  # threads share this process's model
            return
        for address in self.client.scheduler_info().get("workers", {}):
            self._warming.append(self.client.submit(
                warm, scene_text, source, what, workers=[address], allow_other_workers=False,
                pure=False))

    def run(self, study, regions, on_result, deadline: float | None = None) -> None:
        """Evaluate ``study`` on every region; ``on_result(region, data)`` as each finishes.

        ``deadline``: a ``time.perf_counter()`` value after which no result is waited for:
        the chunks not finished are cancelled and
        :class:`~nhham.errors.BudgetExceeded` is raised (what finished before was
        handed to ``on_result``).
        """
        if self.scheduler == "synchronous":
            for region in regions:
                if deadline is not None and time.perf_counter() > deadline:
                    raise BudgetExceeded("the study's --budget ran out")
                on_result(region, evaluate(study, region))
            return
        if self.client is None:
            self._run_threads(study, regions, on_result, deadline)
            return
        from dask.distributed import as_completed

        shared = self.client.scatter(study, broadcast=True)
        futures = {self.client.submit(evaluate, shared, region, pure=False): region
                   for region in regions}
        try:
            timeout = None if deadline is None else max(0.0, deadline - time.perf_counter())
            for future in as_completed(futures, timeout=timeout):
                on_result(futures[future], future.result())
        except TimeoutError:
            raise BudgetExceeded("the study's --budget ran out") from None
        finally:
            self.client.cancel(list(futures))

    def _run_threads(self, study, regions, on_result, deadline) -> None:
        """The chunks on dask's threaded scheduler, each result handed over (in this
        thread) as it finishes and then dropped from dask's cache, so that a study's
        results are never all in memory at once. The deadline is looked at as each chunk
        finishes (a chunk is a fraction of a second to a few seconds of work)."""
        import dask.threaded

        tasks = {("nhham-chunk", i): (partial(evaluate, study, region),)
                 for i, region in enumerate(regions)}

        def finished(key, result, dsk, state, worker_id):
            state["cache"][key] = None   # written: dask need not keep it
            on_result(regions[key[1]], result)
            if deadline is not None and time.perf_counter() > deadline:
                raise BudgetExceeded("the study's --budget ran out")

        # callbacks as get_async documents them: (start, start_state, pretask, posttask,
        # finish); not the global dask.callbacks.Callback, which other threads would see
        dask.threaded.get(tasks, list(tasks), num_workers=self.workers,
                          callbacks=[(None, None, None, finished, None)])

    def close(self) -> None:
        if self.client is not None and self._warming:
            self.client.cancel(self._warming)
        for thing in self._owned:
            try:
                thing.close()
            except Exception:  # pragma: no cover - closing must not hide the result
                pass
        self._owned = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _count(client, asked) -> int:
    return len(client.scheduler_info().get("workers", {})) or asked
