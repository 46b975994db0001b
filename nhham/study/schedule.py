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
- an address (``"tcp://host:8786"``, ``"tls://host:8786"``): the scheduler of a running
  cluster. What the cluster sends back (the chunks' results) is unpickled in this
  process: a scheduler or worker that is hostile or compromised runs code here, and on
  ``tcp://`` the scene, design and options travel in clear text. ``tls://`` encrypts and
  authenticates with the certificates of the user's dask configuration
  (``distributed.comm.tls``: ``ca-file``, ``client.cert``, ``client.key``; read by
  ``distributed.Security``); a plain ``tcp://`` address that is not this machine's
  (loopback) is warned about once. Other schemes (``ucx://``, ``inproc://``) are refused;
- in Python, a ``dask.distributed.Client`` (``client=``) is used as it is.

``workers`` is at most :func:`max_workers` (four per core available, at least 8).

Ctrl-C during a study (SIGINT to the process group or to this process alone), from the
start of its workers on: the workers of a local cluster are started with SIGINT blocked
(only this process answers it; :func:`_started_apart`), and on the interrupt they are
killed, not closed politely (a polite close waits on workers in the middle of a chunk);
:meth:`Pool.abandon`. An interrupt while the cluster starts waits for the start to end
(a second or two), then kills its workers.

A :class:`Pool` is started before the study is prepared and told the scene at once
(:meth:`Pool.warm`), so each worker parses it and builds its model while this process
makes the study's own decisions; each chunk is then one task ``evaluate(study, region)``
with the :class:`~nhham.study.tasks.Study` (plain data) scattered to the workers once.
Results are handed to ``on_result`` in the order they finish, so the caller writes each
one as it comes.
"""

from __future__ import annotations

import ipaddress
import logging
import os
import re
import signal
import threading
import time
import warnings
from functools import partial

from nhham import progress
from nhham.errors import BudgetExceeded, InputError, NhhamWarning, OptionalDependencyError
from nhham.study.stop import resume_chunks, stop_chunks
from nhham.study.tasks import evaluate, warm

__all__ = ["Pool", "SCHEDULERS", "SCHEMES", "default_workers", "max_workers",
           "check_scheduler"]

#: The local schedulers (anything else is an address of a cluster's scheduler).
SCHEDULERS = ("processes", "threads", "synchronous")

#: The address schemes of a remote scheduler a study connects to.
SCHEMES = ("tcp", "tls")

#: Seconds a connection to a remote scheduler is tried without a --budget.
CONNECT_TIMEOUT_S = 30.0

_ADDRESS = re.compile(r"^(?:([A-Za-z][A-Za-z0-9+.-]*)://)?(\[[^\]]+\]|[^:/\[\]]+)(?::(\d+))?/?$")


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def max_workers() -> int:
    """The most local workers a study starts: four per core available, at least 8
    (``--workers 100000`` would ask for as many processes)."""
    return max(8, 4 * default_workers())


def check_scheduler(scheduler: str | None, workers: int | None,
                    warn: bool = True) -> str | None:
    """The scheme of a remote scheduler's address (None for a local one); refuses a
    scheme that is not supported, an address that is not one, and too many workers;
    warns (``warn``) about a plain ``tcp://`` address off this machine.

    Raises
    ------
    InputError
        Naming ``--scheduler`` or ``--workers``.
    """
    if workers is not None:
        if int(workers) < 1:
            raise InputError(f"--workers: at least 1, got {workers}", key="--workers")
        if int(workers) > max_workers():
            raise InputError(f"--workers: at most {max_workers()} local workers here (four "
                             f"per core available, at least 8), got {workers}; a larger "
                             f"cluster is a running dask scheduler (--scheduler ADDRESS)",
                             key="--workers")
    if scheduler is None or scheduler in SCHEDULERS:
        return None
    match = _ADDRESS.match(str(scheduler).strip())
    scheme = (match.group(1) or "tcp").lower() if match else None
    if match is None or (match.group(1) is None and match.group(3) is None):
        raise InputError(f"--scheduler: {scheduler!r} is neither {', '.join(SCHEDULERS)} "
                         f"nor the address of a dask scheduler (tcp://host:port, "
                         f"tls://host:port)", key="--scheduler")
    if scheme not in SCHEMES:
        raise InputError(f"--scheduler: the address scheme {scheme}:// is not supported (give "
                         f"tls://host:port, or tcp://host:port on a trusted network)",
                         key="--scheduler")
    if warn and scheme == "tcp" and not _loopback(match.group(2)):
        warnings.warn(f"--scheduler {scheduler}: a plain tcp:// address off this machine: "
                      f"the scene and options travel in clear text and the results the "
                      f"cluster sends back are unpickled here (a compromised scheduler runs "
                      f"code in this process); use tls:// with certificates in your dask "
                      f"configuration", NhhamWarning, stacklevel=2)
    return scheme


def _loopback(host: str) -> bool:
    host = host.strip("[]")
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:   # a host name: not resolved here (that may hang); not loopback
        return False


def _security(scheduler: str):
    """The ``distributed.Security`` of a ``tls://`` address: the certificates of the
    user's dask configuration (refused without them)."""
    from distributed import Security

    security = Security()
    if not (getattr(security, "tls_ca_file", None)
            and getattr(security, "tls_client_cert", None)):
        raise InputError(f"--scheduler: {scheduler} is a TLS address, and your dask "
                         f"configuration has no TLS certificates (set distributed.comm.tls."
                         f"ca-file, .client.cert and .client.key, e.g. in "
                         f"~/.config/dask/distributed.yaml)", key="--scheduler")
    return security


def _started_apart(make):
    """``make()`` (the start of a local cluster and its client) run in a thread of its own
    whose SIGINT is blocked, while this thread waits for it.

    The block is inherited by the threads the start makes (the cluster's event loop, the
    nannies' process starters) and by the worker processes, through fork and exec (as
    multiprocessing's resource tracker is protected): Ctrl-C is this process's alone to
    answer and no worker prints a traceback, while this thread keeps its handler. A
    Ctrl-C during the start raises KeyboardInterrupt here: the start is waited for (a
    second Ctrl-C stops the wait; the workers exit with this process, which they watch),
    its workers killed and its client and cluster closed without waiting, and the
    interrupt goes on.
    """
    made: dict = {}
    # an Event, not Thread.join: a join interrupted by Ctrl-C takes the thread for
    # stopped (Python 3.11, bpo-45274), and a second join would not wait
    ended = threading.Event()

    def start():
        if hasattr(signal, "pthread_sigmask"):   # not on Windows
            signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            made["value"] = make()
        except BaseException as exc:   # handed to the waiting thread
            made["error"] = exc
        finally:
            ended.set()

    threading.Thread(target=start, name="nhham: start a local cluster", daemon=True).start()
    try:
        ended.wait()
    except KeyboardInterrupt:
        ended.wait()
        if "value" in made:
            Pool("processes", 0, made["value"][0], owned=made["value"]).abandon()
        raise
    if "error" in made:
        raise made["error"]
    return made["value"]


def _quiet_resource_tracker() -> None:
    """Start multiprocessing's resource tracker with its leak warning off: the workers of
    a local cluster killed on Ctrl-C leave semaphores that the tracker reports on stderr
    when nhham exits, after the one line `nhham: interrupted` (it cleans them up all the
    same). The tracker takes its warning filters from this interpreter's -W options when
    it starts; a tracker already running is left as it is."""
    import sys

    try:
        from multiprocessing import resource_tracker
    except ImportError:   # pragma: no cover - no tracker on this platform
        return
    option = "ignore::UserWarning:multiprocessing.resource_tracker"
    sys.warnoptions.append(option)
    try:
        resource_tracker.ensure_running()
    except OSError:   # pragma: no cover - it starts again where it is needed
        pass
    finally:
        sys.warnoptions.remove(option)


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
              client=None, local: str = "threads", deadline: float | None = None) -> "Pool":
        """Start the workers (a local cluster is made here; an address is connected to);
        ``local``: the scheduler when none is named and there is more than one worker;
        ``deadline`` (a ``time.perf_counter()``): the connection to an address is not
        tried beyond it (:class:`~nhham.errors.BudgetExceeded`)."""
        scheme = check_scheduler(scheduler, workers)
        workers = default_workers() if workers is None else int(workers)
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
            _quiet_resource_tracker()

            def local_cluster():
                cluster = LocalCluster(n_workers=workers, threads_per_worker=1,
                                       processes=True, dashboard_address=None,
                                       # the workers' heartbeats failing while the
                                       # cluster closes are logged as errors: not the
                                       # user's concern
                                       silence_logs=logging.CRITICAL)
                return Client(cluster), cluster

            processes = "1 worker process" if workers == 1 else f"{workers} worker processes"
            with progress.part(f"start a local Dask cluster of {processes}"):
                client, cluster = _started_apart(local_cluster)
            return cls(scheduler, workers, client, owned=(client, cluster))
        security = _security(scheduler) if scheme == "tls" else None
        timeout = CONNECT_TIMEOUT_S
        if deadline is not None:
            timeout = min(timeout, max(deadline - time.perf_counter(), 0.1))
        try:
            client = Client(scheduler, timeout=timeout, security=security)
        except Exception as exc:   # unreachable, or what answers is not a dask scheduler
            if deadline is not None and time.perf_counter() >= deadline - 0.05:
                raise BudgetExceeded(f"the study's --budget ran out while connecting to "
                                     f"the scheduler at {scheduler}") from None
            raise InputError(f"--scheduler: cannot reach {scheduler!r} ({type(exc).__name__}: "
                             f"{exc}); give "
                             f"'processes', 'threads', 'synchronous' or the address of a "
                             f"running dask scheduler", key="--scheduler") from None
        return cls(scheduler, _count(client, workers), client, owned=(client,))

    def warm(self, scene_text: str, source: str, what: str, values: tuple = ()) -> None:
        """Have every worker parse the scene (with the parameter ``values``, pairs) and
        build its model now (not waited for)."""
        if self.client is None:  # threads share this process's model
            return
        for address in self.client.scheduler_info().get("workers", {}):
            self._warming.append(self.client.submit(
                warm, scene_text, source, what, values, workers=[address],
                allow_other_workers=False, pure=False))

    def run(self, study, regions, on_result, deadline: float | None = None) -> None:
        """Evaluate ``study`` on every region; ``on_result(region, data)`` as each finishes.

        ``deadline``: a ``time.perf_counter()`` value after which no result is waited for
        and the chunks' runs stop: the chunks not finished are cancelled and
        :class:`~nhham.errors.BudgetExceeded` is raised (what finished before was
        handed to ``on_result``).
        """
        resume_chunks()
        until = None if deadline is None else time.time() + (deadline - time.perf_counter())
        if self.scheduler == "synchronous":
            for region in regions:
                if deadline is not None and time.perf_counter() > deadline:
                    raise BudgetExceeded("the study's --budget ran out")
                on_result(region, evaluate(study, region, until))
            return
        if self.client is None:
            self._run_threads(study, regions, on_result, deadline, until)
            return
        from dask.distributed import as_completed

        shared = self.client.scatter(study, broadcast=True)
        futures = {self.client.submit(evaluate, shared, region, until, pure=False): region
                   for region in regions}
        try:
            timeout = None if deadline is None else max(0.0, deadline - time.perf_counter())
            for future in as_completed(futures, timeout=timeout):
                on_result(futures[future], future.result())
        except TimeoutError:
            raise BudgetExceeded("the study's --budget ran out") from None
        except KeyboardInterrupt:
            raise   # abandon(): the cluster is not asked for anything more
        except BaseException:
            self.client.cancel(list(futures))
            raise
        self.client.cancel(list(futures))

    def _run_threads(self, study, regions, on_result, deadline, until) -> None:
        """The chunks on dask's threaded scheduler, each result handed over (in this
        thread) as it finishes and then dropped from dask's cache, so that a study's
        results are never all in memory at once. The deadline is looked at as each chunk
        finishes, and by a simulation's runs."""
        import dask.threaded

        tasks = {("nhham-chunk", i): (partial(evaluate, study, region, until),)
                 for i, region in enumerate(regions)}

        def finished(key, result, dsk, state, worker_id):
            state["cache"][key] = None   # written: dask need not keep it
            on_result(regions[key[1]], result)
            if deadline is not None and time.perf_counter() > deadline:
                raise BudgetExceeded("the study's --budget ran out")

        # callbacks as get_async documents them: (start, start_state, pretask, posttask,
        # finish); not the global dask.callbacks.Callback, which other threads would see
        try:
            dask.threaded.get(tasks, list(tasks), num_workers=self.workers,
                              callbacks=[(None, None, None, finished, None)])
        except BaseException:
            stop_chunks()   # the threads still in a chunk end it now
            raise

    def abandon(self) -> None:
        """After Ctrl-C: stop at once. The chunks running in this process stop; the
        worker processes of a local cluster made here are killed (a polite close waits
        for their chunks, or for workers that are gone); a remote cluster is left
        (closing the client releases its tasks there), without waiting for an answer."""
        stop_chunks()
        if self.client is None:
            return
        cluster = next((c for c in self._owned if c is not self.client), None)
        if cluster is not None:
            _silence_distributed()
            _kill_workers(cluster)
        self._warming = []
        owned, self._owned = self._owned, []
        closer = threading.Thread(target=_close_quietly, args=(owned, 2.0), daemon=True)
        closer.start()
        closer.join(timeout=0.5)

    def close(self) -> None:
        if self.client is not None and self._warming:
            self.client.cancel(self._warming)
        _close_quietly(self._owned)
        self._owned = []

    def __enter__(self):
        return self

    def __exit__(self, exc_type, *exc):
        # Ctrl-C anywhere in the study (its preparation too): nothing waits on workers
        if exc_type is not None and issubclass(exc_type, KeyboardInterrupt):
            self.abandon()
        else:
            self.close()


def _silence_distributed() -> None:
    """Turn off dask.distributed's logging in this process: the scheduler of a local
    cluster whose workers are killed logs each closed connection at CRITICAL, with a
    traceback, after the one line `nhham: interrupted`. Nothing it says then concerns the
    user, whose study stopped; it stays off for the rest of the process (which, for the
    command, ends now)."""
    for name in ["distributed", *logging.root.manager.loggerDict]:
        if name == "distributed" or name.startswith("distributed."):
            logging.getLogger(name).setLevel(logging.CRITICAL + 1)


def _kill_workers(cluster) -> None:
    """SIGKILL the worker processes of a local cluster (their nannies live here). Each
    nanny is marked closing first: a running nanny starts another worker in place of one
    that died, whose start this process, exiting, would cut short (the new worker then
    prints a traceback after `nhham: interrupted`)."""
    from distributed.core import Status

    for nanny in list(getattr(cluster, "workers", {}).values()):
        if hasattr(nanny, "status"):
            nanny.status = Status.closing
        pid = getattr(getattr(getattr(nanny, "process", None), "process", None), "pid", None)
        if pid:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:   # already gone
                pass


def _close_quietly(things, timeout: float | None = None) -> None:
    """Close clients and clusters (within ``timeout`` seconds each, if given); an error
    while closing must not hide the result."""
    for thing in things:
        try:
            if timeout is not None and _takes_timeout(thing):
                thing.close(timeout=timeout)
            else:
                thing.close()
        except BaseException:  # pragma: no cover - closing must not hide the result
            pass


def _takes_timeout(thing) -> bool:
    import inspect

    try:
        return "timeout" in inspect.signature(thing.close).parameters
    except (TypeError, ValueError):
        return False


def _count(client, asked) -> int:
    return len(client.scheduler_info().get("workers", {})) or asked
