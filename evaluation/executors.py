"""Where a sweep's tasks run: in this process, in a local process pool, or on Ray.

    from evaluation.executors import run_tasks
    results = run_tasks(work, [(1,), (2,)], workers=2, ray="local")

``run_tasks`` returns the results in task order whatever ran them, so a sweep's rows (and its
``trials.csv``) are the same byte for byte on every executor. ``ray`` is ``None`` (the local process
pool), ``"local"`` (start a Ray instance on this machine with ``workers`` CPUs), ``"auto"`` (join the
cluster ``ray start`` started here) or a cluster address ``HOST:PORT``. A task that raises is never
dropped: :class:`TaskError` names it; Ray retries a task whose worker died (``MAX_RETRIES`` times).
Ray is an optional extra (``pip install .[ray]``).
"""
from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import socket
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any

from cbm import Cancelled

from .stop import Stopped

MAX_RETRIES = 2
"""Times Ray reruns a task whose worker process or node died (an exception the task raises is not retried)."""
CONNECT_TIMEOUT_S = 10.0
"""Seconds to wait for a cluster address to answer before giving up."""


class ExecutorError(RuntimeError):
    """The executor cannot run: Ray missing, or its cluster unreachable (one line for the user)."""


class TaskError(RuntimeError):
    """A task raised: the message names the task and the error."""


def run_tasks(fn: Callable[..., Any], tasks: Sequence[tuple], *, workers: int = 1, ray: str | None = None,
              done: Callable[[Any], None] | None = None, name: Callable[[tuple], str] = repr) -> list[Any]:
    """``fn(*task)`` of every task, in task order. ``done(result)`` is called as each task finishes
    (in completion order); ``name(task)`` names a task that raised in the :class:`TaskError`."""
    done = done or (lambda result: None)
    if ray is not None:
        with ray_session(ray, workers):
            return _run_on_ray(fn, tasks, done, name)
    if workers <= 1:
        return [_finished(_call(fn, task, name), done) for task in tasks]
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        started: list[multiprocessing.process.BaseProcess] = []
        try:
            with ctrl_c_held():
                before = set(multiprocessing.active_children())
                futures = {pool.submit(fn, *task): i for i, task in enumerate(tasks)}
                started = [p for p in multiprocessing.active_children() if p not in before]
            results: list[Any] = [None] * len(tasks)
            for future in as_completed(futures):
                i = futures[future]
                results[i] = _finished(_result(future.result, tasks[i], name), done)
            return results
        except BaseException:
            stop_pool(pool, started)
            raise


@contextlib.contextmanager
def ctrl_c_held() -> Iterator[None]:
    """SIGINT blocked while the pool starts its workers (``submit`` spawns them): they inherit the
    block, so Ctrl-C, sent to the whole process group, reaches the parent only, which ends them
    (``stop_pool``). A Ctrl-C meanwhile is delivered to the parent when the block lifts."""
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def stop_pool(pool: ProcessPoolExecutor, workers: Sequence[multiprocessing.process.BaseProcess],
              grace_s: float = 1.0) -> None:
    """End ``pool`` now (a stop signal or a failed task): its ``workers`` (the processes it started,
    ``multiprocessing.active_children`` before and after its tasks were submitted) terminated,
    killed if still alive after ``grace_s``, none left orphaned; then the pool shut down with its
    pending tasks cancelled, waiting at most ``grace_s`` for its manager thread.

    The manager thread holds the last references to the pool's queues: left running, it releases
    their semaphores (unlink, then tell multiprocessing's resource tracker) while the process exits,
    and an exit between the two makes the tracker warn of "leaked semaphore objects". With its
    workers gone it finds the pool broken and ends; ``shutdown(wait=True)`` joins it (in a helper
    thread, so that a manager that hangs cannot hold the stop). Only public API: no pool internals."""
    for process in workers:
        process.terminate()
    deadline = time.monotonic() + grace_s
    for process in workers:
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            process.kill()
            process.join()
    closing = threading.Thread(target=pool.shutdown, kwargs={"wait": True, "cancel_futures": True},
                               name="pool-shutdown", daemon=True)
    closing.start()
    closing.join(grace_s)


def _finished(result: Any, done: Callable[[Any], None]) -> Any:
    done(result)
    return result


def _call(fn: Callable[..., Any], task: tuple, name: Callable[[tuple], str]) -> Any:
    return _result(lambda: fn(*task), task, name)


