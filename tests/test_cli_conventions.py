"""Conventions of the command line: --version, help with examples, did-you-mean for mistyped
commands, options and registered names, ``plugins NAME``, ``info --json``, ``run --set``
and the report of a study after ``--only``."""

import json
import os
import shlex
import subprocess
import sys
import textwrap

import pytest

import granframe
from granframe.run.runner import Simulation
from granframe.run.storage import RunStore, describe
from granframe.tools.cli import COMMAND_HELP, build_parser, main
from granframe.tools.cli_inputs import with_settings as _with_settings

from conftest import FAKE_SITE
from test_fault_injection import NEW


def fails(capsys, argv) -> str:
    """The last line of what ``granframe argv`` wrote to stderr, which must exit with 2."""
    try:
        code = main(argv)
    except SystemExit as exc:     # argparse's usage errors
        code = exc.code
    assert code == 2
    return capsys.readouterr().err.rstrip("\n").splitlines()[-1]


# -- --version and --help --------------------------------------------------------------

def test_version(capsys):
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out == f"granframe {granframe.__version__}\n"


def _commands():
    parser = build_parser()
    [commands] = [a for a in parser._actions if a.dest == "command"]
    return parser, commands.choices


def test_every_command_help_has_a_description_and_examples_that_parse(capsys):
    parser, commands = _commands()
    assert set(commands) == set(COMMAND_HELP)
    for name, command in commands.items():
        with pytest.raises(SystemExit):
            main([name, "--help"])
        text = capsys.readouterr().out
        description, examples = COMMAND_HELP[name]
        assert description in text                     # kept as written (raw formatting)
        assert f"\nexamples:\n{examples}\n" in text
        lines = examples.splitlines()
        assert lines and all(line.split()[:2] == ["granframe", name] for line in lines)
        for line in lines:               # every example is a valid command line
            for example in line.split("&&"):
                words = shlex.split(example)
                assert words[0] == "granframe"
                parser.parse_args(words[1:])


# -- did you mean ------------------------------------------------------------------------

def test_a_mistyped_command_gets_the_closest(capsys):
    assert fails(capsys, ["rn", "x"]).endswith("invalid choice: 'rn' (choose from 'plugins', "
                                               "'bench', 'run', 'plot', 'info', 'check', "
                                               "'sweep', 'refine', 'advise', 'limits'); did you "
                                               "mean 'run'?")
    assert fails(capsys, ["bench", "--precision", "float23"]) == (
        "granframe bench: error: argument --precision: invalid choice: 'float23' (choose from "
        "'float64', 'float32'); did you mean 'float32'?")


def test_a_mistyped_option_gets_the_closest(capsys):
    assert fails(capsys, ["run", "d.toml", "--out", "s.zarr", "--ovewrite"]) == (
        "granframe run: error: unrecognized arguments: --ovewrite; did you mean "
        "'--overwrite'?")
    # before a missing required argument; each of several gets its own
    assert fails(capsys, ["run", "d.toml", "--ovewrite", "--qiuck"]) == (
        "granframe run: error: unrecognized arguments: --ovewrite --qiuck; did you mean "
        "'--overwrite' for '--ovewrite', '--quick' for '--qiuck'?")
    assert fails(capsys, ["--verison"]) == (
        "granframe: error: unrecognized arguments: --verison; did you mean '--version'?")
    assert fails(capsys, ["info", "a.zarr", "b.zarr"]) == (
        "granframe info: error: unrecognized arguments: b.zarr")
    assert fails(capsys, ["bench", "--threads", "-3", "--jsn"]) == (
        "granframe bench: error: unrecognized arguments: --jsn; did you mean '--json'?")
    # what argparse accepted before still parses: abbreviations, negative numbers
    args = build_parser().parse_args(["run", "d.toml", "--out", "s.zarr", "--overw"])
    assert args.overwrite


