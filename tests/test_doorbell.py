"""The per-step handshake in shared memory (dem_region/doorbell.py): counters and values cross
between processes in order, and the orchestrator's block is gone after close."""
import multiprocessing as mp
import socket
import threading
import time
from contextlib import contextmanager
from multiprocessing import resource_tracker, shared_memory

import numpy as np
import pytest

from dem_region.doorbell import ADVANCE, DONE, ENGINE_S, GO, HOOK, MODELS_S, STEPS, Backoff, Doorbell, Readable, available


def _worker(name: str, rounds: int) -> None:
    """Answer each advance k with k hooks of k's steps each, then done k with values from k."""
    bell, wait, hooks = Doorbell(name), Backoff(), 0
    for k in range(1, rounds + 1):
        while not bell.rung(ADVANCE, k):
            wait()
        wait.reset()
        for _ in range(int(bell.value[STEPS])):
            hooks += 1
            bell.ring(HOOK, hooks)
            while not bell.rung(GO, hooks):
                wait()
            wait.reset()
        bell.ring(DONE, k, {ENGINE_S: 0.5 * k, MODELS_S: float(hooks)})
    bell.close()


def test_the_handshake_crosses_processes_in_order_and_leaves_no_block():
    bell, rounds = Doorbell(), 300
    child = mp.get_context("spawn").Process(target=_worker, args=(bell.name, rounds))
    child.start()
    try:
        wait, hooks, seen = Backoff(), 0, []
        for k in range(1, rounds + 1):
            steps = 1 + k % 3
            bell.ring(ADVANCE, k, {STEPS: steps})
            while not bell.rung(DONE, k):
                if bell.rung(HOOK, hooks + 1):
                    hooks += 1
                    bell.ring(GO, hooks)
                    wait.reset()
                else:
                    wait()
            seen.append((bell.value[ENGINE_S], bell.value[MODELS_S]))
        child.join(timeout=30)
        assert child.exitcode == 0
        assert hooks == sum(1 + k % 3 for k in range(1, rounds + 1))
        # each done's values are the ones written before it, not a later round's
        assert np.allclose(seen, [(0.5 * k, sum(1 + j % 3 for j in range(1, k + 1))) for k in range(1, rounds + 1)])
    finally:
        if child.is_alive():
            child.kill()
        name = bell.name
        bell.close()
    with pytest.raises(FileNotFoundError):
        shared_memory.SharedMemory(name=name)


def test_a_long_wait_sleeps_instead_of_holding_a_core_and_a_message_ends_it():
    """Past its spin and yield rounds the backoff waits ``longest`` per round without using the
    core (process time far below wall time); waiting in a socket's select, it returns as soon
    as a message arrives."""
    import time
    from multiprocessing import Pipe
    wait = Backoff(spin=2, yield_rounds=4, longest=2e-3)
    for _ in range(4):
        wait()
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(20):
        wait()
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    assert 20 * 2e-3 <= wall < 20 * 2e-3 + 0.5 and cpu < 0.5 * wall
    a, b = Pipe()
    wait = Backoff(spin=0, yield_rounds=0, longest=5.0)
    b.send("query")
    t0 = time.perf_counter()
    assert wait(a.poll) and time.perf_counter() - t0 < 1.0


def test_with_wake_ups_a_long_wait_sleeps_until_rung_or_a_message_comes():
    """Wake-ups (eventfds handed over a socket pair, as to a worker): a waiter rung after 0.3 s
    used a small part of that time on its core and woke at once; one sleeping when a message
    comes returns True."""
    import socket
    import threading
    import time
    from dem_region.doorbell import can_wake
    if not can_wake():
        pytest.skip("no eventfds here")
    ours, theirs = socket.socketpair()
    bell = Doorbell()
    other = Doorbell(bell.name)
    try:
        bell.send_wakeups(ours.fileno())
        other.receive_wakeups(theirs.fileno())
        seen = {}

        def waiter():
            wait = Backoff(bell=other)
            t0, c0 = time.perf_counter(), time.thread_time()
            while not other.rung(ADVANCE, 1):
                wait()
            seen["woke"], seen["wall"], seen["cpu"] = time.perf_counter(), time.perf_counter() - t0, time.thread_time() - c0

        thread = threading.Thread(target=waiter)
        thread.start()
        time.sleep(0.3)
        rung_at = time.perf_counter()
        bell.ring(ADVANCE, 1)
        thread.join(timeout=5)
        assert seen["wall"] >= 0.3 and seen["cpu"] < 0.2 * seen["wall"] and seen["woke"] - rung_at < 0.05
        # asleep in the other direction, a message on the socket ends the wait
        wait = Backoff(bell=bell, spin=0, patience=0.0)
        theirs.send(b"x")
        t0 = time.perf_counter()
        while not wait(lambda timeout=0.0: False):
            assert time.perf_counter() - t0 < 1.0
    finally:
        other.close()
        bell.close()
        ours.close()
        theirs.close()


