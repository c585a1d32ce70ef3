"""The ``femdem`` command line (contract in shared/design/ARCHITECTURE.md).

Exit codes: 0 ok; 1 the run failed with an error (engine failure or defect; the message is
in summary.json); 2 bad input (one line: key, value, what is allowed); 3 run stopped on a
detected instability; 130 interrupted (Ctrl-C), 143 terminated (SIGTERM, a batch scheduler's
notice before its SIGKILL): both close the engines and their workers and leave a run that
can checkpoint in its ``.partial`` directory for ``--resume``.
"""
from __future__ import annotations

import argparse
import functools
import os
import signal
import sys
import threading
from pathlib import Path

from .case import DEFAULT_ENGINE, ENGINES, MODES, bundled_cases, load_case
from .params import CaseError, parse_set


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # argparse's own errors are bad input too: one line, exit 2
        print(f"femdem: {message}", file=sys.stderr)
        raise SystemExit(2)


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="femdem", description="FEM far field + DEM damage zone co-simulation")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    d = sub.add_parser("doctor", help="engines, versions, MPI stacks, what is missing")
    d.add_argument("--json", action="store_true")
    sub.add_parser("cases", help="list bundled cases")
    k = sub.add_parser("params", help="a case's parameters: dotted key, value, allowed range, unit, meaning")
    k.add_argument("case", help="bundled case name or path to a .toml case file")
    sub.add_parser("schema", help="what a study case file may declare: tables, keys, allowed values, meaning "
                   "(docs/cases.md)")
    r = sub.add_parser("run", help="run a case")
    r.add_argument("case", nargs="?", help="bundled case name or path to a .toml case file")
    # LIGGGHTS by default: the fastest path (zero-copy arrays; YADE's per-particle Python calls
    # cost ~2 us per particle and step, more than its own step: README "Engines")
    r.add_argument("--dem", default=None, help=f"DEM engine: {', '.join(ENGINES)} (default {DEFAULT_ENGINE})")
    r.add_argument("--mode", default=None, help=f"{', '.join(MODES)} (default: the case's first mode)")
    r.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a parameter by its dotted key (as echoed in summary.json); keys, "
                        "values and allowed ranges: femdem params CASE")
    r.add_argument("--out", default=None, help="run directory (default runs/<case>-<mode>-<time>)")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.add_argument("--resume", default=None, metavar="DIR", help="continue a stopped run from its last checkpoint")
    b = sub.add_parser("bench", help="speed against error over a parameter sweep")
    b.add_argument("case")
    b.add_argument("--sweep", action="append", default=[], metavar="KEY=V1,V2,...", help="a swept parameter")
    b.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="fixed for every run")
    b.add_argument("--mode", default="coupled", help="mode of the swept runs")
    b.add_argument("--dem", default="liggghts")
    b.add_argument("--reference-mode", default="dem", help="mode of the reference run (default dem)")
    b.add_argument("--reference-set", action="append", default=[], metavar="KEY=VALUE",
                   help="overrides of the reference run (e.g. the finest setting)")
    b.add_argument("--qoi", action="append", default=[], help="quantity of interest to compare (repeatable)")
    b.add_argument("--repeat", type=int, default=1, metavar="N",
                   help="rounds of the reference and every point, run side by side: medians of wall time and "
                        "speedup (default 1, the reference from the cache if there)")
    c = sub.add_parser("compare", help="the same case on several DEM engines, side by side")
    c.add_argument("case")
    c.add_argument("--dem", required=True, help="comma-separated engines, e.g. yade,liggghts")
    c.add_argument("--mode", default=None)
    c.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    c.add_argument("--out", default=None)
    b.add_argument("--out", default=None)
    return p


