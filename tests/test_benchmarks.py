"""The asv benchmark suite (benchmarks/, docs/benchmarks.md "Tracking across commits") runs:
every benchmark module imports, and each benchmark's setup and time_ functions run once with
the module's QUICK parameters (its smallest size), for every value of its other parameters
(backends, store places). A backend that cannot be built here (pyfftw or numba absent)
makes setup raise NotImplementedError, which asv reports as skipped: so does this test.
"""

import importlib
import inspect
import itertools
import pathlib
import pkgutil
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import benchmarks  # noqa: E402  (the repository root must be on the path first)
from benchmarks import _support  # noqa: E402

MODULES = sorted(name for _, name, _ in pkgutil.iter_modules(benchmarks.__path__)
                 if not name.startswith("_"))


def _benchmarks(module):
    """(class, [time_ method names]) of every benchmark class of ``module``."""
    found = []
    for _, cls in inspect.getmembers(module, inspect.isclass):
        if cls.__module__ != module.__name__:
            continue
        timed = sorted(name for name in dir(cls) if name.startswith("time_"))
        if timed:
            found.append((cls, timed))
    return found


def _cases():
    for name in MODULES:
        module = importlib.import_module(f"benchmarks.{name}")
        quick = getattr(module, "QUICK", {})
        for cls, timed in _benchmarks(module):
            choices = [[quick[p]] if p in quick else list(values)
                       for p, values in zip(cls.param_names, cls.params)]
            for params in itertools.product(*choices):
                yield pytest.param(cls, timed, params,
                                   id=f"{name}.{cls.__name__}[{'-'.join(params)}]")


def test_every_module_has_benchmarks_and_quick_parameters():
    assert MODULES == ["bench_operator", "bench_space", "bench_store"]
    for name in MODULES:
        module = importlib.import_module(f"benchmarks.{name}")
        classes = _benchmarks(module)
        assert classes, name
        for cls, _ in classes:
            assert len(cls.params) == len(cls.param_names)
            assert set(module.QUICK) <= set(cls.param_names)


@pytest.fixture(scope="module", autouse=True)
def _release_built():
    yield
    _support.release()


@pytest.mark.parametrize("cls, timed, params", list(_cases()))
def test_benchmark_runs_once(cls, timed, params):
    bench = cls()
    try:
        bench.setup(*params)
    except NotImplementedError as exc:
        pytest.skip(str(exc))
    for name in timed:
        bench.setup(*params)          # asv runs setup before every timed call
        assert getattr(bench, name)(*params) is None
