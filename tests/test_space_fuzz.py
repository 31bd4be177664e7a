"""Space descriptions fuzzed as a careless or hostile user would write them, through
``granframe limits``, ``granframe run --set`` and the Python API: every case ends within a
time bound with exit status 0, 2 or 3 (the API: a result, or ValueError/TypeError naming
a parameter, or a health stop), no traceback, and no store left "running".

The cases are counted by path and outcome in :data:`COUNTS`; the last test prints them
(``pytest -s tests/test_space_fuzz.py``)."""

import collections
import contextlib
import copy
import io
import math
import time

import pytest
import tomli_w
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from conftest import mutated
from test_cli_fuzz import time_limit
from test_space_bad_input import BASE as SOD
from granframe.run.description import RunDescription
from granframe.run.runner import HealthError, Simulation
from granframe.run.storage import RunStore
from granframe.tools.cli import main

#: seconds one case may take (a generated run is two steps of 10 cells of a 16^2 grid)
LIMIT = 30
#: what a run may allocate (granframe.memory's budget)
BUDGET = 256 * 2 ** 20

#: the Sod tube between a specular and a diffuse wall, 10 cells, two steps
BASE = {**SOD, "space": {**SOD["space"], "cells": 10}}

EXTREME = [0, -1, 1, 2.5, 1e-300, 5e-324, 1e300, 1.7e308, 9.2e18, 1e30, -1e300, math.nan,
           math.inf, -math.inf, 10 ** 20, "x", "", True, [], [1.0, 2.0], {"name": "x"}]
KEYS = {
    "space.cells": [10, 5, 4, 0, -3, 10 ** 9, 10 ** 12, 8.5, "10"],
    "space.length": [1.0, 0.25, 1e-60, 1e60, 1e308, 0.0],
    "space.block_cells": [5, 2, 3, 0, 7, 100],
    "space.reconstruction": ["muscl", "weno5", "upwind", "nope"],
    "space.left": ["specular", "periodic", "diffuse", "nope"],
    "space.right": ["specular", "periodic", "diffuse"],
    "space.right.temperature": [1.2, 0.0, 1e-300, 1e300, 5.0],
    "space.right.accommodation": [1.0, 0.5, 0.0, 2.0],
    "space.right.velocity": [0.0, 1.0, 1e300, [1.0, 2.0]],
    "space.collisions": [True, False, 1, "no"],
    "initial.left.density": [1.0, 1e300, 1e-300, 1e50, 1e-50, 0.0],
    "initial.right.temperature": [0.8, 5e-324, 1e308, 1e-50, 1e50, 30.0],
    "initial.left.velocity": [0.0, 1.0, 10.0, 1e300, [1.0, 2.0, 3.0]],
    "initial.interface": [0.5, 0.0, 1.0, 0.999],
    "initial": ["maxwellian", "riemann", {"name": "sinusoidal_mode"},
                {"name": "sinusoidal_mode", "mode": 100},
                {"name": "sinusoidal_mode", "field": "velocity", "amplitude": 1e300},
                {"name": "space_function", "function": "nowhere:f0"}],
    "knudsen": [1.0, 9.2e18, 1e-300, 1e300, 1e-3],
    "heat_bath": [0.0, 0.1, 1e300],
    "time_step": [0.003, 1e-320, 0.006, 1.7e308, 0.002],
    "final_time": [0.006, 0.003, 1e308, 0.0],
    "output.snapshot_interval": [0.003, 1.7e308, 0.006, 0.0],
    "grid.truncation_radius": [6.4, 1e30, 19.0],
    "grid.half_width": [7.1, 1e30, 1e-3],
    "grid.n_modes": [16, 8, 4, 10 ** 9, 15],
    "operator.precision": ["float64", "float32", [1.0, 2.0], "x"],
    "operator.name": ["fast_spectral", "direct_spectral"],
    "integrator": ["rk4", "dopri54", "penalised_euler", "if_rk4", "x"],
    "space": [None],
}
#: one to three keys changed, each to one of its own values (twice as likely) or an extreme
changes = st.lists(st.sampled_from(list(KEYS)).flatmap(lambda key: st.tuples(
    st.just(key), st.one_of(st.sampled_from(KEYS[key]), st.sampled_from(KEYS[key]),
                            st.sampled_from(EXTREME)))),
    min_size=1, max_size=3)

#: (path, outcome) -> number of cases
COUNTS = collections.Counter()




