import importlib
import pathlib
import textwrap

import pytest

from granframe.registry import Registries, get_plugin_manager

FAKE_SITE = pathlib.Path(__file__).parent / "fake_site"


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
