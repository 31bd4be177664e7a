"""granframe's import layers and the absence of import cycles.

The contracts are those of ``[tool.importlinter]`` in pyproject.toml (``lint-imports`` in
the repository root checks them by hand); CI runs pytest, so these tests are how CI checks
them. An import inside a function counts like any other: it is a dependency all the same,
and one that only shows when the function runs.
"""

import pathlib
import subprocess
import sys
import tomllib

import grimp
import pytest

ROOT = pathlib.Path(__file__).parent.parent
PYPROJECT = ROOT / "pyproject.toml"
CONFIG = tomllib.loads(PYPROJECT.read_text())["tool"]["importlinter"]

#: lint-imports, run by this interpreter so that it sees this environment's packages.
LINT_IMPORTS = "from importlinter.cli import lint_imports_command; lint_imports_command()"


@pytest.mark.parametrize("contract", [c["id"] for c in CONFIG["contracts"]])
def test_import_contract_is_kept(contract):
    """One contract, by its id; a broken one fails with import-linter's report (the
    chains of imports that break it, with their lines)."""
    out = subprocess.run([sys.executable, "-c", LINT_IMPORTS, str(PYPROJECT), "--contract",
                          contract, "--no-cache", "--no-logo"],
                         cwd=ROOT, capture_output=True, text=True)
    if out.returncode != 0:
        pytest.fail(f"contract '{contract}' is broken:\n{out.stdout}{out.stderr}", pytrace=False)


def shortest_cycle(graph: grimp.ImportGraph, module: str) -> list[str] | None:
    """The shortest chain of imports from ``module`` back to itself, as the modules it
    passes (``module`` first and last); None when there is none."""
    cycles = [[module, *chain] for imported in graph.find_modules_directly_imported_by(module)
              if (chain := graph.find_shortest_chain(importer=imported, imported=module))]
    return min(cycles, key=lambda c: (len(c), c), default=None)


def describe(graph: grimp.ImportGraph, chain: list[str]) -> str:
    """One line per import of ``chain``: importer -> imported and where it is imported."""
    lines = []
    for importer, imported in zip(chain, chain[1:]):
        details = graph.get_import_details(importer=importer, imported=imported)
        where = "; ".join(f"l.{d['line_number']}: {d['line_contents']}" for d in details)
        lines.append(f"  {importer} -> {imported} ({where})")
    return "\n".join(lines)


def test_no_import_cycle():
    """No module of granframe or of its plugins imports itself through other modules.

    The graph is built module by module, nothing squashed, function-level imports
    included; the first module (by name) on a cycle is reported with its shortest cycle.
    """
    graph = grimp.build_graph(*CONFIG["root_packages"], cache_dir=None)
    for module in sorted(graph.modules):
        cycle = shortest_cycle(graph, module)
        if cycle is not None:
            pytest.fail(f"import cycle through {module} ({len(cycle) - 1} imports):\n"
                        + describe(graph, cycle), pytrace=False)