class _UntilReaderLeaves:
    """A terminal stream that goes quiet when its reader leaves (``femdem run ... 2>&1 | head``):
    a write to the closed pipe would raise BrokenPipeError in the middle of a run, so from then on
    the stream's descriptor writes to /dev/null and the run, its files and its exit code go on."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            self._silence()
            return len(text)

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._silence()

    def _silence(self) -> None:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, self._stream.fileno())  # the buffered text goes there too
        os.close(null)

    def __getattr__(self, name):  # isatty, fileno, encoding, ... as the stream's
        return getattr(self._stream, name)


def _kept(stop: BaseException) -> str:
    """"; the run is kept in DIR: ..." for a run stopped while it ran (run.execute names its
    directory on the exception), else ""."""
    if getattr(stop, "hint", None):  # (a study of several runs says how it goes on)
        return f"; {stop.hint}"
    d = getattr(stop, "run_dir", None)
    return f"; the run is kept in {d}: continue it with femdem run --resume {d}" if d and d.is_dir() else ""


class Terminated(BaseException):
    """SIGTERM received: unwinds the run as Ctrl-C does (its engines and workers closed, its
    shared memory released), not caught as an error on the way."""


def _terminate(signum, frame):
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a second notice does not cut the clean-up short
    raise Terminated


def main(argv: list[str] | None = None) -> int:
    """Exit codes as in the module docstring; no traceback reaches the terminal: an unforeseen
    error prints one line and leaves its traceback in a log file."""
    streams = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = map(_UntilReaderLeaves, streams)
    # SIGTERM's default ends the process where it stands: an engine's worker, its MPI ranks and
    # shared memory were left to the OS (only Python's resource tracker released the memory, not
    # always: tests/test_faults.py). Handled while main runs (a caller's handler is put back).
    on_main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _terminate) if on_main else None
    # errors in finalizers (h5py's objects of a file whose write failed) go to the log, not the terminal
    unraisable, sys.unraisablehook = sys.unraisablehook, _log_unraisable
    try:
        return _main(argv)
    except KeyboardInterrupt as exc:
        print(f"femdem: interrupted{_kept(exc)}", file=sys.stderr)
        return 130
    except Terminated as exc:
        print(f"femdem: terminated (SIGTERM){_kept(exc)}", file=sys.stderr)
        return 143
    except Exception as exc:  # a defect: one line here, the traceback in a log
        from .run import OutOfSpace
        if isinstance(exc, OutOfSpace):  # (the run's device filled: not a defect)
            print(f"femdem: {exc}", file=sys.stderr)
            return 1
        log = _log_traceback()
        print(f"femdem: internal error: {type(exc).__name__}: {exc} (traceback in {log})", file=sys.stderr)
        return 1
    finally:
        if on_main:
            signal.signal(signal.SIGTERM, previous)
        sys.unraisablehook = unraisable
        for stream in (sys.stdout, sys.stderr):  # now, where a closed pipe is caught, not at exit
            stream.flush()
        sys.stdout, sys.stderr = streams


def _log_unraisable(u) -> None:
    """sys.unraisablehook: the exception's traceback into this process's log (never raises)."""
    import traceback
    try:
        with _log_path().open("a") as f:
            f.write(f"{u.err_msg or 'Exception ignored in'}: {u.object!r}\n"
                    + "".join(traceback.format_exception(u.exc_type, u.exc_value, u.exc_traceback)))
    except Exception:  # (its device full too)
        pass


@functools.lru_cache(maxsize=None)
def _log_path() -> Path:
    """This process's log of what the terminal is spared (one file, made at the first use)."""
    import datetime
    from . import CACHE
    log = CACHE / "logs" / f"femdem-{datetime.datetime.now():%Y%m%d-%H%M%S}-{os.getpid()}.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    return log


def _log_traceback() -> Path:
    import traceback
    log = _log_path()
    with log.open("a") as f:
        f.write(f"femdem {' '.join(sys.argv[1:])}\n{traceback.format_exc()}")
    return log


