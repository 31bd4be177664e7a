"""Plugin discovery: entry points, built-ins through the same hooks, errors, CLI."""

import json
import os
import pathlib
import re
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


# -- the kernel contract of docs/plugins.md, and parameters by name --------------------------

DOCS = pathlib.Path(__file__).parent.parent / "docs" / "plugins.md"


def _section(title: str) -> str:
    """The text of the section ``## title`` of docs/plugins.md."""
    text = DOCS.read_text()
    start = text.index(f"## {title}\n")
    end = text.find("\n## ", start + 1)
    return text[start:] if end < 0 else text[start:end]


def _python_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, re.S)


def test_the_documented_kernel_example_runs():
    """Every Python block of "Writing a collision kernel", executed in order: the kernel and
    its hook, an operator and the step limits on it, and the conformance class it shows."""
    blocks = _python_blocks(_section("Writing a collision kernel"))
    assert len(blocks) == 2
    namespace = {"__name__": "docs_plugins_example"}
    for block in blocks:
        exec(compile(block, str(DOCS), "exec"), namespace)
    assert namespace["q"].shape == namespace["grid"].shape
    namespace["TestSoftenedHardSpheres"]().test_collision_kernel()
    # the documented class is the example plugin's, verbatim
    documented = re.search(r"@attrs\.frozen\nclass SoftenedHardSpheres.*?\n\n\n", blocks[0],
                           re.S).group(0)
    assert documented in (FAKE_SITE / "granframe_example_plugin.py").read_text()


def test_the_documented_restitution_law_is_the_example_plugins():
    [law] = [b for b in _python_blocks(_section("Step by step: a new restitution law"))
             if "class ExponentialDecay" in b]
    documented = re.search(r"@attrs\.frozen\nclass ExponentialDecay.*?\n\n\n", law,
                           re.S).group(0)
    assert documented in (FAKE_SITE / "granframe_example_plugin.py").read_text()


def test_a_misspelled_parameter_names_the_closest(monkeypatch, fresh_registries):
    with pytest.raises(TypeError) as caught:
        granframe.restitution_law("toscani", strenght=1.0, exponent=0.5)
    assert str(caught.value) == (
        "restitution_laws 'toscani': unknown parameter 'strenght'; did you mean 'strength'? "
        "Accepted parameters: strength, exponent")
    with pytest.raises(TypeError) as caught:
        granframe.restitution_law("viscoelastic", a=0.2)     # nothing close: no suggestion
    assert str(caught.value) == (
        "restitution_laws 'viscoelastic': unknown parameter 'a'; accepted parameters: "
        "strength")
    with pytest.raises(TypeError) as caught:
        granframe.restitution_law("toscani", strength=1.0)
    assert str(caught.value) == ("restitution_laws 'toscani': missing required parameter "
                                 "'exponent'; accepted parameters: strength, exponent")
    monkeypatch.syspath_prepend(str(FAKE_SITE))
    with pytest.raises(TypeError, match=r"^collision_kernels 'softened_hard_spheres': unknown "
                                        r"parameter 'speed_scal'; did you mean 'speed_scale'\? "):
        fresh_registries().create("collision_kernels", "softened_hard_spheres", speed_scal=2.0)


def test_a_misspelled_parameter_of_a_description_names_the_closest():
    from granframe.run.description import RunDescription
    from test_runner import heated

    with pytest.raises(TypeError, match=r"^collision_kernels 'vhs': unknown parameter "
                                        r"'exponnent'; did you mean 'exponent'\? "):
        heated(kernel={"name": "vhs", "exponnent": 0.5})
    text = heated().to_toml().replace('name = "maxwellian"\n',
                                      'name = "maxwellian"\ntemperatur = 2.0\n')
    with pytest.raises(TypeError, match=r"^initial_conditions 'maxwellian': unknown parameter "
                                        r"'temperatur'; did you mean 'temperature'\? "):
        RunDescription.from_toml(text)
    with pytest.raises(TypeError) as caught:
        heated(operator={"name": "fast_spectral", "radial_point": 8})
    assert str(caught.value).startswith(
        "RunDescription: parameter 'operator' = {'radial_point': 8} is invalid; has an unknown "
        "option: collision_operators 'fast_spectral': unknown parameter 'radial_point'; did "
        "you mean 'radial_points'? ")


def test_an_unknown_name_or_family_names_the_closest(fresh_registries):
    registries = fresh_registries()
    with pytest.raises(UnknownNameError) as caught:
        registries.get("restitution_laws", "toscanni")
    assert str(caught.value) == ("restitution_laws: name 'toscanni' is not registered; known: "
                                 "constant, tanh, threshold, toscani, viscoelastic; did you "
                                 "mean 'toscani'?")
    with pytest.raises(UnknownNameError, match=r"known families: .*; did you mean "
                                               r"'restitution_laws'\?$"):
        registries.names("restitution_law")


def test_entries_describe_their_parameters(fresh_registries):
    from granframe.registry import REQUIRED

    registries = fresh_registries()
    toscani = registries.get("restitution_laws", "toscani")
    assert [(p.name, p.type, p.required) for p in toscani.parameters()] == [
        ("strength", "float", True), ("exponent", "float", True)]
    assert toscani.summary() == ("Toscani's law e(r) = 1 / (1 + c r^gamma) [Toscani 2000], "
                                 "c >= 0, gamma real.")
    fast = registries.get("collision_operators", "fast_spectral").parameters()
    # after grid, kernel, restitution and backend; types from the numpydoc Parameters section
    assert fast[0].name == "radial_points" and fast[0].type == "int" and fast[0].default is None
    assert {p.name for p in fast}.isdisjoint({"grid", "kernel", "restitution", "backend"})
    maxwellian = {p.name: p for p in registries.get("initial_conditions", "maxwellian")
                  .parameters()}
    assert maxwellian["temperature"].default == 1.0 and maxwellian["velocity"].type == "tuple | None"
    assert maxwellian["temperature"].to_dict() == {"name": "temperature", "type": "float",
                                                   "required": False, "default": 1.0}
    assert repr(REQUIRED) == "REQUIRED"
    assert registries.get("time_integrators", "rk4").parameters() == []
    assert [e.family for e in registries.find("maxwell")] == ["collision_kernels"]
