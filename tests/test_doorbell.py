"""The per-step handshake in shared memory (dem_region/doorbell.py): counters and values cross
between processes in order, and the orchestrator's block is gone after close."""
import multiprocessing as mp
from multiprocessing import shared_memory

import numpy as np
import pytest

from dem_region.doorbell import ADVANCE, DONE, ENGINE_S, GO, HOOK, MODELS_S, STEPS, Backoff, Doorbell


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


def test_a_long_wait_sleeps_instead_of_holding_a_core():
    """Past its spin and yield rounds the backoff sleeps, longer and longer up to its bound."""
    import time
    wait = Backoff(spin=2, yield_rounds=4, longest=2e-3)
    for _ in range(4):
        wait()
    t0 = time.perf_counter()
    for _ in range(20):
        wait()
    slept = time.perf_counter() - t0
    assert slept > 10 * 1e-3  # most of the 20 rounds at the 2 ms bound