class SteppingEngine:
    """A made-up engine: counts its steps (the class's ``steps``), pauses ``pause`` s in each,
    raises at step ``fail_at``, and runs the hook after each step."""

    steps, pause, fail_at, queries = 0, 0.0, -1, 0

    def start(self, hook):
        if hook:
            hook()

    def advance(self, hook):
        type(self).steps += 1
        if type(self).steps == self.fail_at:
            raise ValueError("a bond stretched past its length")
        time.sleep(self.pause)
        if hook:
            hook()

    def energies(self):  # a query: how many times it was asked
        type(self).queries += 1
        return {"queries": type(self).queries}

    def finalize(self):
        pass


@contextmanager
def remote_in_a_thread(engine, monkeypatch):
    """The orchestrator's side (a RemoteBackend) over a socket pair against the worker's
    serve() in a thread of this process, running the made-up ``engine`` class; at the end the
    worker is told to finish and must have stopped."""
    from multiprocessing.connection import Connection

    from dem_region import backends, worker
    from dem_region.backends.remote import RemoteBackend

    class SameProcessBell(Doorbell):
        """The worker's attachment; here in the owner's process, whose registration stays (the
        owner's unlink unregisters it once)."""

        def __init__(self, name=None):
            super().__init__(name)
            if name is not None:
                resource_tracker.register(self.shm._name, "shared_memory")  # noqa: SLF001

    monkeypatch.setattr(backends, "get_backend", lambda name: engine)
    monkeypatch.setattr(worker, "Doorbell", SameProcessBell)
    ours, theirs = socket.socketpair()
    serving = threading.Thread(target=worker.serve, args=(Connection(theirs.detach()), "made-up"), daemon=True)
    serving.start()
    remote = object.__new__(RemoteBackend)  # its state without a child process
    remote.name, remote.ranks, remote.conn, remote.bell, remote.proc = "made-up", 1, Connection(ours.detach()), None, None
    remote._hooks = remote._advances = remote._evaluations = remote._steps_left = 0
    remote._dt, remote._models_pending, remote.models_s, remote.transport_s, remote.interface_s = 1e-6, False, 0.0, 0.0, 0.0
    remote._state_views, remote._prewrite, remote._wait = None, False, None
    remote._advancing, remote._replies_owed, remote._stuck = False, 0, False
    try:
        yield remote
        remote._call("finalize")
        serving.join(timeout=10)
        assert not serving.is_alive()
    finally:
        remote.conn.close()
        if remote.bell is not None:
            remote.bell.close()


def test_an_advance_that_fails_in_the_worker_is_reported_where_it_failed_and_the_next_one_runs(monkeypatch):
    """The worker's serve() against the orchestrator's RemoteBackend._run over a socket pair and
    the doorbell, with a made-up engine whose second step raises: the orchestrator raises the
    engine's message naming the line that failed, and the counters stay in step (the third
    advance runs)."""

    class Engine(SteppingEngine):
        steps, fail_at = 0, 2

    with remote_in_a_thread(Engine, monkeypatch) as remote:
        remote.start(None)
        remote.advance(None)
        with pytest.raises(RuntimeError, match=r"ValueError: a bond stretched past its length \(test_doorbell.py:\d+\)"):
            remote.advance(None)
        remote.advance(None)
        assert Engine.steps == 3 and remote._advances == 3


@pytest.mark.skipif(not available(), reason="the doorbell needs x86's store order")
def test_an_advance_of_many_steps_hooks_each_step_and_stops_where_the_orchestrators_hook_fails(monkeypatch):
    """One advance of several steps (run_clock's block up to the next sample) crosses once each
    way and runs the orchestrator's hook after every step; when that hook raises at step k,
    the worker takes no step after k, the exception reaches the caller, and the next advance
    runs from there with the counters in step."""

    class Engine(SteppingEngine):
        steps = 0

    seen = []

    def hook():
        seen.append(Engine.steps)
        if Engine.steps == 7:
            raise ArithmeticError("the far field diverged")

    with remote_in_a_thread(Engine, monkeypatch) as remote:
        remote.start(hook)
        remote.advance(hook, 5)
        assert seen == [0, 1, 2, 3, 4, 5] and remote._advances == 1
        with pytest.raises(ArithmeticError, match="diverged"):
            remote.advance(hook, 5)
        assert Engine.steps == 7 and seen[-1] == 7
        seen.clear()
        remote.advance(hook, 3)  # the next advance starts where the failed one stopped
        assert seen == [8, 9, 10] and Engine.steps == 10 and remote._advances == 3


