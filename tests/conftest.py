import coupling  # noqa: F401  (first: it sets the BLAS threads before numpy loads)
import json
from pathlib import Path

import pytest

from coupling.cli import main


@pytest.fixture
def femdem(tmp_path, capsys):
    """Run the CLI in-process; returns (exit code, summary or None, stderr)."""
    counter = iter(range(1000))

    def run(*args):
        out = tmp_path / f"run{next(counter)}"
        argv = list(args) + (["--out", str(out), "--quiet"] if args and args[0] == "run" else [])
        code = main(argv)
        err = capsys.readouterr().err
        summary = json.loads((out / "summary.json").read_text()) if (out / "summary.json").exists() else None
        return code, summary, err

    return run


def assert_checks(summary):
    assert summary["status"] == "ok", summary["message"]
    assert summary["checks"], "a verification case must record checks"
    for name, c in summary["checks"].items():
        assert c["passed"], f"{name}: {c}"
