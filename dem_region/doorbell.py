"""The per-step handshake between the orchestrator and an engine's worker, in shared memory.

Each clock step the orchestrator starts the engine's advance and waits for its end ("advance",
then "done"); each engine step the worker hands the interface forces over and waits for the
velocities back ("hook", then "go"). As pickled socket messages these cost about 0.1 ms each
(a wake-up through the kernel each), more than a LAMMPS step of a few thousand particles.
Here each side owns its counters in a shared block and only ever raises them: the worker
rings ``hook`` k, the orchestrator answers ``go`` k, and the same for advance / done (one
rank; on several, rank 0 forwards each advance to the other ranks by MPI, so it keeps the
socket). A waiter reads the other's counter, and every 32nd round the socket (which still
carries the queries a hook may make, errors, and several ranks' advances): it spins a few
rounds, then yields its core (a few milliseconds), then waits in the socket's select 0.2 ms at
a time, so a long wait (output, a checkpoint) does not hold a core.

One writer per counter and x86's store order make the counter's new value visible after the
arrays written before it (the forces, the velocities); elsewhere (``available``) the
handshake stays on the socket.
"""
from __future__ import annotations

import os
import platform
import time
from multiprocessing import resource_tracker, shared_memory

import numpy as np

# counters: the worker raises HOOK and DONE, the orchestrator GO and ADVANCE
HOOK, GO, ADVANCE, DONE = range(4)
# values beside them: an advance's steps, whether the orchestrator has a hook, the models' dt
# (the orchestrator's); the engine's and the hosted models' seconds of that advance (the worker's)
STEPS, ASK, DT, ENGINE_S, MODELS_S = range(5)


class Backoff:
    """Wait politely for a counter, watching a socket too: spin ``spin`` rounds, then yield the
    core until ``yield_rounds`` (a few milliseconds), then wait in the socket's select for
    ``longest`` s at a time, which a message ends at once. ``poll(timeout)`` (a Connection's)
    costs about 20 us (it builds a selector), so before that it is asked every 32nd round."""

    def __init__(self, spin: int = 64, yield_rounds: int = 5000, longest: float = 2e-4):
        self.spin, self.yield_rounds, self.longest = spin, yield_rounds, longest
        self.rounds = 0

    def reset(self) -> None:
        self.rounds = 0

    def __call__(self, poll=None) -> bool:
        """One round; True when ``poll`` says a socket message is waiting."""
        self.rounds += 1
        if self.rounds > self.yield_rounds:
            if poll is None:
                time.sleep(self.longest)
                return False
            return poll(self.longest)
        if poll is not None and self.rounds % 32 == 0 and poll(0):
            return True
        if self.rounds > self.spin:
            os.sched_yield()
        return False


def available() -> bool:
    """x86's store order makes a counter visible after the arrays written before it; on other
    machines (no fence here) the handshake stays on the socket."""
    return platform.machine().lower() in ("x86_64", "amd64")


class Doorbell:
    """Four int64 counters (HOOK, GO, ADVANCE, DONE) and five float64 values (STEPS ...
    MODELS_S) in shared memory. Without ``name`` the orchestrator makes the block (and unlinks
    it in close); with it the worker attaches."""

    def __init__(self, name: str | None = None):
        self.owner = name is None
        self.shm = shared_memory.SharedMemory(name=name, create=self.owner, size=8 * 9)
        if not self.owner:  # Python < 3.13 registers attached blocks too and would unlink it at exit
            resource_tracker.unregister(self.shm._name, "shared_memory")  # noqa: SLF001
        self.count = np.ndarray((4,), dtype=np.int64, buffer=self.shm.buf)
        self.value = np.ndarray((5,), dtype=np.float64, buffer=self.shm.buf, offset=32)
        if self.owner:
            self.count[:] = 0
            self.value[:] = 0.0
        self.name = self.shm.name

    def ring(self, which: int, k: int, values: dict[int, float] | None = None) -> None:
        """Counter ``which`` to k, after the values ({slot: value}) it hands over."""
        for slot, v in (values or {}).items():
            self.value[slot] = v
        self.count[which] = k

    def rung(self, which: int, k: int) -> bool:
        return int(self.count[which]) >= k

    def close(self) -> None:
        self.count = self.value = None
        self.shm.close()
        if self.owner:
            self.shm.unlink()
