"""Where a fleet's files are analysed (:mod:`gyrofilter.analysis.fleet`): local worker
processes, or a Dask distributed cluster (the ``[cluster]`` extra). Both yield ``(index, result)``
of :func:`gyrofilter.analysis.fleet.work.analyse_recording` as files finish."""
from __future__ import annotations

import asyncio
import contextlib
import multiprocessing
import os
import signal
import threading
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool

from ...errors import MissingExtraError, SettingsError, one_line
from ...extras import install_hint, require
from ...inputs import quote
from .work import analyse_recording, failed


#: environment of local worker processes: one thread per numeric library, as many workers as cores
#: (two workers with a BLAS thread pool each on 2 cores: 1.8x slower); a value set already is kept
WORKER_ENVIRONMENT = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


#: longest wait (s) for a Dask scheduler to answer (``--scheduler``): the connection and Dask's
#: handshake, which Dask itself would wait for without end
SCHEDULER_TIMEOUT_S = 10.0


#: how often (s) a local worker process checks that the process that started it is still there
PARENT_POLL_S = 0.5


def default_jobs():
    """The CPU cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def run_local(paths, settings, jobs):
    """Yield ``(index, result)`` of :func:`analyse_recording` (with ``settings``) for each of ``paths`` as it
    finishes, in ``jobs`` worker processes (:class:`~concurrent.futures.ProcessPoolExecutor`).

    ``jobs=1`` runs in one worker process too: every backend computes with one thread per
    numeric library (:data:`WORKER_ENVIRONMENT`, Dask's default for its workers), because a
    multi-threaded BLAS sums in another order and the last bits of some results would depend on
    where they ran. A worker that dies (killed, out of memory) fails the files it had, with that
    reason. When the caller stops (Ctrl-C, an error) the workers are ended at once, not after
    their current file; when the calling process dies (SIGKILL), each worker ends by itself within
    :data:`PARENT_POLL_S` seconds (:func:`_worker_init`)."""
    # fresh processes (not forks of this one and its thread pools) that start with WORKER_ENVIRONMENT
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_worker_init, initargs=(os.getpid(),))
    try:
        with _worker_environment():  # the workers start during the first submits
            futures = {pool.submit(analyse_recording, path, settings): i for i, path in enumerate(paths)}
        for future in as_completed(futures):
            i = futures[future]
            try:
                result = future.result()
            except BrokenProcessPool:
                result = failed(paths[i], "a worker process ended abruptly (killed, or out of memory: "
                                          "try a smaller --jobs)")
            yield i, result
    except BaseException:  # Ctrl-C, an error, or the caller closed this generator: end the workers now
        processes = list((pool._processes or {}).values())  # no public way before Python 3.14
        pool.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            process.terminate()
        raise
    pool.shutdown()


@contextlib.contextmanager
def _worker_environment():
    """Set the variables of :data:`WORKER_ENVIRONMENT` that are not set, for processes started
    inside the block; restore the environment after it."""
    added = {k: v for k, v in WORKER_ENVIRONMENT.items() if k not in os.environ}
    os.environ.update(added)
    try:
        yield
    finally:
        for key in added:
            os.environ.pop(key, None)


def _worker_init(parent_pid):
    """Set up a local worker process: Ctrl-C is left to the parent, which ends the workers
    (:func:`run_local`), and a daemon thread ends the worker at once (``os._exit``) when the
    parent ``parent_pid`` is gone: a killed parent cannot end its workers, which would otherwise
    finish their file and then wait for work for ever. The check, every :data:`PARENT_POLL_S`
    seconds, compares ``os.getppid()`` with ``parent_pid`` (an orphan is adopted by another
    process), which works wherever Python runs."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_exit_with_parent, args=(parent_pid,), name="gyrofilter-parent-watch",
                     daemon=True).start()


def _exit_with_parent(parent_pid):
    while os.getppid() == parent_pid:
        time.sleep(PARENT_POLL_S)
    os._exit(1)


def run_dask(paths, settings, address, timeout_s=None):
    """Connect to the Dask distributed cluster whose scheduler is at ``address``, then return an
    iterator that yields ``(index, result)`` of :func:`analyse_recording` (with ``settings``) for
    each of ``paths`` as it finishes there (``dask.distributed.Client.map``). The workers read the
    files at the same paths, so the paths must name the same files on every worker (a shared file
    system). A file whose task killed its workers (Dask's ``KilledWorker``) fails with that reason.

    SettingsError, before any work, when no Dask scheduler answers at ``address`` within
    ``timeout_s`` seconds (default :data:`SCHEDULER_TIMEOUT_S`): nothing listening, a server of
    another protocol (an HTTP server), one that never answers, a malformed address."""
    distributed = _distributed()
    client = _connect(distributed, address, SCHEDULER_TIMEOUT_S if timeout_s is None else timeout_s)
    return _dask_results(distributed, client, paths, settings)


def _connect(distributed, address, timeout_s):
    """A ``distributed.Client`` of the scheduler at ``address``, or SettingsError in one line.

    Dask's own connect waits for the peer's handshake without a time limit and sizes its buffer
    from the peer's first 8 bytes (an HTTP server's make 3 EiB: MemoryError), so the handshake is
    first tried alone, under ``timeout_s`` seconds; only a peer that completes it gets a Client."""
    from distributed.comm import connect

    async def handshake():
        comm = await asyncio.wait_for(connect(address, timeout=timeout_s), timeout_s)
        await comm.close()

    try:
        asyncio.run(handshake())
        return distributed.Client(address, timeout=timeout_s)
    except Exception as exc:  # noqa: BLE001 - whatever the comm layer raises, no scheduler is there
        if isinstance(exc, (TimeoutError, asyncio.TimeoutError)):
            reason = f"no answer within {timeout_s:g} s"
        elif isinstance(exc, MemoryError):
            reason = "it answered in another protocol"
        else:
            reason = one_line(exc)[:120]
        raise SettingsError(f"--scheduler {quote(address)}: no Dask scheduler answered there ({reason})") from None


def _dask_results(distributed, client, paths, settings):
    """The results of ``paths`` on ``client``'s cluster as they finish (:func:`run_dask`); closes the client."""
    with client:
        futures = client.map(analyse_recording, paths, settings=settings, pure=False)
        index = {future.key: i for i, future in enumerate(futures)}
        for future in distributed.as_completed(futures):
            i = index[future.key]
            try:
                result = future.result()
            except distributed.KilledWorker as exc:
                result = failed(paths[i], f"the Dask workers running it died ({exc})")
            yield i, result


def _distributed():
    """``dask.distributed``, or MissingExtraError naming the ``[cluster]`` extra."""
    require("dask", "--scheduler (a Dask cluster)")
    try:
        import dask.distributed
    except ImportError:  # dask without its distributed scheduler
        raise MissingExtraError(f"--scheduler needs dask.distributed: {install_hint('cluster')}") from None
    return dask.distributed