def test_a_mistyped_registered_name_gets_the_closest(capsys, tmp_path):
    assert fails(capsys, ["bench", "--backend", "nmpy"]) == (
        "granframe: error: bench: parameter 'backend' = 'nmpy' is invalid; must be a "
        "registered array backend: cupy, numpy, pyfftw; did you mean 'numpy'?")
    description = tmp_path / "d.toml"
    description.write_text(NEW.to_toml().replace('name = "maxwell"', 'name = "maxwel"'))
    assert fails(capsys, ["run", str(description), "--out", str(tmp_path / "s.zarr")]) == (
        "granframe: error: collision_kernels: name 'maxwel' is not registered; known: "
        "hard_spheres, maxwell, vhs; did you mean 'maxwell'?")
    assert fails(capsys, ["plugins", "toscan"]) == (
        "granframe: error: plugins: name 'toscan' is not registered in any family; did you "
        "mean 'toscani'? (granframe plugins lists them)")
    assert fails(capsys, ["plugins", "restitution_laws", "toscanni"]).endswith(
        "known: constant, tanh, threshold, toscani, viscoelastic; did you mean 'toscani'?")
    assert fails(capsys, ["plugins", "restitution_law", "toscani"]).endswith(
        "; did you mean 'restitution_laws'?")


# -- plugins NAME ------------------------------------------------------------------------

def test_plugins_name_shows_one_implementation(capsys):
    assert main(["plugins", "toscani"]) == 0
    assert capsys.readouterr().out == textwrap.dedent(f"""\
        toscani (restitution_laws)
          description  Toscani's law e(r) = 1 / (1 + c r^gamma) [Toscani 2000], c >= 0, gamma real.
          source       plugin 'builtin' of granframe {granframe.__version__}
          factory      granframe.model.restitution.Toscani
        parameters:
          strength  float  required
          exponent  float  required
        """)
    assert main(["plugins", "collision_operators", "fast_spectral"]) == 0
    text = capsys.readouterr().out
    assert "  summary      Fast spectral collision operator, O(M N_rho N^d log N) per " \
           "evaluation.\n" in text
    assert "parameters (after grid, kernel, restitution, backend):\n" \
           "  radial_points  int " in text
    assert "  precision      {\"float64\", \"float32\"}  default 'float64'\n" in text
    assert main(["plugins", "rk4"]) == 0
    assert capsys.readouterr().out.endswith("parameters: none\n")