def settings_of(change) -> tuple[dict, list[str]]:
    """The base table with the keys TOML cannot carry (None: removed) applied, and the
    ``--set KEY=VALUE`` arguments of the others."""
    table, arguments = copy.deepcopy(BASE), []
    for key, value in change:
        try:
            text = tomli_w.dumps({"v": value}).partition("=")[2].strip()
        except (TypeError, ValueError):
            text = None
        if value is None or text is None or "\n" in text:
            mutated(table, [(key, value)])
        else:
            arguments += ["--set", f"{key}={text}"]
    return table, arguments


def outcome(code: int, stderr: str) -> str:
    """The kind of an exit: 'ok', 'health stop' or the error's owner ('RiemannProblem',
    'run', ...)."""
    if code == 0:
        return "ok"
    if code == 3:
        return "health stop or above the step limit"
    first = stderr.split("granframe: error: ", 1)[-1]
    return "error: " + first.split(":", 1)[0].split(" parameter")[0][:40]


def command(path, arguments, tmp_path, monkeypatch):
    """Run ``granframe ARGUMENTS`` in ``tmp_path``: (status, stderr), within LIMIT."""
    monkeypatch.setenv("GRANFRAME_MEMORY_BUDGET", str(BUDGET))
    monkeypatch.chdir(tmp_path)
    stderr = io.StringIO()
    started = time.perf_counter()
    with time_limit(LIMIT), contextlib.redirect_stderr(stderr), \
            contextlib.redirect_stdout(io.StringIO()):
        try:
            code = main(arguments)
        except SystemExit as exc:      # argparse: a usage error, status 2
            code = exc.code
    text = stderr.getvalue()
    COUNTS[(path, outcome(code, text))] += 1
    COUNTS[(path, "seconds")] += time.perf_counter() - started
    event(f"{path}: exit {code}")
    assert code in (0, 2, 3), (arguments, code, text)
    assert "Traceback" not in text, (arguments, text)
    if code == 2:      # one line naming what is wrong (a parameter, a name, a file)
        assert text.startswith("granframe: error: ") and text.count("\n") == 1, (arguments,
                                                                                 text)
    return code, text


FUZZ = settings(max_examples=60, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow,
                                       HealthCheck.function_scoped_fixture])


@given(change=changes)
@FUZZ
def test_limits_of_generated_space_descriptions(change, tmp_path, monkeypatch):
    table, arguments = settings_of(change)
    (tmp_path / "d.toml").write_text(tomli_w.dumps(table))
    command("limits", ["limits", "d.toml", *arguments], tmp_path, monkeypatch)


@given(change=changes)
@settings(FUZZ, max_examples=30)
def test_runs_of_generated_space_descriptions(change, tmp_path, monkeypatch):
    table, arguments = settings_of(change)
    (tmp_path / "d.toml").write_text(tomli_w.dumps(table))
    out = tmp_path / f"s{len(list(tmp_path.iterdir()))}.zarr"
    code, text = command("run", ["run", "d.toml", "--out", str(out), "--no-progress",
                                 *arguments], tmp_path, monkeypatch)
    if RunStore.exists(out):
        status = RunStore.open(out, complete=False).progress["status"]
        assert status != "running", (arguments, code, status, text)
        assert status == ("finished" if code == 0 else "failed"), (arguments, code, status)


@given(change=changes)
@FUZZ
def test_the_api_on_generated_space_descriptions(change, monkeypatch):
    """RunDescription.from_dict and Simulation (f0, the operator, the checks; no steps)."""
    monkeypatch.setenv("GRANFRAME_MEMORY_BUDGET", str(BUDGET))
    table = mutated(copy.deepcopy(BASE), change)
    started = time.perf_counter()
    try:
        with time_limit(LIMIT):
            Simulation(RunDescription.from_dict(table))
        kind = "ok"
    except (ValueError, TypeError, HealthError) as exc:
        message = str(exc)
        assert message and "\n" not in message and "Traceback" not in message, message
        assert "__init__()" not in message, message       # Python's own, not a parameter's
        kind = f"{type(exc).__name__}: {message.split(':', 1)[0][:40]}"
    COUNTS[("api", kind)] += 1
    COUNTS[("api", "seconds")] += time.perf_counter() - started
    event(f"api: {kind}")


def test_the_fuzz_counts():
    """Run after the fuzz tests (file order): every path ran, and the counts by outcome."""
    lines = []
    for path in ("limits", "run", "api"):
        cases = {kind: n for (p, kind), n in COUNTS.items() if p == path and kind != "seconds"}
        if not cases:
            pytest.skip("run with the fuzz tests above")
        lines.append(f"{path}: {sum(cases.values())} cases in "
                     f"{COUNTS[(path, 'seconds')]:.1f} s: " + ", ".join(
                         f"{n} {kind}" for kind, n in sorted(cases.items(), key=lambda x: -x[1])))
    print("\nspace fuzz counts\n" + "\n".join(lines))