def _result(get: Callable[[], Any], task: tuple, name: Callable[[tuple], str]) -> Any:
    try:
        return get()
    except Cancelled:
        raise
    except Exception as error:
        raise TaskError(f"task {name(task)} failed: {type(error).__name__}: {error}") from error


def _run_on_ray(fn: Callable[..., Any], tasks: Sequence[tuple], done: Callable[[Any], None],
                name: Callable[[tuple], str]) -> list[Any]:
    """Submit every task, then collect them with ``ray.wait`` as they finish (progress across the
    cluster). A stop signal is raised as itself (``stop_within``) and cancels nothing (``ray_session``)."""
    import ray

    pending: list[Any] = []
    try:
        remote = ray.remote(max_retries=MAX_RETRIES)(fn)
        shared = [ray.put(arg) for arg in _shared_arguments(tasks)]
        refs = [remote.remote(*_with_shared(task, shared)) for task in tasks]
        index = {ref: i for i, ref in enumerate(refs)}
        results: list[Any] = [None] * len(tasks)
        pending = list(refs)
        while pending:
            ready, pending = ray.wait(pending, num_returns=1, timeout=WAIT_S)
            for ref in ready:
                results[index[ref]] = _finished(_ray_result(ray, ref, tasks[index[ref]], name), done)
    except BaseException as error:
        stop = stop_within(error)
        if stop is not None:
            raise stop from None
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    return results


WAIT_S = 0.2
"""Seconds one ``ray.wait`` may last: a stop signal's exception surfaces from it within this."""


def stop_within(error: BaseException) -> Stopped | None:
    """The stop signal behind ``error``: itself, or the one Ray's compiled code turned into another
    exception (our handler raises :class:`Stopped` from where Ray checks for signals, inside
    ``ray.wait``, and Ray answers ``SystemError: ... returned a result with an exception set``:
    status 1 and a traceback, issue 50, item 7)."""
    seen: set[int] = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, Stopped):
            return error
        seen.add(id(error))
        error = error.__cause__ or error.__context__
    return None


def _shared_arguments(tasks: Sequence[tuple]) -> list[Any]:
    """The first argument when every task shares it (a sweep): stored once in Ray's object store."""
    first = tasks[0][0] if tasks and tasks[0] else None
    return [first] if first is not None and all(task and task[0] is first for task in tasks) else []


def _with_shared(task: tuple, shared: list[Any]) -> tuple:
    return (shared[0], *task[1:]) if shared else task


def _ray_result(ray: Any, ref: Any, task: tuple, name: Callable[[tuple], str]) -> Any:
    try:
        return ray.get(ref)
    except ray.exceptions.RayTaskError as error:
        cause = error.cause if error.cause is not None else error
        raise TaskError(f"task {name(task)} failed: {type(cause).__name__}: {cause}") from None
    except ray.exceptions.RayError as error:
        first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise TaskError(f"task {name(task)} failed on the cluster after {MAX_RETRIES} retries: {first}") from None


@contextlib.contextmanager
def ray_session(address: str | None, workers: int = 1) -> Iterator[None]:
    """Ray connected for the block (nothing when ``address`` is None): ``"local"`` starts a quiet
    local instance with ``workers`` CPUs, ``"auto"`` or ``HOST:PORT`` joins a cluster. A session
    already open is reused and left open; one this call opened is shut down after the block.

    Except after a stop signal (:class:`Stopped`): then no Ray call is made, neither a forced
    cancel nor ``ray.shutdown`` (issue 50, item 7: a forced cancel whose task then completes trips
    Ray's "Tried to complete task that was not pending" check, and a shutdown still running when
    the stop's deadline kills the instance ends the process with status 1 and Ray's crash report;
    the shutdown also ends the raylet first, leaving its dashboard and runtime-env agents to
    outlive the command). The command ends at once instead (``evaluation.cli.exit_now``), killing
    the whole local instance, its tree intact, with every other process it started; a cluster
    ends the tasks of a driver that is gone."""
    if address is None:
        yield
        return
    ray = import_ray()
    if address not in ("local", "auto"):
        check_reachable(address)
    if ray.is_initialized():
        yield
        return
    with stop_handlers_kept():
        _connect(ray, address, workers)
    try:
        yield
    except (Stopped, KeyboardInterrupt):
        raise
    except BaseException:
        ray.shutdown()
        raise
    ray.shutdown()


