"""Injected faults: the engine worker dies mid-run; the orchestrator is killed mid-run."""
import glob
import json
import os
import shutil
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


def _blocks_of(pid: int) -> list[str]:
    """The shared-memory blocks process ``pid`` made (doorbell.new_block names them after it):
    other tests running beside this one make their own."""
    return glob.glob(f"/dev/shm/femdem_{pid}_*")


def test_killed_orchestrator_leaves_no_worker_or_shared_memory(tmp_path):
    proc = _start(tmp_path / "run")
    worker = _wait_for_worker(proc)
    t0 = time.time()  # (on a loaded machine the worker may start well before the handshake's blocks)
    while not _blocks_of(proc.pid) and time.time() - t0 < 60:
        time.sleep(0.2)
    assert _blocks_of(proc.pid), "the orchestrator's blocks are named after it"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    t0 = time.time()
    while time.time() - t0 < 20:
        alive = subprocess.run(["ps", "-p", str(worker)], capture_output=True).returncode == 0
        if not alive and not _blocks_of(proc.pid):
            break
        time.sleep(0.2)
    assert not alive, "the worker outlived the orchestrator"
    assert not _blocks_of(proc.pid), "shared memory left behind"
    assert not (tmp_path / "run").exists(), "a killed run must not look finished"