def test_plugins_name_json(capsys):
    assert main(["plugins", "maxwellian", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["schema"] == "granframe.plugin/1" and doc["family"] == "initial_conditions"
    assert doc["name"] == "maxwellian" and doc["source"]["plugin"] == "builtin"
    assert doc["factory"] == "granframe.model.initial.Maxwellian"
    assert doc["parameters"] == [
        {"name": "density", "type": "float", "required": False, "default": 1.0},
        {"name": "velocity", "type": "tuple | None", "required": False, "default": None},
        {"name": "temperature", "type": "float", "required": False, "default": 1.0}]
    assert main(["plugins", "quadratures", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert list(doc["families"]) == ["quadratures"]


def test_plugins_name_in_several_families_needs_the_family(capsys, make_distribution,
                                                           fresh_registries, monkeypatch):
    make_distribution("granframe-twice", "granframe_twice", """
        import granframe
        from granframe.model.restitution import Constant

        @granframe.hookimpl
        def granframe_register_initial_conditions(registry):
            registry.add("toscani", Constant, examples=[{"value": 0.5}])
    """)
    registries = fresh_registries()
    monkeypatch.setattr("granframe.registry.default_registries", lambda: registries)
    assert fails(capsys, ["plugins", "toscani"]) == (
        "granframe: error: plugins: name 'toscani' is registered in several families "
        "(restitution_laws, initial_conditions); give FAMILY NAME, e.g. granframe plugins "
        "restitution_laws toscani")
    assert main(["plugins", "initial_conditions", "toscani"]) == 0
    assert "plugin 'granframe_twice' of granframe-twice 0.1" in capsys.readouterr().out
    assert fails(capsys, ["plugins", "a", "b", "c"]) == (
        "granframe: error: plugins: parameter 'names' = 'a b c' is invalid; give NAME or "
        "FAMILY NAME, e.g. granframe plugins collision_kernels vhs")


def test_plugins_name_of_an_installed_plugin():
    out = subprocess.run([sys.executable, "-m", "granframe.tools.cli", "plugins",
                          "softened_hard_spheres"],
                         env=dict(os.environ, PYTHONPATH=str(FAKE_SITE)),
                         capture_output=True, text=True, check=True)
    assert out.stdout.endswith("parameters:\n  exponent     float  default 1.0\n"
                               "  speed_scale  float  default 1.0\n")
    assert "  source       plugin 'example' of granframe-example-plugin 1.2.0\n" in out.stdout


# -- info --json -------------------------------------------------------------------------

def test_info_json_has_what_info_says(tmp_path, capsys, monkeypatch):
    store = tmp_path / "s.zarr"
    Simulation(NEW).run(store, progress=False)
    assert main(["info", str(store), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["schema"] == "granframe.info/1" and doc["store"] == str(store)
    assert doc["progress"]["status"] == "finished"
    assert doc["metadata"]["description"] == NEW.to_dict()
    assert doc["snapshots"] == {"count": 4, "shape": [16, 16], "first_time": 0.0,
                                "last_time": pytest.approx(0.3, rel=1e-15)}
    moments = doc["moments"]
    assert moments["records"] == 7 and moments["steps"] == 6
    text = describe(store)
    assert f"{moments['temperature']['first']:.10g} -> " \
           f"{moments['temperature']['last']:.10g}" in text
    for key, value in doc["metadata"]["provenance"].items():
        assert f"{key}" in text and f"{value}" in text
    monkeypatch.setattr("granframe.run.storage.store_kind", lambda path: "sweep")
    assert fails(capsys, ["info", str(store), "--json"]) == (
        f"granframe: error: info: parameter 'store' = '{store}' is invalid; --json describes "
        f"run stores, and it is a sweep store (granframe info {store} describes it)")


# -- run --set ---------------------------------------------------------------------------

def test_set_overrides_keys_of_the_description():
    changed = _with_settings(NEW, ["grid.n_modes=8", "final_time=0.1", "kernel.name=vhs",
                                   "kernel.exponent=0.5", 'title="with --set"',
                                   "operator.sphere.n_points=4",
                                   "health.step_limit=false"])
    assert changed.grid.n_modes == 8 and changed.final_time == 0.1
    assert changed.kernel.name == "vhs" and changed.kernel.params == {"exponent": 0.5}
    assert changed.title == "with --set" and not changed.health.step_limit
    assert changed.operator.params["sphere"] == {"name": "circle_trapezoid", "n_points": 4}
    # a key the table leaves out (None) but the description has
    adaptive = _with_settings(NEW, ["integrator.name=dopri54", "tolerance=1e-6"])
    assert adaptive.integrator.name == "dopri54" and adaptive.tolerance == 1e-6
    # the half width and truncation radius follow the support radius
    wider = _with_settings(NEW, ["grid.support_radius=12"])
    assert wider.grid == granframe.VelocityGrid(2, 16, 12.0)
    assert _with_settings(NEW, ["operator.sphere={name = 'circle_trapezoid', n_points = 6}"]
                          ).operator.params["sphere"]["n_points"] == 6


def test_set_refuses_a_key_the_description_cannot_have():
    with pytest.raises(ValueError) as caught:
        _with_settings(NEW, ["grid.n_mode=64"])
    assert str(caught.value) == ("run: parameter 'set' = 'grid.n_mode=64' is invalid; "
                                 "'grid.n_mode' is not a key of the description; did you "
                                 "mean 'grid.n_modes'?")
    with pytest.raises(ValueError, match=r"'kernel.exponent' is not a key of the description; "
                                         r"did you mean 'kernel.energy_exponent'\?$"):
        _with_settings(NEW, ["kernel.exponent=1"])          # maxwell has no exponent
    with pytest.raises(ValueError, match=r"^run: parameter 'set' = 'grid.n_modes' is invalid; "
                                         r"must be KEY=VALUE, e.g. --set grid.n_modes=64$"):
        _with_settings(NEW, ["grid.n_modes"])
    with pytest.raises(ValueError, match=r"'n_modes' = 15 is invalid"):
        _with_settings(NEW, ["grid.n_modes=15"])           # the description's own checks


def test_run_with_set(tmp_path, capsys):
    description = tmp_path / "d.toml"
    description.write_text(NEW.to_toml())
    store = tmp_path / "s.zarr"
    assert main(["run", str(description), "--out", str(store), "--set", "final_time=0.1",
                 "--set", "restitution.value=0.8", "--no-progress"]) == 0
    stored = RunStore.open(store).metadata["description"]
    assert stored["final_time"] == 0.1 and stored["restitution"]["value"] == 0.8
    assert fails(capsys, ["run", str(description), "--out", str(store), "--set",
                          "heat_bth=0.2"]) == (
        "granframe: error: run: parameter 'set' = 'heat_bth=0.2' is invalid; 'heat_bth' is "
        "not a key of the description; did you mean 'heat_bath'?")


# -- a study's report after --only -------------------------------------------------------

STUDY = '''
import json
import pathlib

from granframe.run.description import RunDescription


def runs(quick=False):
    text = pathlib.Path(__file__).with_name("d.toml").read_text()
    return {"a": RunDescription.from_toml(text), "b": RunDescription.from_toml(text)}


def report(stores, out):
    out.mkdir(parents=True, exist_ok=True)
    {body}
'''


def _study(tmp_path, body):
    (tmp_path / "d.toml").write_text(NEW.replace(final_time=0.1).to_toml())
    study = tmp_path / "study.py"
    study.write_text(STUDY.replace("{body}", body))
    return study


def test_only_still_writes_the_report(tmp_path, capsys):
    study = _study(tmp_path, 'return {"runs": sorted(stores)}')
    out = tmp_path / "out"
    assert main(["run", str(study), "--out", str(out), "--only", "b", "--no-progress"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == (
        f"report: {out / 'report'} (summary.json and figures), from 1 of 2 runs: b")
    assert json.loads((out / "report" / "summary.json").read_text()) == {"runs": ["b"]}
    # the next subset: the report covers every run that has ended
    assert main(["run", str(study), "--out", str(out), "--only", "a", "--no-progress"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == (
        f"report: {out / 'report'} (summary.json and figures)")
    assert json.loads((out / "report" / "summary.json").read_text()) == {"runs": ["a", "b"]}
    assert fails(capsys, ["run", str(study), "--out", str(out), "--only", "a,bb"]) == (
        "granframe: error: run: parameter 'only' = 'a,bb' is invalid; the study's runs are "
        "a, b; did you mean 'b'?")


def test_a_report_that_reads_a_run_not_made_waits_for_it(tmp_path, capsys):
    study = _study(tmp_path, 'return {"a": str(stores["a"]), "b": str(stores["b"])}')
    out = tmp_path / "out"
    assert main(["run", str(study), "--out", str(out), "--only", "b", "--no-progress"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == (
        "report: waiting for 1 of 2 runs (it reads 'a', which has not ended): run them with "
        "--only a, or run again with --resume")
    assert not (out / "report" / "summary.json").exists()
    broken = _study(tmp_path, 'return {"x": stores["x"]}')     # not a run: the report's bug
    message = fails(capsys, ["run", str(broken), "--out", str(out), "--resume", "--only", "b"])
    assert message.startswith(f"granframe: error: run: the report of study '{broken}' failed: "
                              "KeyError: 'x' (at ")