def _main(argv: list[str] | None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.command == "doctor":
            from .doctor import doctor
            return doctor(as_json=args.json)
        if args.command == "cases":
            return _cases()
        if args.command == "params":
            return _params(args.case)
        if args.command == "schema":
            from .study import document_schema
            print(document_schema())
            return 0
        if args.command == "run":
            return _run(args)
        if args.command == "compare":
            from .compare import cli as compare_cli
            return compare_cli(args)
        if args.command == "bench":
            from .bench import cli as bench_cli
            return bench_cli(args)
    except CaseError as exc:
        print(f"femdem: {exc}", file=sys.stderr)
        return 2
    return 0


def _cases() -> int:
    cases = bundled_cases()
    w = max(map(len, cases), default=0)
    for name, path in cases.items():
        try:
            case = load_case(str(path))
            print(f"{name:{w}s}  {'/'.join(case.scene.MODES):16s} {case.description}")
        except CaseError as exc:
            print(f"{name:{w}s}  (invalid: {exc})")
    return 0


def _params(name: str) -> int:
    """One line per parameter of the case: key = value (the case file's), allowed, meaning."""
    from .case import COMMON
    case = load_case(name)
    schema = {**COMMON, **case.scene.PARAMETERS}
    for key in sorted(schema):
        value = case.parameters[key]
        text = repr([list(row) for row in value]) if schema[key].kind == "table" else repr(value)  # as --set takes it
        print(f"{key} = {text}  # {schema[key].allowed()}; {schema[key].doc}")
    return 0


def _run(args) -> int:
    from .case import refuse_ineffective
    from .run import execute, resume
    for flag in ("out", "resume"):
        if getattr(args, flag) == "":
            raise CaseError(f"--{flag} '': empty; allowed: a directory path")
    if args.resume:
        ignored = [f"--{k}" for k in ("dem", "mode", "set", "out") if getattr(args, k)] + (["CASE"] if args.case else [])
        if ignored:
            raise CaseError(f"--resume {args.resume}: {ignored[0]} would be ignored (a resumed run keeps its case, "
                            "engine, mode, parameters and directory); allowed: --resume DIR [--quiet]")
        code, out, summary = resume(args.resume, args.quiet)
    else:
        if not args.case:
            raise CaseError("CASE: missing; allowed: a bundled case name, a .toml path, or --resume DIR")
        if args.dem is not None and args.dem not in ENGINES:
            raise CaseError(f"--dem {args.dem}: allowed {', '.join(ENGINES)}")
        case = load_case(args.case, parse_set(args.set))
        mode = case.scene.MODES[0] if args.mode is None else args.mode
        if mode not in MODES:
            raise CaseError(f"--mode {mode}: allowed {', '.join(MODES)}")
        refuse_ineffective(case, mode, args.dem)
        code, out, summary = execute(case, mode, args.dem or DEFAULT_ENGINE, args.out, args.quiet)
    if not args.quiet or code:  # a run that failed reports on stderr, where its caller looks
        _report(summary, out, sys.stderr if code else sys.stdout)
    return code


def _report(s: dict, out, file) -> None:
    print(f"{s['case']} ({s['mode']}{', ' + s['dem_backend'] if s['dem_backend'] else ''}): "
          f"{s['status']} in {s['timing_s']['total']:.2f} s, {s['clock']['steps']} steps", file=file)
    if s["message"]:
        print(f"  {s['message']}", file=file)
    for name, c in s["checks"].items():
        ref = c["reference"]
        ranged = isinstance(ref, list)
        err = (f"rel_err {c['rel_err']:.2e}" if c["rel_err"] is not None else "range" if ranged
               else f"limit {c['tol']:g}")
        value = "n/a" if c["value"] is None else f"{c['value']:.6g}"
        ref = f"[{ref[0]:.6g}, {ref[1]:.6g}]" if ranged else f"{ref:.6g}"
        print(f"  check {name}: {value} vs {ref} ({err}, "
              f"{'PASS' if c['passed'] else 'FAIL'}; {c['source']})", file=file)
    print(f"  results: {out}/summary.json", file=file)
    plots = sorted((out / "plots").glob("*.png"))
    if plots:
        print(f"  plot:    {plots[0]}", file=file)


if __name__ == "__main__":
    raise SystemExit(main())