def _descendants(pid: int) -> list[int]:
    rows = [line.split() for line in subprocess.run(["ps", "-eo", "pid=,ppid="], capture_output=True,
                                                     text=True).stdout.splitlines()]
    children: dict[int, list[int]] = {}
    for p, pp in rows:
        children.setdefault(int(pp), []).append(int(p))
    out, todo = [], [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            out.append(c)
            todo.append(c)
    return out


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_killed_orchestrator_leaves_no_lammps_rank_behind(tmp_path, sig):
    """LAMMPS on two ranks under its mpiexec: when the orchestrator is killed, rank 0 sees the
    socket close (in a receive or a send), tells the other rank, both shut LAMMPS down and
    mpiexec exits. SIGTERM is a notice (a batch scheduler's, before its SIGKILL): the run
    closes its engine and releases its shared memory itself, says so in one line and exits
    143, its partial directory left to resume (its SIGTERM used to end it as SIGKILL does,
    and once its block outlived it by 30 s, session 44)."""
    out = tmp_path / "run"
    mpich_before = set(glob.glob("/dev/shm/mpich*"))
    proc = subprocess.Popen([sys.executable, "-m", "coupling.cli", "run", "coupled_vibration", "--dem", "lammps",
                             "--set", "dem.ranks=2", "--set", "run.steps=200000", "--quiet", "--out", str(out)],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.time()
    while time.time() - t0 < 60 and not (Path(str(out) + ".partial") / "plots").exists():
        time.sleep(0.2)
    time.sleep(1.0)
    family = _descendants(proc.pid)
    ranks = [p for p in family if "dem_region.worker" in Path(f"/proc/{p}/cmdline").read_text(errors="ignore")]
    assert len(ranks) >= 3, "mpiexec and two ranks expected"  # mpiexec's own line names the worker too
    os.kill(proc.pid, sig)
    _, err = proc.communicate()
    if sig == signal.SIGTERM:
        partial = Path(str(out) + ".partial")
        assert proc.returncode == 143, (proc.returncode, err)
        assert err == f"femdem: terminated (SIGTERM); the run is kept in {partial}: continue it with femdem run " \
                      f"--resume {partial}\n", err
        assert not _blocks_of(proc.pid), "the orchestrator released its shared memory before it exited"
        assert Path(str(out) + ".partial").is_dir() and not out.exists()
    t0 = time.time()
    while time.time() - t0 < 30:
        alive = [p for p in family if subprocess.run(["ps", "-p", str(p)], capture_output=True).returncode == 0]
        left = _blocks_of(proc.pid) + sorted(set(glob.glob("/dev/shm/mpich*")) - mpich_before)
        if not alive and not left:
            break
        time.sleep(0.2)
    assert not alive, f"processes outlived the orchestrator: {alive}"
    assert not left, f"shared memory left behind: {left}"


def test_a_terminated_yade_run_closes_and_waits_to_resume(tmp_path):
    """SIGTERM during a coupled run on YADE in process, whose coupling hook YADE calls from its
    own loop: the run stops as an interrupted one (exit 143, one line, its partial directory and
    checkpoint kept) and --resume finishes it; it had ended as an internal error with YADE's
    traceback on the terminal."""
    out = tmp_path / "run"
    args = [sys.executable, "-m", "coupling.cli", "run", "coupled_vibration", "--dem", "yade", "--quiet",
            "--set", "run.steps=20000", "--set", "output.checkpoint_every=2000"]
    proc = subprocess.Popen([*args, "--out", str(out)], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    partial = Path(str(out) + ".partial")
    t0 = time.time()
    while time.time() - t0 < 120 and proc.poll() is None and not (partial / "checkpoint" / "state.h5").exists():
        time.sleep(0.1)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, (proc.returncode, err)
    assert err == f"femdem: terminated (SIGTERM); the run is kept in {partial}: continue it with femdem run " \
                  f"--resume {partial}\n", err
    assert (partial / "checkpoint").is_dir() and not out.exists()
    r = subprocess.run([sys.executable, "-m", "coupling.cli", "run", "--resume", str(partial), "--quiet"], cwd=ROOT,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"


def _as_nobody(cmd, cwd):
    return subprocess.run(["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", "env", "HOME=/nonexistent",
                           *cmd], cwd=cwd, capture_output=True, text=True)


@pytest.mark.skipif(os.geteuid() != 0 or not shutil.which("setpriv"), reason="needs root to become another user")
def test_an_ordinary_user_without_a_home_runs_cases():
    """As 'nobody' (no writable home, project files owned by root): a run in a directory of
    theirs works on the in-process and the worker engines (numba and matplotlib caches go to
    a per-user temporary directory); one where they cannot write is refused in one line."""
    import tempfile
    femdem = str(Path(sys.executable).parent / "femdem")
    home = Path(tempfile.mkdtemp(prefix="femdem-user-"))
    try:
        home.chmod(0o777)
        for args in (["bar_wave"], ["coupled_vibration", "--set", "run.steps=200"],
                     ["coupled_vibration", "--dem", "lammps", "--set", "run.steps=200"]):
            r = _as_nobody([femdem, "run", *args, "--quiet"], home)
            assert r.returncode == 0, r.stderr
        assert len(list((home / "runs").iterdir())) == 3
        r = _as_nobody([femdem, "run", "bar_wave", "--quiet"], ROOT)  # the project is root's
        assert r.returncode == 2 and "not writable" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    finally:
        shutil.rmtree(home, ignore_errors=True)


def test_a_run_whose_reader_left_finishes_and_keeps_its_results(tmp_path):
    """`femdem run ... 2>&1 | head -0`: the pipe's reader is gone before the first line. The
    warning printed before the run and the report after it go nowhere; the run, its files and
    its exit code are those of a run on a terminal (it stopped with BrokenPipeError before)."""
    out = tmp_path / "run"
    read, write = os.pipe()
    os.close(read)
    try:
        r = subprocess.run([sys.executable, "-m", "coupling.cli", "run", "enf_coarse", "--out", str(out),
                            "--set=geometry.half_span=0.03", "--set=geometry.crack_length=0.015",
                            "--set=geometry.length=0.06", "--set=clock.t_end=1e-6"],
                           cwd=ROOT, stdout=write, stderr=write, timeout=300)
    finally:
        os.close(write)
    s = json.loads((out / "summary.json").read_text())
    assert (r.returncode, s["status"]) == (0, "ok"), s["message"]
    assert any("beam theory's peak load (LEFM) does not apply" in w for w in s["warnings"])
    assert not (out / "error.log").exists()


@pytest.mark.parametrize("target", ["empty", "dangling"])
def test_a_linked_out_directory_publishes_the_run_where_it_points(tmp_path, capsys, target):
    """--out a symbolic link (to an empty directory, or dangling): the run is published where the
    link points and read through it. It ran to its end and then failed to rename DIR.partial onto
    the link (internal error, exit 1), its result left in DIR.partial."""
    from coupling.cli import main
    where = tmp_path / "target"
    if target == "empty":
        where.mkdir()
    link = tmp_path / "link"
    link.symlink_to(where)
    assert main(["run", "bar_wave", "--set", "clock.t_end=2e-5", "--out", str(link), "--quiet"]) == 0
    assert json.loads((link / "summary.json").read_text())["status"] == "ok"
    assert (where / "history.h5").is_file() and link.is_symlink()
    assert not list(tmp_path.glob("*.partial"))


def test_resuming_a_run_this_user_cannot_write_is_refused_in_one_line(tmp_path, capsys, monkeypatch):
    """--resume of a run that ended with an error, in a directory this user cannot rename (another
    user's): one line naming --resume, exit 2 (it was an internal error, exit 1)."""
    from coupling import checkpoint, run
    from coupling.cli import main
    final = tmp_path / "stopped"
    final.mkdir()
    (final / "summary.json").write_text(json.dumps({"status": "error"}))

    def refused(src, dst):
        raise PermissionError(13, "Permission denied", str(src))
    monkeypatch.setattr(checkpoint, "latest", lambda d: d / "checkpoint")
    monkeypatch.setattr(run.os, "replace", refused)
    assert main(["run", "--resume", str(final), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"femdem: --resume {final}: not writable by this user"), err


def test_ctrl_c_while_the_command_imports_is_one_line(tmp_path):
    """Ctrl-C in the command's first seconds (its modules importing: numba, scipy, the scenes)
    ends it as during a run: exit 130, one line; it printed the import's traceback (and, raised
    inside the imports, once a wrapper's source, once nothing: the command ran on, exit 0)."""
    femdem = str(Path(sys.executable).parent / "femdem")
    for delay in (0.2, 0.6):
        proc = subprocess.Popen([femdem, "run", "free_vibration", "--out", str(tmp_path / f"r{delay}"), "--quiet"],
                                cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(delay)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
        # (one line; on a fast machine the run may have begun, and the line names its directory)
        assert proc.returncode == 130 and err.startswith("femdem: interrupted") and err.count("\n") == 1, \
            (delay, proc.returncode, err)


def test_a_ctrl_c_while_the_command_imports_waits_for_them(monkeypatch, capsys):
    """A Ctrl-C raised inside the imports was not safe (CI, session 47: scipy's decorator module
    printed a wrapper's source before re-raising; another run swallowed it and ran the whole
    command, exit 0): SIGINT is held while they load, the import finishes, and then the command
    ends in one line, exit 130. An import that fails still shows what it printed."""
    import threading
    import types
    from coupling import entry
    finished = []

    class Importing(types.ModuleType):
        def __getattr__(self, name):
            if name != "main":  # (what the import machinery asks of a module)
                raise AttributeError(name)
            signal.pthread_kill(threading.get_ident(), signal.SIGINT)  # Ctrl-C, half way through
            sum(range(10_000))  # (bytecodes, at which Python raises a signal it was given)
            finished.append(True)
            return lambda argv: 7

    old = signal.signal(signal.SIGINT, signal.default_int_handler)  # (as in a command)
    try:
        monkeypatch.setitem(sys.modules, "coupling.cli", Importing("coupling.cli"))
        assert entry.main([]) == 130 and finished == [True]
        assert capsys.readouterr().err == "femdem: interrupted\n"
        assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, set())  # unblocked again

        class Failing(types.ModuleType):
            def __getattr__(self, name):
                if name != "main":
                    raise AttributeError(name)
                print("A NumPy version >=1.25 is required", file=sys.stderr)
                raise ImportError("numpy too old")

        monkeypatch.setitem(sys.modules, "coupling.cli", Failing("coupling.cli"))
        with pytest.raises(ImportError):
            entry.main([])
        assert capsys.readouterr().err == "A NumPy version >=1.25 is required\n"
        assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, set())
    finally:
        signal.signal(signal.SIGINT, old)


@pytest.mark.skipif(os.geteuid() != 0 or not shutil.which("mount"), reason="needs root to mount a small tmpfs")
def test_a_full_device_stops_the_run_in_one_line_and_it_resumes(tmp_path):
    """The run's device fills up (a 200 KB tmpfs; bar_wave's frames take more): one line naming
    the run's directory, exit 1, no traceback, the directory kept; with room again --resume
    finishes it. HDF5, failing to flush, left its file half-closed: h5py's tracebacks on the
    terminal, then a segmentation fault (exit 139) as the file was freed."""
    dev = tmp_path / "dev"
    dev.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(dev)]).returncode:
        pytest.skip("tmpfs cannot be mounted here")
    try:
        femdem = str(Path(sys.executable).parent / "femdem")
        out = dev / "run"
        r = subprocess.run([femdem, "run", "bar_wave", "--set", "clock.t_end=1e-6", "--quiet", "--out", str(out)],
                           cwd=tmp_path, capture_output=True, text=True, timeout=300)
        partial = dev / "run.partial"
        assert r.returncode == 1, (r.returncode, r.stderr)
        assert r.stderr == (f"femdem: no space left on the device of {partial} (No space left on device); the run "
                            f"stopped and is kept there as written: free space, then --resume {partial}\n"), r.stderr
        assert (partial / "run.json").is_file() and not out.exists()
        assert subprocess.run(["mount", "-o", "remount,size=64m", str(dev)]).returncode == 0
        r = subprocess.run([femdem, "run", "--resume", str(partial), "--quiet"], cwd=tmp_path, capture_output=True,
                           text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        assert json.loads((out / "summary.json").read_text())["status"] == "ok"
    finally:
        subprocess.run(["umount", "-l", str(dev)])


def test_a_run_whose_case_file_changed_is_not_resumed(tmp_path, capsys):
    """--resume rebuilds the case from its file and the run's parameters: a file edited since the
    run started (a probe added, its duration changed) resumed as a mix of the two, status ok (the
    new probe nan from the checkpoint on). Refused in one line, exit 2; the file as it was resumes."""
    from coupling.cli import main
    case = tmp_path / "wave.toml"
    case.write_text((ROOT / "cases" / "verification" / "bar_wave.toml").read_text())
    out = tmp_path / "run"
    assert main(["run", str(case), "--set", "clock.t_end=2e-5", "--out", str(out), "--quiet"]) == 0
    (out / "summary.json").unlink()  # as a run stopped before its first checkpoint
    partial = Path(str(out) + ".partial")
    out.rename(partial)
    capsys.readouterr()
    case.write_text(case.read_text() + "\n# edited\n")
    assert main(["run", "--resume", str(partial), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"its input {case} (case_file) changed since the run started" in err[0], err
    case.write_text(case.read_text().removesuffix("\n# edited\n"))
    assert main(["run", "--resume", str(partial), "--quiet"]) == 0
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"
    partial.mkdir()
    (partial / "run.json").write_text(json.dumps({**json.loads((out / "run.json").read_text())}))
    case.unlink()
    assert main(["run", "--resume", str(partial), "--quiet"]) == 2
    assert "is gone or unreadable" in capsys.readouterr().err


@pytest.mark.parametrize("args, env", [
    (["chung_ooi_1"], {}),  # a scheduler's bare environment: no PATH, no HOME (LIGGGHTS in process)
    (["chung_ooi_1", "--dem", "yade"], {}),
    (["bonded_block_modulus"], {"HOME": "/dev/null", "PATH": "/usr/bin:/bin"}),  # a home that is no directory
])
def test_a_bare_environment_runs_cases(tmp_path, args, env):
    """Without PATH OpenMPI's start in process aborted before MPI_Init (exit 1, nothing said);
    without HOME YADE stopped on KeyError 'HOME'; with HOME not a directory the calibration's
    cache failed (it ignored the project's cache directory)."""
    femdem = str(Path(sys.executable).parent / "femdem")
    r = subprocess.run([femdem, "run", *args, "--quiet", "--out", str(tmp_path / "run")], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and r.stderr == "", (r.returncode, r.stderr)
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["status"] == "ok"


def test_a_stopped_comparison_is_finished_by_the_same_command(tmp_path):
    """SIGTERM during `femdem compare`: exit 143, one line saying how it goes on; the same command
    with the same --out keeps the finished engine's run, resumes the stopped one and writes
    compare.json (it was refused: --out not empty, and compare.json could not be had)."""
    out = tmp_path / "cmp"
    cmd = [sys.executable, "-m", "coupling.cli", "compare", "coupled_vibration", "--dem", "liggghts,lammps",
           "--set", "run.steps=1500", "--set", "output.checkpoint_every=300", "--out", str(out)]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.time()
    while time.time() - t0 < 120 and proc.poll() is None and not (out / "lammps.partial" / "checkpoint").exists():
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143 and err == (f"femdem: terminated (SIGTERM); the comparison is kept in {out}: "
                                              f"finish it with the same command and --out {out}\n"), err
    first = json.loads((out / "liggghts" / "summary.json").read_text())
    other = [c if c != "run.steps=1500" else "run.steps=1400" for c in cmd]  # not this comparison's
    r = subprocess.run(other, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "holds a run on liggghts of another case or other parameters" in r.stderr, r.stderr
    shutil.copytree(out / "lammps.partial", tmp_path / "alone" / "lammps.partial")  # the stopped run alone
    r = subprocess.run([c if c != str(out) else str(tmp_path / "alone") for c in other], cwd=ROOT,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "holds a run on lammps of another case or other parameters" in r.stderr, r.stderr
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    result = json.loads((out / "compare.json").read_text())
    assert result["status"] == {"liggghts": "ok", "lammps": "ok"}
    assert json.loads((out / "liggghts" / "summary.json").read_text()) == first  # kept, not run again
    again = [sys.executable, "-m", "coupling.cli", "compare", "coupled_vibration", "--dem", "liggghts,lammps",
             "--set", "run.steps=1000", "--out", str(out)]  # another comparison into a finished one's directory
    r = subprocess.run(again, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "not an empty directory" in r.stderr, r.stderr


def test_a_run_whose_load_file_changed_is_not_resumed(tmp_path):
    """The same for a file a parameter names (a load curve): its contents were not in run.json."""
    from coupling.case import input_digests
    from coupling.params import CaseError
    from coupling.run import _same_inputs
    case, curve = tmp_path / "c.toml", tmp_path / "load.csv"
    case.write_text("# a case\n")
    curve.write_text("0,0\n1,1\n")
    params = {"loads.press.file": str(curve)}
    info = {"case_file": str(case), "parameters": params, "inputs": input_digests(case, params)}
    _same_inputs(info, "--resume X")  # unchanged: taken
    curve.write_text("0,0\n1,10\n")
    with pytest.raises(CaseError, match=r"its input .*load.csv \(loads.press.file\) changed since the run started"):
        _same_inputs(info, "--resume X")
