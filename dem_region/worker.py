"""A DEM engine in its own process: the far end of ``backends.remote.RemoteBackend``.

Started as ``python -m dem_region.worker FD ENGINE``, FD a connected socket. Control
messages are small pickled tuples over the socket; the interface arrays (forces out,
velocities in) live in shared memory blocks the orchestrator created. The worker exits when
told, or when the socket closes (the orchestrator died), so no engine process outlives it.
"""
from __future__ import annotations

import socket
import sys
import time
from pathlib import Path
from multiprocessing import resource_tracker, shared_memory
from multiprocessing.connection import Connection

import numpy as np


def _attach(name: str, shape) -> tuple[shared_memory.SharedMemory, np.ndarray]:
    shm = shared_memory.SharedMemory(name=name)
    # Python < 3.13 registers attached blocks too and would unlink the parent's block at exit
    resource_tracker.unregister(shm._name, "shared_memory")  # noqa: SLF001
    return shm, np.ndarray(shape, dtype=np.float64, buffer=shm.buf)


def _plain(value):
    """numpy values -> Python lists / floats (a numpy 2 pickle does not load under numpy 1)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def serve(conn: Connection, engine: str) -> None:
    from dem_region.backends import get_backend
    from dem_region.scene import DemScene

    backend = get_backend(engine)()
    state = {"ids": np.zeros(0, int), "F": None, "V": None, "blocks": [], "in_hook": 0.0}

    def between():
        """The engine's coupling hook: interface forces out, then serve queries until 'go'."""
        t0 = time.perf_counter()
        try:
            _between()
        finally:
            state["in_hook"] += time.perf_counter() - t0

    def _between():
        if state["F"] is not None:
            state["F"][:] = backend.forces(state["ids"])
        conn.send(("hook",))
        while True:
            msg = conn.recv()
            if msg[0] == "go":
                break
            handle(msg)
        if state["V"] is not None:
            backend.set_velocities(state["ids"], state["V"])

    def handle(msg) -> bool:
        """Run one control message; False when the worker should stop."""
        op, args = msg[0], msg[1:]
        try:
            if op == "build":
                backend.build(DemScene.from_wire(args[0]))
                # plain Python values: the orchestrator may run another numpy (no numpy pickles)
                conn.send(("ok", str(backend.version), float(backend.critical_dt())))
            elif op == "prescribe":
                ids = state["ids"] = np.asarray(args[0], int)
                backend.prescribe(ids)
                (sf, state["F"]), (sv, state["V"]) = _attach(args[1], (len(ids), 3)), _attach(args[2], (len(ids), 3))
                state["blocks"] += [sf, sv]
                conn.send(("ok",))
            elif op == "set_dt":
                backend.set_dt(args[0])
                conn.send(("ok",))
            elif op in ("start", "advance"):
                hook = between if args[1] else None  # the orchestrator has a hook to run
                t0, state["in_hook"] = time.perf_counter(), 0.0
                for _ in range(args[0] if op == "advance" else 1):
                    getattr(backend, op)(hook)
                # the engine's own time: the orchestrator separates it from the transport
                conn.send(("done", time.perf_counter() - t0 - state["in_hook"]))
            elif op == "call":  # bulk queries: positions, velocities, energies, forces(ids)
                out = getattr(backend, args[0])(*args[1:])
                # plain lists: the two processes may run different numpy versions
                conn.send(("ok", _plain(out)))
            elif op == "finalize":
                backend.finalize()
                conn.send(("ok",))
                return False
            else:
                conn.send(("error", f"unknown operation {op!r}"))
        except (EOFError, OSError):
            raise
        except Exception as exc:  # report, then keep serving so the orchestrator can stop cleanly
            import traceback
            where = traceback.extract_tb(exc.__traceback__)[-1]
            if isinstance(exc, NotImplementedError):  # a refusal: the orchestrator reports it as bad input
                conn.send(("error", str(exc), "NotImplementedError"))
            else:
                conn.send(("error", f"{type(exc).__name__}: {exc} ({Path(where.filename).name}:{where.lineno})"))
        return True

    try:
        while handle(conn.recv()):
            pass
    except (EOFError, OSError):
        pass  # the orchestrator is gone: stop
    for b in state["blocks"]:
        b.close()


def main() -> None:
    fd, engine = int(sys.argv[1]), sys.argv[2]
    sock = socket.socket(fileno=fd)
    serve(Connection(sock.detach()), engine)


if __name__ == "__main__":
    main()
