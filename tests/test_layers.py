"""granframe's import layers, the absence of import cycles, and what the studies and the
tools import (granframe and its public names only).

The contracts are those of ``[tool.importlinter]`` in pyproject.toml (``lint-imports`` in
the repository root checks them by hand); CI runs pytest, so these tests are how CI checks
them. An import inside a function counts like any other: it is a dependency all the same,
and one that only shows when the function runs.
"""

import ast
import pathlib
import re
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


# -- What the studies and the tools import ----------------------------------------------------

STUDIES = ROOT / "studies"
#: modules whose private-name imports another change is reworking (the rest of the check
#: applies to them)
PRIVATE_NAMES_PENDING = {"granframe/tools/cli.py"}
#: calls that add to the import path or load a source file as a module
PATH_CALLS = {"sys.path.insert", "sys.path.append", "sys.path.extend", "site.addsitedir"}
#: a 'module:function' reference, which a run description resolves by importing the module
REFERENCE = re.compile(r"([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*):[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*")
FILE_LOADERS = {"importlib.util.spec_from_file_location", "spec_from_file_location",
                "importlib.machinery.SourceFileLoader", "SourceFileLoader", "runpy.run_path",
                "imp.load_source"}


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def import_violations(source: str, study_names=frozenset(), private_names=True) -> list:
    """(line, reason) for each way a module of studies/ or granframe/tools/ reaches past the
    package: a private name imported from another module (``from m import _x``, a private
    module ``m._x``, or ``m._x`` of a granframe module or a study it imported), a change of
    sys.path, a source file loaded as a module, an import from tests/ (a ``tests``,
    ``conftest`` or ``test_*`` module), or an import of another study (by module name, or
    as a ``'study:function'`` reference a run description resolves)."""
    tree = ast.parse(source)
    found, modules = [], set()

    def internal(module: str) -> bool:
        top = module.split(".")[0]
        return top == "granframe" or top in study_names

    def check_module(line, module):
        parts = module.split(".")
        if parts[0] in ("tests", "conftest") or parts[0].startswith("test_"):
            found.append((line, f"imports {module} from tests/"))
        if parts[0] in study_names:
            found.append((line, f"imports the study {parts[0]}"))
        if private_names and any(_private(p) for p in parts):
            found.append((line, f"imports the private module {module}"))

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                check_module(node.lineno, alias.name)
                if internal(alias.name):
                    modules.add(alias.asname or alias.name.split(".")[0])
        elif isinstance(node, ast.ImportFrom):
            module = "." * node.level + (node.module or "")
            check_module(node.lineno, module.lstrip(".") or ".")
            for alias in node.names:
                if private_names and _private(alias.name):
                    found.append((node.lineno, f"imports the private name {alias.name} from "
                                               f"{module}"))
                if internal(module.lstrip(".")) or node.level:
                    modules.add(alias.asname or alias.name)
        elif isinstance(node, ast.Call):
            called = ast.unparse(node.func)
            if called in PATH_CALLS:
                found.append((node.lineno, f"changes the import path ({called})"))
            if called in FILE_LOADERS:
                found.append((node.lineno, f"loads a source file as a module ({called})"))
            if (called.endswith("import_module") and node.args
                    and isinstance(node.args[0], ast.Constant)
                    and isinstance(node.args[0].value, str)):
                check_module(node.lineno, node.args[0].value)
        elif isinstance(node, (ast.Assign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                if ast.unparse(target).startswith("sys.path"):
                    found.append((node.lineno, "changes the import path (sys.path)"))
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            reference = REFERENCE.fullmatch(node.value)
            if reference and reference.group(1) in study_names:
                found.append((node.lineno, f"refers to the study function {node.value}"))
    if private_names:
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and _private(node.attr)
                    and isinstance(node.value, ast.Name) and node.value.id in modules):
                found.append((node.lineno, f"uses the private name {node.value.id}."
                                           f"{node.attr} of another module"))
    return sorted(set(found))


def test_studies_and_tools_import_only_the_package_and_its_public_names():
    """Every module of studies/ and granframe/tools/: no private name of another module,
    no sys.path change or source file loaded by path, nothing from tests/, no other study
    (a study imports granframe and granframe.tools.studykit)."""
    names = frozenset(path.stem for path in STUDIES.glob("*.py"))
    paths = sorted(STUDIES.glob("*.py")) + sorted((ROOT / "granframe" / "tools").glob("*.py"))
    problems = []
    for path in paths:
        relative = path.relative_to(ROOT).as_posix()
        for line, reason in import_violations(path.read_text(), names,
                                              relative not in PRIVATE_NAMES_PENDING):
            problems.append(f"  {relative}:{line}: {reason}")
    if problems:
        pytest.fail("studies and tools reach past the package:\n" + "\n".join(problems),
                    pytrace=False)


@pytest.mark.parametrize("source, reason", [
    ("from granframe.space.exact import _positive", "private name _positive"),
    ("from granframe import _version", "private name _version"),
    ("import granframe._builtin", "private module granframe._builtin"),
    ("import granframe.tools.cli as cli\ncli._main()", "private name cli._main"),
    ("import sys\nsys.path.insert(0, 'tests')", "import path"),
    ("import sys\nsys.path[:0] = ['x']", "import path"),
    ("import importlib.util\nimportlib.util.spec_from_file_location('s', 'space.py')",
     "source file"),
    ("import test_space_validation as T", "from tests/"),
    ("from tests.conftest import x", "from tests/"),
    ("from space import cfl_time_step", "the study space"),
    ("import importlib\nimportlib.import_module('granular_hcs')", "the study granular_hcs"),
    ("f = {'function': 'granular_hcs:longitudinal_mode'}", "study function"),
])
def test_the_import_check_finds_each_way_past_the_package(source, reason):
    found = import_violations(source, frozenset({"space", "granular_hcs"}))
    assert any(reason in text for _, text in found), found


def test_the_import_check_accepts_public_names_and_the_standard_library():
    source = ("import os\nimport numpy\nfrom granframe.tools.studykit import finish\n"
              "from granframe.theory import euler\neuler.euler_riemann\nos._exit\n"
              "s = 'granframe.theory.modes:longitudinal_maxwellian'\n")
    assert import_violations(source, frozenset({"space"})) == []