@pytest.mark.skipif(not available(), reason="the doorbell needs x86's store order")
def test_an_interrupt_while_the_worker_advances_stops_its_advance(monkeypatch):
    """An exception in the orchestrator while it waits for an advance without hooks (an all-DEM
    run; Ctrl-C) stops the worker's advance within a step (ABORT), reaches the caller, and the
    next advance runs with the counters in step."""

    class Engine(SteppingEngine):
        steps, pause = 0, 1e-3

    class Interrupted(Backoff):
        t0, raised = None, False

        def __call__(self, poll=None):
            # once, 50 ms into the wait (its rounds are no clock: with wake-ups a round sleeps up
            # to 0.1 s; a count of 200 rounds outlasted the 10 s advance in one CI run)
            Interrupted.t0 = Interrupted.t0 or time.perf_counter()
            if not Interrupted.raised and time.perf_counter() - Interrupted.t0 > 0.05:
                Interrupted.raised = True
                raise KeyboardInterrupt
            return super().__call__(poll)

    with remote_in_a_thread(Engine, monkeypatch) as remote:
        remote.start(None)
        remote.advance(None, 2)
        assert Engine.steps == 2
        remote._wait = Interrupted(bell=remote.bell)
        with pytest.raises(KeyboardInterrupt):
            remote.advance(None, 10_000)  # 10 s of steps
        stopped = Engine.steps
        assert 2 < stopped < 2 + 10_000
        remote.advance(None, 3)
        assert Engine.steps == stopped + 3 and remote._advances == 3


@pytest.mark.skipif(not available(), reason="the doorbell needs x86's store order")
def test_an_interrupt_while_a_hook_waits_for_a_query_leaves_no_stale_reply(monkeypatch):
    """Ctrl-C while the orchestrator's hook waits for a query's reply (a sample's energies): the
    advance stops, the reply that was on its way is read off, and the next query gets its own
    answer, not that one."""

    class Engine(SteppingEngine):
        steps, queries = 0, 0

    with remote_in_a_thread(Engine, monkeypatch) as remote:
        receive = remote._recv

        def interrupted():
            monkeypatch.setattr(remote, "_recv", receive)  # once
            raise KeyboardInterrupt

        def hook():
            if Engine.steps == 3:
                monkeypatch.setattr(remote, "_recv", interrupted)
                remote._call("call", "energies")

        remote.start(None)
        with pytest.raises(KeyboardInterrupt):
            remote.advance(hook, 10)
        assert Engine.steps == 3 and Engine.queries == 1
        assert remote._call("call", "energies")[1] == {"queries": 2}


def test_a_waits_poll_of_the_socket_says_what_connection_poll_says_and_allocates_nothing_lasting():
    """doorbell.Readable, the waits' poll: False on a quiet socket, True with a message waiting
    and after the other side hung up (as Connection.poll); a call's transient Python objects stay
    under 100 bytes (Connection.poll built a selector, a few hundred: a wait's allocations then
    grew with its rounds, which made tests/test_hot_path.py's engine stage flaky)."""
    import tracemalloc
    from multiprocessing.connection import Connection
    ours, theirs = socket.socketpair()
    conn, other = Connection(ours.detach()), Connection(theirs.detach())
    ready = Readable(conn.fileno())
    assert not ready(0.0) and not conn.poll(0.0)
    ready(0.0)
    tracemalloc.start()
    try:
        held, _ = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        for _ in range(100):
            ready(0.0)
        peak = tracemalloc.get_traced_memory()[1] - held
    finally:
        tracemalloc.stop()
    assert peak < 100, peak
    other.send(("hook",))
    assert ready(0.0) and conn.poll(0.0)
    assert conn.recv() == ("hook",) and not ready(0.0)
    t0 = time.perf_counter()
    assert not ready(0.02) and time.perf_counter() - t0 >= 0.015  # a timeout in seconds
    other.close()
    assert ready(0.0) and conn.poll(0.0)  # the hang-up
    conn.close()
