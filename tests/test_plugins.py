"""Plugin discovery: entry points, built-ins through the same hooks, errors, CLI."""

import json
import os
import subprocess
import sys

import pytest

import granframe
from granframe.errors import PluginError, UnknownNameError
from granframe.registry import FAMILIES, Registries, get_plugin_manager

from conftest import FAKE_SITE

EXPECTED_BUILTINS = {
    "restitution_laws": {"constant", "toscani", "viscoelastic", "tanh", "threshold"},
    "collision_kernels": {"vhs", "maxwell", "hard_spheres"},
    "quadratures": {"gauss_legendre", "circle_trapezoid", "lebedev", "sphere_product"},
    "array_backends": {"numpy"},
}


def test_builtins_register_through_the_public_hooks(fresh_registries):
    registries = fresh_registries()
    pm = registries.plugin_manager
    assert pm.get_plugin("builtin") is not None
    for family, names in EXPECTED_BUILTINS.items():
        assert names <= set(registries.names(family))
        for name in names:
            entry = registries.get(family, name)
            assert entry.source.plugin == "builtin" and entry.source.distribution == "granframe"
            assert entry.description
    # every family has a hook with the project prefix
    assert set(FAMILIES.values()) <= {h for h in dir(pm.hook) if h.startswith("granframe_")}


def test_out_of_tree_plugin_adds_a_law_and_a_kernel(monkeypatch, fresh_registries):
    monkeypatch.syspath_prepend(str(FAKE_SITE))
    registries = fresh_registries()
    law_entry = registries.get("restitution_laws", "exponential_decay")
    assert law_entry.source.plugin == "example"
    assert law_entry.source.distribution == "granframe-example-plugin"
    assert law_entry.source.version == "1.2.0"
    law = registries.create("restitution_laws", "exponential_decay", minimum=0.4, scale=2.0)
    import numpy
    e = law(numpy.array([0.0, 2.0, 1e6]))
    numpy.testing.assert_allclose(e, [1.0, 0.4 + 0.6 * numpy.exp(-1.0), 0.4])
    assert isinstance(law, granframe.RestitutionLaw) and not law.is_constant
    with pytest.raises(ValueError, match="'minimum' = 1.5"):
        registries.create("restitution_laws", "exponential_decay", minimum=1.5)
    kernel = registries.create("collision_kernels", "forward_peaked", exponent=1.0, anisotropy=0.5)
    assert kernel.angular_part(numpy.array([1.0]))[0] == 1.5
    assert kernel.prefactor(2) == pytest.approx(1 / (2 * numpy.pi))
    # the built-ins are still there, side by side
    assert {"constant", "exponential_decay"} <= set(registries.names("restitution_laws"))


def test_out_of_tree_plugin_through_the_public_api(monkeypatch):
    """The process-wide registry used by granframe.restitution_law sees it too."""
    monkeypatch.syspath_prepend(str(FAKE_SITE))
    code = ("import granframe, numpy; "
            "law = granframe.restitution_law('exponential_decay', minimum=0.5); "
            "print(law(numpy.array([0.0]))[0], granframe.collision_kernel('forward_peaked').exponent)")
    out = subprocess.run([sys.executable, "-c", code], env=_env_with_fake_site(),
                         capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["1.0", "0.0"]


def test_plugin_can_be_disabled_by_environment(monkeypatch, fresh_registries):
    monkeypatch.syspath_prepend(str(FAKE_SITE))
    monkeypatch.setenv("GRANFRAME_DISABLE_PLUGINS", "example, other")
    registries = fresh_registries()
    assert "exponential_decay" not in registries.names("restitution_laws")
    with pytest.raises(UnknownNameError, match="'exponential_decay' is not registered; known: "
                                               "constant, tanh, threshold, toscani, viscoelastic"):
        registries.get("restitution_laws", "exponential_decay")


def test_duplicate_name_names_both_sources(make_distribution, fresh_registries):
    make_distribution("granframe-clash", "granframe_clash", """
        import granframe
        from granframe.model.restitution import Constant

        @granframe.hookimpl
        def granframe_register_restitution_laws(registry):
            registry.add("constant", Constant)
    """)
    with pytest.raises(PluginError, match=r"'constant' is registered twice: by plugin "
                                          r"'builtin' of granframe .* and by plugin "
                                          r"'granframe_clash' of granframe-clash 0.1"):
        fresh_registries()


def test_misspelled_hook_is_caught(make_distribution):
    make_distribution("granframe-typo", "granframe_typo", """
        import granframe

        @granframe.hookimpl
        def granframe_register_restitution_law(registry):
            pass
    """)
    with pytest.raises(PluginError, match="granframe_register_restitution_law.*misspelled"):
        get_plugin_manager()


def test_broken_plugin_is_reported_with_its_origin(make_distribution):
    make_distribution("granframe-broken", "granframe_broken", "raise RuntimeError('boom')\n")
    with pytest.raises(PluginError, match="granframe_broken.*boom.*GRANFRAME_DISABLE_PLUGINS"):
        get_plugin_manager()


def test_invalid_registered_name(make_distribution):
    make_distribution("granframe-badname", "granframe_badname", """
        import granframe
        from granframe.model.restitution import Constant

        @granframe.hookimpl
        def granframe_register_restitution_laws(registry):
            registry.add("Bad-Name", Constant)
    """)
    with pytest.raises(PluginError, match="'Bad-Name' is invalid; names are snake_case"):
        Registries(*get_plugin_manager())


def test_unknown_family_and_name_types(fresh_registries):
    registries = fresh_registries()
    with pytest.raises(UnknownNameError, match="known families: collision_kernels"):
        registries.names("restitution")
    with pytest.raises(TypeError, match="name = 3 is invalid; must be a string"):
        registries.get("quadratures", 3)


def _env_with_fake_site():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(FAKE_SITE), env.get("PYTHONPATH")]))
    return env


