"""The per-step handshake between the orchestrator and an engine's worker, in shared memory.

The orchestrator starts the engine's advance over the steps up to its next history sample and
waits for its end ("advance", then "done"); each engine step the worker hands the interface
forces over and waits for the velocities back ("hook", then "go"). A hook that fails in the
orchestrator raises ABORT with its go: the worker takes no further step of that advance. As pickled socket messages these cost about 0.1 ms each
(a wake-up through the kernel each), more than a LAMMPS step of a few thousand particles.
Here each side owns its counters in a shared block and only ever raises them: the worker
rings ``hook`` k, the orchestrator answers ``go`` k, and the same for advance / done (one
rank; on several, rank 0 forwards each advance to the other ranks by MPI, so it keeps the
socket). A waiter reads the other's counter, and every 32nd round the socket (which still
carries the queries a hook may make, errors, and several ranks' advances): it spins a few
rounds, then yields its core (a few milliseconds), then waits in the socket's select 0.2 ms at
a time, so a long wait (output, a checkpoint) does not hold a core.

With wake-ups (Linux eventfds, handed to the worker over the socket: ``send_wakeups``) a ring
also writes the other side's eventfd, and a waiter that has spun its few rounds sleeps in the
kernel until the ring or a message wakes it: two processes that take turns then hold one core
between them, not two, which is what a busy machine (another run, pytest's workers) needs.

One writer per counter and x86's store order make the counter's new value visible after the
arrays written before it (the forces, the velocities); elsewhere (``available``) the
handshake stays on the socket.
"""
from __future__ import annotations

import os
import platform
import secrets
import select
import socket
import time
from multiprocessing import resource_tracker, shared_memory

import numpy as np

# counters: the worker raises HOOK and DONE, the orchestrator GO and ADVANCE
HOOK, GO, ADVANCE, DONE = range(4)
# values beside them, the orchestrator's: an advance's steps, whether the orchestrator has a
# hook, the models' dt, whether its hook failed (the worker then takes no further step of that
# advance), whether the hosted models' states go into their block after the last step's
# models (the sample that ends the advance reads them there: no round trip); the worker's: the
# engine's, the hosted models' and the interface's seconds of that advance (its reads and
# writes of the engine's arrays), and the advance whose states it wrote
STEPS, ASK, DT, ABORT, SYNC, ENGINE_S, MODELS_S, INTERFACE_S, WRITTEN = range(9)
VALUES = 9


# with wake-ups, a waiter yields at least this long (s) before it sleeps: a wake-up through this
# VM's kernel costs more than a short wait (measured on the LAMMPS coarse beam: wall x 0.91
# alone, x 0.88 beside a busy process, CPU x 0.85, medians of 5 pairs against never sleeping);
# a waiter that adapts yields twice its typical wait, at most PATIENCE_MAX: a wait a little
# longer than the floor (the engine's step and the hosted laws: 0.3 ms in the main job) then
# ends awake instead of costing a wake-up each step (docs/benchmarks.md, session 27). The
# environment's FEMDEM_PATIENCE and FEMDEM_PATIENCE_MAX override both for such measurements.
PATIENCE = float(os.environ.get("FEMDEM_PATIENCE", "3e-4"))
PATIENCE_MAX = max(PATIENCE, float(os.environ.get("FEMDEM_PATIENCE_MAX", "2e-3")))
# a spinning waiter yields its core every this many rounds (a yield costs 0.5 us here): every
# 16th took the main job's transport from 11 to 9 % of the engine alone, but the coarse beam
# beside a busy process 5 % slower (medians of 3, session 27): kept at every round
YIELD_EVERY = int(os.environ.get("FEMDEM_YIELD_EVERY", "1"))


class Readable:
    """``Connection.poll(timeout)`` on socket ``fd`` through one poll object made once: the
    Connection's builds a selector at every call (~20 us, and a few hundred bytes of Python
    objects: a wait's allocations then depended on how many rounds it took,
    tests/test_hot_path.py). True when a message, or the other side's hang-up, is waiting or
    comes within ``timeout`` s."""

    def __init__(self, fd: int):
        self._poller = select.poll()
        self._poller.register(fd, select.POLLIN)

    def __call__(self, timeout: float = 0.0) -> bool:
        return bool(self._poller.poll(timeout * 1e3))


class Backoff:
    """Wait politely for a counter, watching a socket too: spin ``spin`` rounds, then yield the
    core until ``yield_rounds`` (a few milliseconds), then wait in the socket's select for
    ``longest`` s at a time, which a message ends at once. ``poll(timeout)`` (Readable) is asked
    every 32nd round before that.
    With a ``bell`` that has wake-ups: after ``patience`` s of that, sleep until rung (or a
    message comes). ``adapt``: the patience follows the waits this Backoff saw end (``reset``
    after each): twice their running mean (1/16 weight to the newest), between ``patience``
    and PATIENCE_MAX."""

    def __init__(self, spin: int = 64, yield_rounds: int = 5000, longest: float = 2e-4, bell: "Doorbell | None" = None,
                 patience: float | None = None, adapt: bool = False):
        self.spin, self.yield_rounds, self.longest = spin, yield_rounds, longest
        self.bell = bell if bell is not None and bell.can_sleep else None
        self.floor = self.patience = PATIENCE if patience is None else patience
        self.adapt, self.typical = adapt, 0.0
        self.rounds, self._since, self._drained, self._t0, self._t_last = 0, None, False, 0.0, 0.0

    def reset(self) -> None:
        """A wait ended (the next call starts another); call it as soon as the counter is seen.
        The wait counted is from its first round to its last (none: it had ended before)."""
        if self.adapt:
            waited = min(self._t_last - self._t0, PATIENCE_MAX) if self.rounds else 0.0
            self.typical += (waited - self.typical) / 16
            self.patience = min(PATIENCE_MAX, max(self.floor, 2.0 * self.typical))
        self.rounds, self._since, self._drained = 0, None, False

    def __call__(self, poll=None) -> bool:
        """One round; True when ``poll`` says a socket message is waiting."""
        self.rounds += 1
        if self.adapt:
            self._t_last = time.perf_counter()
            if self.rounds == 1:
                self._t0 = self._t_last
        if self.bell is not None and self.rounds > self.spin:
            now = time.perf_counter()
            if self._since is None:
                self._since = now
            if now - self._since > self.patience:  # a long wait: sleep until rung
                if not self._drained:  # rings before this are in the counter the caller looks at next
                    self._drained = True
                    self.bell.drain()
                    return poll is not None and poll(0)
                return self.bell.sleep()
        if self.rounds > self.yield_rounds:
            if poll is None:
                time.sleep(self.longest)
                return False
            return poll(self.longest)
        if poll is not None and self.rounds % 32 == 0 and poll(0):
            return True
        if self.rounds > self.spin and self.rounds % YIELD_EVERY == 0:
            os.sched_yield()
        return False


