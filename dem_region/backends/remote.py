"""A DEM back-end that runs in a worker process (shared memory for arrays and the per-step
handshake, dem_region/doorbell.py; a socket for control).

Same contract as the in-process adapters, so the orchestrator cannot tell the difference and
the same case gives the same numbers either way. Needed by LAMMPS, whose MPICH cannot share
a process with the OpenMPI of YADE, LIGGGHTS and mpi4py (ENGINES.md).
"""
from __future__ import annotations

import os
import pickle
import shutil
import socket
import tempfile
import time
import subprocess
import sys
from functools import cached_property
from multiprocessing import shared_memory
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Callable

import numpy as np

from .. import state_block, wire
from ..doorbell import (ABORT, ADVANCE, ASK, DONE, DT, ENGINE_S, GO, HOOK, INTERFACE_S, MODELS_S, STEPS, SYNC, WRITTEN,
                        Backoff, Doorbell, Readable, available, can_wake, new_block)
from ..model_step import set_model_states
from ..scene import DemScene
from .base import EngineUnavailable

ROOT = Path(__file__).resolve().parents[2]


class RemoteBackend:
    """Proxy for engine ``engine`` running under ``python`` (with ``env``) in a child process;
    with ``ranks`` > 1 the child is ``mpiexec -n ranks`` (the executable next to ``python``)
    and rank 0 connects back to a listening socket (mpiexec does not hand on descriptors)."""

    native_laws = ("elastic",)
    connect_timeout = 120.0  # s for the ranks to start and rank 0 to connect

    def __init__(self, engine: str, python: str | None = None, env: dict | None = None, ranks: int = 1):
        self.name = engine
        self.ranks = int(ranks)
        self.restart_file = "dem.yade.bz2" if engine == "yade" else "dem.npz"
        self.transport_s = 0.0  # s spent on the transport during start / advance
        self.models_s = 0.0  # s the models hosted in the worker took (host_models)
        self.interface_s = 0.0  # s the worker took reading and writing the interface on the engine's arrays
        self._evaluations, self._synced = 0, -1  # hosted models' steps so far, and at the last sync
        # the block the hosted models' states come through at a sync, its layout and views
        self._state_block, self._state_entries, self._state_views = None, None, None
        # whether the worker writes their states into that block after the models of the current
        # advance's last step (SYNC), and the steps of that advance not yet hooked
        self._prewrite, self._steps_left = False, 0
        # an advance under way; the replies owed to queries sent; an advance that would not stop
        self._advancing, self._replies_owed, self._stuck = False, 0, False
        self._compiled, self._compiled_booked = 0.0, 0.0  # s, the worker's compiling: read, booked
        self._dt = 0.0
        env = dict(env if env is not None else os.environ)
        env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
        python = python or sys.executable
        if self.ranks == 1:
            parent, child = socket.socketpair()
            self.proc = subprocess.Popen([python, "-m", "dem_region.worker", str(child.fileno()), engine],
                                         pass_fds=(child.fileno(),), env=env, cwd=str(ROOT))
            child.close()
        else:
            parent = self._launch_ranks(python, engine, env)
        self.conn = Connection(parent.detach())
        self.bell: Doorbell | None = None  # the per-step handshake, made at the first start
        self._wait: Backoff | None = None  # the waits for the worker's hooks and its done
        self._hooks = self._advances = 0  # hooks the worker rang, advances rung to it, so far
        self.blocks: list[shared_memory.SharedMemory] = []
        self.ids = np.zeros(0, int)
        self.prescribed = self.ids
        self._row = np.zeros(0, int)  # particle id -> its row in F / V, -1 if not an interface particle
        self._added_here = None  # (len(ids), 3) N added to interface particles during this hook
        self._model_ids = None  # the coupling-layer models' particles, read and written in shared memory
        self._models_pending = False  # their forces written this hook, not yet applied by the worker

    def _launch_ranks(self, python: str, engine: str, env: dict) -> socket.socket:
        mpiexec = Path(python).parent / "mpiexec"
        if not mpiexec.exists():
            raise EngineUnavailable(f"dem.ranks = {self.ranks}: {mpiexec} missing; fix: ./scripts/setup.sh")
        tmp = tempfile.mkdtemp(prefix="femdem-ranks-")
        path = os.path.join(tmp, "worker.sock")
        listener = socket.socket(socket.AF_UNIX)
        try:
            listener.bind(path)
            listener.listen(1)
            listener.settimeout(1.0)
            self.proc = subprocess.Popen([str(mpiexec), "-n", str(self.ranks), python, "-m", "dem_region.worker",
                                          f"unix:{path}", engine], env=env, cwd=str(ROOT),
                                         start_new_session=False)
            t0 = time.monotonic()
            while True:
                try:
                    return listener.accept()[0]
                except socket.timeout:
                    if self.proc.poll() is not None or time.monotonic() - t0 > self.connect_timeout:
                        self.proc.kill()
                        raise self._died() from None
        finally:
            listener.close()
            shutil.rmtree(tmp, ignore_errors=True)

    def _died(self) -> EngineUnavailable:
        try:
            code = self.proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            code = None
        return EngineUnavailable(f"--dem {self.name}: the engine worker died (exit code {code})")

    def _send(self, msg) -> None:
        try:
            self.conn.send(msg)
        except OSError:
            raise self._died() from None

    def _recv(self):
        try:
            return self.conn.recv()
        except (EOFError, OSError):
            raise self._died() from None

    def _call(self, *msg, then=None):
        """Send ``msg`` and return the worker's reply; ``then(socket fd)`` runs between (what
        goes on the socket outside the messages: the doorbell's wake-ups)."""
        if self._models_pending:  # a query after the models' bulk write sees their forces applied
            self._models_pending = False
            self._call("models_flush")
        self._send(msg)
        self._replies_owed += 1
        if then is not None:
            then(self.conn.fileno())
        reply = self._recv()
        self._replies_owed -= 1
        if reply[0] == "error":
            self._raise(reply)
        return reply

    def _raise(self, reply) -> None:
        """A worker's error reply as an exception (a refusal as NotImplementedError: bad input)."""
        if reply[0] == "error" and reply[2:] == ("NotImplementedError",):
            raise NotImplementedError(reply[1])
        raise RuntimeError(f"{self.name} worker: {reply[1] if reply[0] == 'error' else reply}")

    def build(self, scene: DemScene) -> None:
        self.scene = scene
        _, self.version, self._dt_crit = self._call("build", scene.to_wire())

    def critical_dt(self) -> float:
        return self._dt_crit

    def set_dt(self, dt: float) -> None:
        self._call("set_dt", float(dt))
        self._dt = float(dt)

    def host_models(self, models) -> bool:
        """Run the coupling layer's models (law bonds, impactors, loads) inside the worker, on
        the engine's own arrays, so that their particles never cross the process boundary;
        call before the first start. Only the transition interface then crosses each step;
        the orchestrator keeps ``models`` as copies brought up to date by ``sync_models``.
        On several ranks each rank evaluates the law bonds of the atoms it owns
        (dem_region/rank_laws.py). False (the orchestrator evaluates them, as before) when a
        model does not pickle (a load curve given as a closure)."""
        if not models:
            return False
        try:
            payload = wire.dumps(list(models))
        except (pickle.PicklingError, TypeError, AttributeError):
            return False
        try:
            self._call("host_models", payload)
        except RuntimeError:  # the worker cannot import a model's class (its venv lacks a module)
            return False
        return True

    def sync_models(self, models) -> None:
        """The orchestrator's copies of the hosted models made equal to the worker's (nothing
        to do if the models took no step since the last sync), through a shared block
        (dem_region/state_block.py) made to the layout the worker announces."""
        if self._synced == self._evaluations:
            return
        if (self.bell is not None and self._steps_left == 0 and self._prewrite
                and self.bell.value[WRITTEN] == self._advances):  # written after the advance's last step
            # views on the block: each model's restore_state copies what it keeps
            set_model_states(models, state_block.read(self._state_views, self._state_entries, [{} for _ in models],
                                                      copy=False))
            self._synced = self._evaluations
            return
        reply = self._call("models_state", self._state_entries)
        if reply[0] == "layout":  # new models, or the first sync: a block to the worker's layout
            entries = reply[1]
            if self._state_block is not None:
                self._state_views = None
                self.blocks.remove(self._state_block)
                self._state_block.close()
                self._state_block.unlink()
            self._state_block = new_block(state_block.offsets(entries)[1])
            self.blocks.append(self._state_block)
            self._call("models_state_block", self._state_block.name, entries)
            self._state_entries, self._state_views = entries, state_block.views(self._state_block.buf, entries)
            reply = self._call("models_state", self._state_entries)
            if reply[0] != "ok":
                raise RuntimeError(f"{self.name} worker: the models' states changed their layout twice in one sync")
        rest = wire.loads(reply[1])
        set_model_states(models, state_block.read(self._state_views, self._state_entries, rest))
        self._synced = self._evaluations

    def law_shares(self) -> list[list[int]]:
        """Per MPI rank, the law bonds of each hosted family it evaluates ([] where the
        orchestrator evaluates them)."""
        return self._call("law_shares")[1]

    def set_models_state(self, states: list[dict]) -> None:
        """The hosted models set to ``states`` (model_states form: a checkpoint restored)."""
        self._call("set_models_state", wire.dumps(states))
        self._evaluations += 1  # the copies here may differ from the worker's now
        self._prewrite = False  # and the states in the block are older than the worker's

    def prescribe(self, ids: np.ndarray, dofs: str = "xyz") -> None:
        if dofs != "xyz":  # a partial prescription (symmetry plane): no interface arrays
            self._call("call", "prescribe", np.asarray(ids).tolist(), dofs)
            return
        self.ids = self.prescribed = np.asarray(ids, int)
        self._row = np.full(int(self.ids.max()) + 1 if len(self.ids) else 0, -1)
        self._row[self.ids] = np.arange(len(self.ids))
        names, (self.F, self.V) = self._shared_pair(len(self.ids))
        self._call("prescribe", self.ids.tolist(), *names)

    def release(self, ids: np.ndarray) -> None:
        """Particles ``ids`` no longer slaved (the interface arrays follow the next prescribe)."""
        self._call("call", "release", np.asarray(ids, int).tolist())
        self.prescribed = np.setdiff1d(self.prescribed, np.asarray(ids, int))

    def set_all_velocities(self, v: np.ndarray) -> None:
        self._call("call", "set_all_velocities", np.asarray(v, float).tolist())

    @cached_property
    def _readable(self) -> Readable:
        """The waits' poll of the socket (doorbell.Readable), made at its first use."""
        return Readable(self.conn.fileno())

    def _run(self, op: str, between: Callable[[], None] | None, n: int = 1) -> None:
        clock = time.perf_counter
        if self.bell is None and available():
            self.bell, wake = Doorbell(), can_wake()
            self._call("doorbell", self.bell.name, wake, then=self.bell.send_wakeups if wake else None)
            self._wait = Backoff(bell=self.bell, adapt=True)  # one for the run: it learns the engine's step
        bell, wait = self.bell, self._wait
        if wait is not None:
            wait.reset()
        if self._stuck:
            raise EngineUnavailable(f"--dem {self.name}: the engine worker did not stop an advance it was told to stop")
        t0 = clock()
        rung = bell is not None and op == "advance" and self.ranks == 1  # (ranks: rank 0 forwards it)
        if rung:
            self._advances += 1
            self._steps_left = n
            self._prewrite = self._state_views is not None  # (the block is made at the first sync)
            bell.ring(ADVANCE, self._advances, {STEPS: n, ASK: float(between is not None), DT: self._dt, ABORT: 0.0,
                                                SYNC: float(self._prewrite)})
        else:
            self._send((op, n, between is not None, self._dt))
        self._advancing = True  # until the worker's done, or its error on the socket
        try:
            in_hook, seconds = self._serve_advance(between, rung, wait)
        except BaseException:  # a hook that failed here, or an interrupt: the worker stops its advance
            if rung and self._advancing:
                self._abort()
            raise
        self._done(between, n, clock() - t0 - in_hook, *seconds)

    def _serve_advance(self, between, rung: bool, wait: Backoff | None) -> tuple[float, tuple]:
        """Answer the worker's hooks until its advance ends: (the hooks' seconds, the worker's
        engine, models and interface seconds)."""
        bell, in_hook = self.bell, 0.0
        while True:
            if bell is not None:
                if bell.rung(HOOK, self._hooks + 1):
                    self._hooks += 1
                    try:
                        in_hook += self._hook(between)
                    except BaseException:
                        if rung:  # the worker finishes this step and takes no further one
                            bell.value[ABORT] = 1.0
                        raise
                    finally:
                        bell.ring(GO, self._hooks)
                    wait.reset()
                    continue
                if rung and bell.rung(DONE, self._advances):
                    self._advancing = False
                    return in_hook, (bell.value[ENGINE_S], bell.value[MODELS_S], bell.value[INTERFACE_S])
                if not wait(self._readable):
                    continue
            msg = self._recv()
            if msg[0] == "hook":  # the socket's handshake (no doorbell on this machine)
                in_hook += self._hook(between)
                self._send(("go",))
            elif msg[0] == "done":
                self._advancing = False
                return in_hook, tuple(msg[1:4])
            else:
                self._advancing = False  # the worker failed its advance and serves again
                self._raise(msg)

    def _abort(self, timeout: float = 30.0) -> None:
        """Stop the worker's advance and wait until it has ended, so that the next call finds it
        serving: ABORT raised, every hook it rings answered at once, the reply to a query the
        interrupted hook made read off the socket, until its done or its error. The models'
        copies here are synced again by a round trip. A worker that does not stop in
        ``timeout`` s is left to ``finalize`` (further advances are refused)."""
        bell = self.bell
        bell.value[ABORT] = 1.0
        self._prewrite, self._evaluations = False, self._evaluations + 1  # the steps it took are not known here
        wait, t0 = Backoff(bell=bell), time.monotonic()
        while self._advancing:
            if time.monotonic() - t0 > timeout:
                self._stuck = True
                return
            hooked = int(bell.count[HOOK])
            if hooked > int(bell.count[GO]):  # a step begun before the abort (its go perhaps never rung)
                self._hooks = hooked
                bell.ring(GO, hooked)
            if bell.rung(DONE, self._advances):
                self._advancing = False
            elif self.proc is not None and self.proc.poll() is not None:
                return
            elif wait(self._readable):
                try:
                    reply = self.conn.recv()
                except (EOFError, OSError):
                    return
                self._replies_owed = max(0, self._replies_owed - 1)
                if reply[0] == "error":  # the advance itself failed: the worker serves again
                    self._advancing = False
        while self._replies_owed and self.conn.poll(timeout):  # a query's reply that came before the done
            self.conn.recv()
            self._replies_owed -= 1

    def _done(self, between, n: int, waited: float, engine_s: float, models_s: float, interface_s: float) -> None:
        """Book an advance's end: ``waited`` s outside the hooks, of which the worker spent
        ``engine_s`` in the engine, ``models_s`` in the hosted models and ``interface_s`` reading
        and writing the interface on the engine's arrays (what an in-process engine does in its
        interface stages); the rest is transport (the handshake, the shared-memory copies, the
        worker's Python around them: what an in-process engine does not pay)."""
        if between is None:  # the worker's hosted models stepped without telling
            self._evaluations += n
            self._steps_left = 0
        self.models_s += float(models_s)
        self.interface_s += float(interface_s)
        self.transport_s += max(0.0, waited - float(engine_s) - float(models_s) - float(interface_s))

    def worker_seconds(self) -> dict[str, float]:
        """The seconds of the worker's advances besides the engine's own, by timing bucket."""
        return {"models": self.models_s, "interface": self.interface_s, "transport": self.transport_s}

    def compile_seconds(self) -> float:
        """s the worker process has spent compiling kernels (physics/compile_clock.py) since
        the last call: booked once where several models use this worker in turn (a zone whose
        particles are released), and readable after ``finalize`` (a rebuilt zone's old model
        is closed before its time is booked)."""
        if not self.conn.closed:
            self._compiled = float(self._call("compile_seconds")[1])
        new, self._compiled_booked = self._compiled - self._compiled_booked, self._compiled
        return new

    def reset_worker_seconds(self) -> None:
        """Start the books (after the start's set-up)."""
        self.models_s = self.interface_s = self.transport_s = 0.0

    def _hook(self, between: Callable[[], None] | None) -> float:
        """The orchestrator's side of one engine step's hook; its wall time (s)."""
        t1 = time.perf_counter()
        self._evaluations += 1
        self._steps_left -= 1
        self._added_here = None  # the worker's F was taken before this hook's additions
        self._models_pending = False
        if between is not None:
            between()
        return time.perf_counter() - t1

    def start(self, between: Callable[[], None] | None = None) -> None:
        self._run("start", between)

    def advance(self, between: Callable[[], None] | None = None, steps: int = 1) -> None:
        """``steps`` engine steps in one advance (one hand-over each way, the hooks between);
        on several ranks, or without the doorbell, one advance per step."""
        if self.ranks == 1 and (self.bell is not None or available()):
            self._run("advance", between, steps)
            return
        for _ in range(steps):
            self._run("advance", between)

    def forces_into(self, ids: np.ndarray, out: np.ndarray) -> None:
        """``forces(ids)`` into out (k, 3) N; the interface's without a temporary."""
        if ids is self.ids:
            if self._added_here is None:
                np.copyto(out, self.F)
            else:
                np.add(self.F, self._added_here, out=out)
        else:
            out[:] = self.forces(ids)

    def forces(self, ids: np.ndarray) -> np.ndarray:
        if ids is self.ids or (len(ids) == len(self.ids) and np.array_equal(ids, self.ids)):
            # written by the worker before its hook; the forces added during the hook (the
            # coupling layer's laws on interface particles) are added here
            return self.F.copy() if self._added_here is None else self.F + self._added_here
        return np.asarray(self._call("call", "forces", np.asarray(ids).tolist())[1])

    def set_velocities(self, ids: np.ndarray, v: np.ndarray) -> None:
        if ids is self.ids or (len(ids) == len(self.ids) and np.array_equal(ids, self.ids)):
            self.V[:] = v  # read by the worker when its hook hands back
        else:
            self._call("call", "set_velocities", np.asarray(ids).tolist(), np.asarray(v).tolist())

    @property
    def bulk_arrays(self) -> bool:
        """One rank: the models' positions and forces move through shared memory (ModelStep)."""
        return self.ranks == 1

    def read_positions(self, ids: np.ndarray, out: np.ndarray) -> None:
        """out (k, 3) m <- positions of particles ``ids`` (the models' set: the worker writes
        them into shared memory before each hook; the first call sets that up)."""
        if self.ranks > 1:
            out[:] = self.positions_of(ids)
            return
        if ids is not self._model_ids:
            self._share_model_particles(ids)
        out[:] = self._X_model

    def positions_into(self, ids: np.ndarray, out: np.ndarray) -> None:
        """out (k, 3) m <- positions of particles ``ids``, for the penalty tie each step: through
        the models' shared block where it is free (the models hosted in the worker, one rank;
        the worker writes the positions before each hook, applies the block's forces after it),
        else by message."""
        if self.ranks == 1 and (self._model_ids is None or ids is self._model_ids):
            self.read_positions(ids, out)
        else:
            out[:] = self.positions_of(ids)

    def _shared_pair(self, k: int) -> tuple[list[str], list[np.ndarray]]:
        """Two new shared-memory blocks of (k, 3) float64 (released by finalize): names, arrays."""
        blocks = [new_block(max(8, 8 * 3 * k)) for _ in range(2)]
        self.blocks += blocks
        return [b.name for b in blocks], [np.ndarray((k, 3), dtype=np.float64, buffer=b.buf) for b in blocks]

    def _share_model_particles(self, ids: np.ndarray) -> None:
        names, (self._X_model, self._F_model) = self._shared_pair(len(ids))
        self._call("models", np.asarray(ids).tolist(), *names)
        self._model_ids = ids
        rows = self._rows_of(np.asarray(ids, int))
        self._model_tied = np.flatnonzero(rows >= 0), rows[rows >= 0]  # model rows on interface particles

    def _rows_of(self, ids: np.ndarray) -> np.ndarray:
        """Rows of ``ids`` in the interface arrays, -1 for the others."""
        if not len(self._row):
            return np.full(len(ids), -1)
        return np.where(ids < len(self._row), self._row[np.minimum(ids, len(self._row) - 1)], -1)

    def _tied_forces(self, rows: np.ndarray, F: np.ndarray) -> None:
        """Forces on interface particles added during this hook: the tie reads them through forces()."""
        if self._added_here is None:
            self._added_here = np.zeros((len(self.ids), 3))
        np.add.at(self._added_here, rows, F)

    def add_forces(self, ids: np.ndarray, F: np.ndarray) -> None:
        if ids is self._model_ids:  # the models' bulk write: applied by the worker when the hook returns
            self._F_model[:] = F
            self._models_pending = True
            src, rows = self._model_tied
            if len(rows):
                self._tied_forces(rows, np.asarray(F, float)[src])
            return
        if len(ids):
            self._call("call", "add_forces", np.asarray(ids).tolist(), np.asarray(F).tolist())
            rows = self._rows_of(np.asarray(ids, int))
            tied = rows >= 0
            if tied.any():
                self._tied_forces(rows[tied], np.asarray(F, float).reshape(-1, 3)[tied])

    def positions_of(self, ids: np.ndarray) -> np.ndarray:
        return np.asarray(self._call("call", "positions_of", np.asarray(ids).tolist())[1])

    def positions(self) -> np.ndarray:
        return np.asarray(self._call("call", "positions")[1])

    def velocities(self) -> np.ndarray:
        return np.asarray(self._call("call", "velocities")[1])

    def energies(self) -> dict[str, float]:
        return self._call("call", "energies")[1]

    def bond_state(self) -> dict:
        return self._call("call", "bond_state")[1]

    def atoms_per_rank(self) -> list[int]:
        return self._call("call", "atoms_per_rank")[1]

    @property
    def supports_checkpoint(self) -> bool:
        """As the engine in the worker (the LAMMPS family saves no Hertz contact history)."""
        return self.name == "yade" or self.scene.contact != "hertz_mindlin"

    def checkpoint(self, path) -> None:
        self._call("call", "checkpoint", str(path))

    def restore(self, path) -> None:
        """A file the worker, alive, cannot restore from is a ValueError: a checkpoint that
        does not fit (a worker that died is EngineUnavailable)."""
        try:
            self._call("call", "restore", str(path))
        except RuntimeError as exc:
            raise ValueError(str(exc)) from None

    def finalize(self) -> None:
        if self.proc.poll() is None and not self._stuck:
            try:  # a worker that does not answer in 10 s is killed below
                if not self._advancing and not self._replies_owed:  # idle: its last compile reading, kept
                    self._send(("compile_seconds",))
                    reply = self._recv() if self.conn.poll(10.0) else ("late",)
                    if reply[0] == "ok":
                        self._compiled = float(reply[1])
                self._send(("finalize",))
                if self.conn.poll(10.0):
                    self._recv()
            except (EngineUnavailable, RuntimeError, OSError):
                pass
        self.conn.close()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        for b in self.blocks:
            b.close()
            b.unlink()
        self.blocks = []
        if self.bell is not None:
            self.bell.close()
            self.bell = None
