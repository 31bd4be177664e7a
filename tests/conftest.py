import importlib
import importlib.util
import pathlib
import textwrap

import pytest

import granframe as gf
from granframe.registry import Registries, get_plugin_manager
from granframe_cupy import gpu_available

FAKE_SITE = pathlib.Path(__file__).parent / "fake_site"

_GPU = [pytest.mark.gpu, pytest.mark.skipif(not gpu_available(),
                                            reason="needs CuPy and a CUDA GPU")]

#: Every array backend a backend-parametrised test body runs on: registry name, options,
#: marks. "cupy-host" is the CuPy backend's code path with NumPy on the host (module =
#: "numpy"); "cupy" and "cupy-generic" run on a GPU, with the fused kernels and with the
#: generic xp steps.
BACKENDS = {
    "numpy": ("numpy", {}, []),
    "pyfftw": ("pyfftw", {}, [pytest.mark.skipif(not importlib.util.find_spec("pyfftw"),
                                                 reason="pyfftw not installed")]),
    "cupy-host": ("cupy", {"module": "numpy"}, []),
    "cupy": ("cupy", {}, _GPU),
    "cupy-generic": ("cupy", {"fused": False}, _GPU),
}


@pytest.fixture(scope="session", params=[pytest.param(key, marks=marks, id=key)
                                         for key, (_, _, marks) in BACKENDS.items()])
def backend_table(request):
    """Run-description table of each array backend of :data:`BACKENDS`."""
    name, options, _ = BACKENDS[request.param]
    return {"name": name, **options}


@pytest.fixture(scope="session")
def backend(backend_table):
    """Each array backend of :data:`BACKENDS`, built (one test body for all of them)."""
    table = dict(backend_table)
    return gf.array_backend(table.pop("name"), **table)


@pytest.fixture
def fresh_registries():
    """Build registries from scratch (the process-wide cache is left alone)."""

    def build():
        importlib.invalidate_caches()
        return Registries(*get_plugin_manager())

    return build


@pytest.fixture
def make_distribution(tmp_path, monkeypatch):
    """Create an installed-looking distribution (module + .dist-info) on sys.path."""

    def make(dist_name: str, module_name: str, source: str, entry_point: str | None = None):
        site = tmp_path / f"site_{dist_name}"
        # installers write the normalised name (PEP 491): "a-b" -> "a_b"
        info = site / f"{dist_name.replace('-', '_')}-0.1.dist-info"
        info.mkdir(parents=True)
        (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist_name}\nVersion: 0.1\n")
        (info / "entry_points.txt").write_text(
            f"[granframe]\n{entry_point or module_name} = {module_name}\n")
        (site / f"{module_name}.py").write_text(textwrap.dedent(source))
        monkeypatch.syspath_prepend(str(site))
        return site

    return make


def mutated(table: dict, changes) -> dict:
    """``table`` (a description table, changed in place) with dotted keys set (None: removed);
    a string where a table is needed becomes ``{name = ...}``."""
    for key, value in changes:
        *parents, last = key.split(".")
        node = table
        for part in parents:
            child = node.get(part)
            node[part] = child = child if isinstance(child, dict) else (
                {"name": child} if isinstance(child, str) else {})
            node = child
        if value is None:
            node.pop(last, None)
        else:
            node[last] = value
    return table