@contextlib.contextmanager
def stop_handlers_kept() -> Iterator[None]:
    """This process's SIGINT and SIGTERM handlers put back after the block: ``ray.init`` replaces
    SIGTERM's with one that exits at once, which would skip a clean stop (``evaluation.stop``)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    kept = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for signum, handler in kept.items():
            if handler is not None:
                signal.signal(signum, handler)


def import_ray() -> Any:
    """The ``ray`` module (imported with ``NO_CRASH_HANDLER``, which it reads once, on import), or
    :class:`ExecutorError` saying how to install it."""
    os.environ.update(NO_CRASH_HANDLER)
    try:
        import ray
    except ImportError:
        raise ExecutorError("--ray needs Ray, which is not installed: pip install .[ray]") from None
    return ray


NO_CRASH_HANDLER = {"RAY_DISABLE_FAILURE_SIGNAL_HANDLER": "1"}
"""Ray's core worker otherwise installs, in the middle of ``ray.init``, a C++ handler for SIGTERM
(among the crash signals) over Python's: a stop signal between then and the end of ``ray.init``
printed Ray's crash report ("*** SIGTERM received ...", then its stack) and could end the process
at once with the signal's default action, status -15 (issue 50, item 7: 5 of 16 stops reported,
2 of 8 stops 7-8 s into a run measured here). Set for this process and so for the instance's
processes it starts; a crash of theirs is still reported to the run as a failed task."""


def _connect(ray: Any, address: str, workers: int) -> None:
    """``ray.init`` for ``address`` (Python's signal handlers left in place: ``NO_CRASH_HANDLER``);
    a SIGTERM during it (Ray's own handler turns it into ``SystemExit(15)``) is raised as
    :class:`evaluation.stop.Stopped`, the same stop as anywhere else."""
    quiet = {"log_to_driver": False, "logging_level": "ERROR"}
    try:
        if address == "local":
            ray.init(num_cpus=max(1, workers), include_dashboard=False, **quiet)
        else:
            ray.init(address=address, **quiet)
    except SystemExit as exit:
        if exit.code == signal.SIGTERM:
            raise Stopped(signal.SIGTERM) from None
        raise
    except (ConnectionError, RuntimeError, ValueError) as error:
        first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise ExecutorError(f"--ray {address}: cannot join the Ray cluster: {first}") from None


GRPC_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
"""An HTTP/2 client's first bytes (the connection preface, then an empty SETTINGS frame): a Ray
cluster's GCS (and the Ray Client server of ``ray://``) is a gRPC server and answers with its own
SETTINGS frame at once; ``ray.init`` itself waits for ever on something that does not."""


def check_reachable(address: str, timeout: float = CONNECT_TIMEOUT_S) -> None:
    """:class:`ExecutorError` unless ``HOST:PORT`` (``ray://`` allowed, port 1 to 65535) accepts a
    connection and answers as a gRPC server within ``timeout`` seconds."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not host or not port.isdigit():
        raise ExecutorError(f"--ray {address}: expected local, auto or HOST:PORT")
    if not 1 <= int(port) <= 65535:
        raise ExecutorError(f"--ray {address}: the port must be between 1 and 65535, got {int(port)}")
    deadline = time.monotonic() + timeout
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout) as connection:
            reply = _first_frame(connection, deadline)
    except OSError as error:
        raise ExecutorError(f"--ray {address}: the Ray cluster is unreachable ({error.strerror or error})") from None
    if reply is None:
        raise ExecutorError(f"--ray {address}: something listens there but does not answer as a Ray cluster "
                            f"(no gRPC reply within {timeout:g} s); give the head's GCS address (6379 by default)")
    if len(reply) < 9 or reply[3] != 4:
        raise ExecutorError(f"--ray {address}: something listens there but it is not a Ray cluster (its reply "
                            f"{reply!r} is not gRPC); give the head's GCS address (6379 by default)")


def _first_frame(connection: socket.socket, deadline: float) -> bytes | None:
    """The first 9 bytes (an HTTP/2 frame header) the server sends after :data:`GRPC_PREFACE`;
    fewer when it closes, None when it says nothing before ``deadline``."""
    connection.sendall(GRPC_PREFACE)
    reply = b""
    while len(reply) < 9:
        connection.settimeout(max(0.01, deadline - time.monotonic()))
        try:
            chunk = connection.recv(9 - len(reply))
        except TimeoutError:
            return None
        if not chunk:
            break
        reply += chunk
    return reply