def test_cli_plugins_json_is_stable_and_lists_sources():
    out = subprocess.run([sys.executable, "-m", "granframe.tools.cli", "plugins", "--json"],
                         env=_env_with_fake_site(), capture_output=True, text=True, check=True)
    doc = json.loads(out.stdout)
    assert doc["schema"] == "granframe.plugins/1"
    assert doc["granframe_version"] == granframe.__version__
    assert list(doc["families"]) == list(FAMILIES)
    names = {f: {e["name"] for e in entries} for f, entries in doc["families"].items()}
    for family, expected in EXPECTED_BUILTINS.items():
        assert expected <= names[family]
    assert len(names["quadratures"]) >= 4
    laws = {e["name"]: e for e in doc["families"]["restitution_laws"]}
    assert laws["exponential_decay"]["source"] == {
        "plugin": "example", "distribution": "granframe-example-plugin", "version": "1.2.0"}
    assert laws["toscani"]["source"]["plugin"] == "builtin"
    for entries in doc["families"].values():
        for e in entries:
            assert set(e) == {"name", "description", "source"} and e["description"]
            assert set(e["source"]) == {"plugin", "distribution", "version"}


def test_cli_plugins_text():
    out = subprocess.run([sys.executable, "-m", "granframe.tools.cli", "plugins"],
                         capture_output=True, text=True, check=True)
    assert "restitution_laws (5)" in out.stdout
    assert "viscoelastic" in out.stdout and "plugin 'builtin' of granframe" in out.stdout


def test_cli_reports_a_broken_plugin_without_traceback(make_distribution):
    site = make_distribution("granframe-broken", "granframe_broken", "import nonexisting_mod\n")
    env = dict(os.environ, PYTHONPATH=str(site))
    out = subprocess.run([sys.executable, "-m", "granframe.tools.cli", "plugins"], env=env,
                         capture_output=True, text=True)
    assert out.returncode == 2
    assert "granframe: error: cannot load plugin 'granframe_broken'" in out.stderr
    assert "Traceback" not in out.stderr


def test_core_imports_neither_pyfftw_nor_cupy():
    code = ("import sys, granframe; granframe.default_registries(); "
            "print(sorted(m for m in ('pyfftw', 'cupy') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_cli_bench_runs_and_reports_the_floor():
    out = subprocess.run([sys.executable, "-m", "granframe.tools.cli", "bench", "--json",
                          "--config", "2:16:8:8", "--repeats", "2", "--backend", "numpy"],
                         capture_output=True, text=True, check=True)
    record = json.loads(out.stdout)["records"][0]
    assert record["transform_pairs"] == 8 * 4
    assert record["evaluation_s"] > 0 and record["floor_s"] > 0
    assert record["time_over_floor"] == record["evaluation_s"] / record["floor_s"]
    # the floor transforms in the operator's own batches
    assert record["floor_s"] == record["fft_batch_s"] * 8 * 4 / record["batch"]
    single = subprocess.run([sys.executable, "-m", "granframe.tools.cli", "bench", "--precision",
                             "float32", "--config", "2:16:8:8", "--repeats", "2", "--backend",
                             "numpy"], capture_output=True, text=True, check=True)
    assert "float32" in single.stdout.splitlines()[0] and "| float32 |" in single.stdout
    bad = subprocess.run([sys.executable, "-m", "granframe.tools.cli", "bench", "--config", "4:16"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "parameter 'config' = '4:16'" in bad.stderr


def test_operators_and_backends_are_plugins():
    registries = granframe.default_registries()
    for name in ("fast_spectral", "direct_spectral"):
        assert registries.get("collision_operators", name).source.plugin == "spectral"
    assert registries.get("array_backends", "pyfftw").source.plugin == "fftw"
