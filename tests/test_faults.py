"""Injected faults: the engine worker dies mid-run; the orchestrator is killed mid-run."""
import glob
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
LONG = ["run", "coupled_vibration", "--set", "dem.process=worker", "--set", "run.steps=200000", "--quiet"]


def _start(out):
    return subprocess.Popen([sys.executable, "-m", "coupling.cli", *LONG, "--out", str(out)], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _workers(parent: int) -> list[int]:
    ps = subprocess.run(["pgrep", "-P", str(parent), "-f", "dem_region.worker"], capture_output=True, text=True)
    return [int(x) for x in ps.stdout.split()]


def _wait_for_worker(proc, timeout=60.0) -> int:
    t0 = time.time()
    while time.time() - t0 < timeout:
        w = _workers(proc.pid)
        if w and (Path(proc.args[-1] + ".partial") / "plots").exists():
            time.sleep(1.0)  # let it run a little
            return w[0]
        time.sleep(0.2)
    raise AssertionError("worker did not start")


def test_engine_worker_crash_is_reported(tmp_path):
    out = tmp_path / "run"
    proc = _start(out)
    worker = _wait_for_worker(proc)
    os.kill(worker, signal.SIGKILL)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1, err
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "error" and "worker died" in s["message"]


def test_killed_orchestrator_leaves_no_worker_or_shared_memory(tmp_path):
    shm_before = set(glob.glob("/dev/shm/*"))
    proc = _start(tmp_path / "run")
    worker = _wait_for_worker(proc)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    t0 = time.time()
    while time.time() - t0 < 20:
        alive = subprocess.run(["ps", "-p", str(worker)], capture_output=True).returncode == 0
        if not alive and set(glob.glob("/dev/shm/*")) <= shm_before:
            break
        time.sleep(0.2)
    assert not alive, "the worker outlived the orchestrator"
    assert set(glob.glob("/dev/shm/*")) <= shm_before, "shared memory left behind"
    assert not (tmp_path / "run").exists(), "a killed run must not look finished"