def new_block(size: int) -> shared_memory.SharedMemory:
    """A shared-memory block of ``size`` bytes made by this process, named after it
    (femdem_PID_...): what a process leaves behind can be told from another's."""
    return shared_memory.SharedMemory(name=f"femdem_{os.getpid()}_{secrets.token_hex(6)}", create=True, size=size)


def can_wake() -> bool:
    """Linux's eventfds (Python 3.10+): a waiter may sleep until it is rung."""
    return hasattr(os, "eventfd") and hasattr(socket, "send_fds")


def available() -> bool:
    """x86's store order makes a counter visible after the arrays written before it; on other
    machines (no fence here) the handshake stays on the socket."""
    return platform.machine().lower() in ("x86_64", "amd64")


class Doorbell:
    """Four int64 counters (HOOK, GO, ADVANCE, DONE) and nine float64 values (STEPS ...
    WRITTEN) in shared memory. Without ``name`` the orchestrator makes the block (and unlinks
    it in close); with it the worker attaches."""

    def __init__(self, name: str | None = None):
        self.owner = name is None
        self.can_sleep = False  # wake-ups (eventfds) made (owner) or received (worker)
        self._ring_fd = self._wake_fd = -1
        self.shm = new_block(8 * (4 + VALUES)) if self.owner else shared_memory.SharedMemory(name=name)
        if not self.owner:  # Python < 3.13 registers attached blocks too and would unlink it at exit
            resource_tracker.unregister(self.shm._name, "shared_memory")  # noqa: SLF001
        self.count = self.shm.buf[:32].cast("q")  # int64s; a waiter reads one each round (cheaper than numpy's)
        self.value = np.ndarray((VALUES,), dtype=np.float64, buffer=self.shm.buf, offset=32)
        if self.owner:
            self.shm.buf[:32] = bytes(32)
            self.value[:] = 0.0
        self.name = self.shm.name

    def ring(self, which: int, k: int, values: dict[int, float] | None = None) -> None:
        """Counter ``which`` to k, after the values ({slot: value}) it hands over."""
        if values:
            for slot, v in values.items():
                self.value[slot] = v
        self.count[which] = k
        if self.can_sleep:  # after the counter: the woken side finds it raised
            os.eventfd_write(self._ring_fd, 1)

    def rung(self, which: int, k: int) -> bool:
        return self.count[which] >= k

    # -- wake-ups ------------------------------------------------------------------------------
    def send_wakeups(self, sock_fd: int) -> None:
        """The orchestrator's side: make the two eventfds (one each side sleeps on) and hand them
        to the worker over the connected Unix socket ``sock_fd`` (SCM_RIGHTS, as the next bytes
        after the message that announced them); the worker calls receive_wakeups."""
        mine, theirs = os.eventfd(0, os.EFD_NONBLOCK), os.eventfd(0, os.EFD_NONBLOCK)
        with socket.socket(fileno=os.dup(sock_fd)) as s:
            socket.send_fds(s, [b"w"], [theirs, mine])  # the worker sleeps on theirs, rings mine
        self._start_sleeping(mine, theirs, sock_fd)

    def receive_wakeups(self, sock_fd: int) -> None:
        """The worker's side of send_wakeups."""
        with socket.socket(fileno=os.dup(sock_fd)) as s:
            _, fds, _, _ = socket.recv_fds(s, 1, 2)
        self._start_sleeping(fds[0], fds[1], sock_fd)

    def _start_sleeping(self, wake_fd: int, ring_fd: int, sock_fd: int) -> None:
        self._wake_fd, self._ring_fd = wake_fd, ring_fd
        self._poller = select.poll()
        self._poller.register(wake_fd, select.POLLIN)
        self._poller.register(sock_fd, select.POLLIN)
        self._sock_fd, self.can_sleep = sock_fd, True

    def drain(self) -> None:
        """Forget the rings so far (their counters are read after this)."""
        try:
            os.eventfd_read(self._wake_fd)
        except BlockingIOError:
            pass

    def sleep(self, longest: float = 0.1) -> bool:
        """Sleep until the other side rings or a socket message comes (at most ``longest`` s);
        True when a message is waiting."""
        events = dict(self._poller.poll(longest * 1e3))
        if self._wake_fd in events:
            self.drain()
        return self._sock_fd in events

    def close(self) -> None:
        if self.can_sleep:
            os.close(self._wake_fd)
            os.close(self._ring_fd)
            self.can_sleep = False
        self.count.release()
        self.count = self.value = None
        self.shm.close()
        if self.owner:
            self.shm.unlink()
