"""The command line over generated descriptions and arguments, as a careless or hostile user
would type them: every command ends with exit status 0, 2 or 3, within a time and memory
bound, with no traceback, and touches no file outside its --out."""

import contextlib
import io
import math
import pathlib
import resource
import shutil
import signal
import tempfile

import pytest
import tomli_w
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from conftest import mutated
from granframe.tools.cli import main
from granframe.run.runner import Simulation
from test_fault_injection import NEW, OLD

#: seconds one command may take (a generated run is a few steps on a 16^2 grid)
LIMIT = 60
#: what a run may allocate (granframe.memory's budget), and the peak the test allows
BUDGET = 512 * 2 ** 20
PEAK_GROWTH = 2 * 2 ** 30

HOSTILE = [0, -1, 1, 2, 3, 7, 16, 0.05, 0.1, 0.3, -0.05, 1e30, 1e308, 1e-320, 1e-12,
           math.nan, math.inf, -math.inf, 10 ** 20, 65536, "x", "", True, [], [1, 2], {},
           {"name": "x"}]
KEYS = {
    "final_time": [0.1, 0.2, 0.3, 0.07, 1e30, 1e308, 0.0, -1.0, math.nan],
    "time_step": [0.05, 0.1, 0.025, 1e-320, 1e-12, 0.0, -0.05, 0.3, math.inf],
    "heat_bath": [0.0, 0.1, 1e30, -1.0],
    "knudsen": [1.0, 0.5, 1e-320, 0.0, -2.0],
    "tolerance": [1e-6, 1e-320, 0.0, -1.0, 1e30],
    "integrator": ["rk4", "dopri54", "forward_euler", "if_rk4", "penalised_euler", "foo", 3],
    "grid.n_modes": [4, 6, 8, 15, 16, 24, 65536, 10 ** 9, -16, 16.5, "16"],
    "grid.dimension": [1, 2, 3, 4, 0],
    "grid.support_radius": [10.0, 5.0, 0.0, -10.0, 1e308, 1e-320],
    "operator.name": ["fast_spectral", "direct_spectral", "nope"],
    "operator.radial_points": [4, 8, 0, -8, 10 ** 9, 8.5],
    "operator.sphere.n_points": [4, 8, 0, 10 ** 9, -4],
    "operator.sphere.name": ["circle_trapezoid", "lebedev", "gauss_legendre", "x"],
    "kernel": ["maxwell", "hard_spheres", "vhs", "x", {"name": "vhs", "exponent": 7.0}],
    "restitution.value": [0.5, 1.0, 0.0, 1.5, -0.5],
    "restitution.name": ["constant", "toscani", "viscoelastic", "tanh", "x"],
    "initial.temperature": [8.0, 1.0, 0.0, -8.0, 1e308, 1e-320],
    "initial.name": ["maxwellian", "box", "bkw", "callable", "x"],
    "backend.name": ["numpy", "pyfftw", "cupy", "x"],
    "backend.threads": [1, 2, 0, -1, 100000, 1.5],
    "output.snapshot_interval": [0.1, 0.05, 0.0, -0.1, 1e-320, 0.03],
    "health.mass_tolerance": [1e-6, 0.0, -1.0, 1e-300],
    "health.positivity_tolerance": [0.01, 0.0, 2.0],
    "title": ["t", "", "../x"],
    "unknown": [1],
}


changes = st.lists(st.one_of(
    st.sampled_from(list(KEYS)).flatmap(lambda k: st.tuples(
        st.just(k), st.one_of(st.sampled_from(KEYS[k]), st.sampled_from(HOSTILE),
                              st.none()))),
    st.tuples(st.sampled_from(list(KEYS)), st.floats(allow_nan=True, allow_infinity=True))),
    max_size=3)
source = st.one_of(
    st.just(("toml", [])), changes.map(lambda c: ("toml", c)), changes.map(lambda c: ("toml", c)),
    st.text(max_size=60).map(lambda text: ("text", text)),
    st.sampled_from(["missing.toml", "notes.txt", "old.zarr", "study.txt"]).map(
        lambda path: ("path", path)))
out = st.sampled_from(["new.zarr", "new.zarr", "new.zarr", "old.zarr", "empty", ".", "..", "notes.txt", "desc.toml",
                       "sub/deeper.zarr", "../escape.zarr", "figures", "user"])
flags = st.one_of(st.just([]), st.lists(st.sampled_from(
    ["--resume", "--overwrite", "--rollback", "--quick", "--only", "a", "--progress",
     "--no-progress"]), max_size=3))
run_command = st.tuples(st.just("run"), source, out, flags)
read_command = st.tuples(st.sampled_from(["info", "check"]),
                         st.sampled_from(["old.zarr", "new.zarr", "notes.txt", "user",
                                          "empty", ".", "damaged.zarr"]))
plot_command = st.tuples(st.just("plot"), st.sampled_from(["notes.txt", "user", "missing",
                                                           "damaged.zarr", "empty"]), out)
bench_command = st.tuples(st.just("bench"), st.lists(st.sampled_from(
    ["--config", "2:15", "2:8:2:4", "3:8", "9:9", "x", "--threads", "0", "-3", "1",
     "--repeats", "0", "-1", "--backend", "foo", "numpy", "--precision", "float16",
     "--json"]), min_size=1, max_size=6))
sweep_command = st.tuples(st.just("sweep"), st.sampled_from(["sweep.toml", "missing.toml",
                                                             "notes.txt", "desc.toml"]),
                          st.sampled_from(["old.zarr", "notes.txt", "new.zarr", "user"]),
                          st.sampled_from([["--workers", "0"], ["--workers", "-1"],
                                           ["--workers", "x"], []]))
advise_command = st.tuples(st.just("advise"), st.sampled_from(["missing.toml", "notes.txt",
                                                               "desc.toml", "garbage.toml"]))
#: a run 7 times in 12, each other command once
command = st.integers(0, 11).flatmap(
    lambda i: [read_command, plot_command, bench_command, sweep_command, advise_command][i - 7]
    if i >= 7 else run_command)


def argv(example, workdir: pathlib.Path) -> tuple[list[str], str | None]:
    """The command line of an example (desc.toml written for it) and its --out."""
    name, *rest = example
    if name == "run":
        (kind, value), target, extra = rest
        if kind == "toml":
            table = mutated(NEW.to_dict(), value)
            try:
                (workdir / "desc.toml").write_text(tomli_w.dumps(table))
            except (TypeError, ValueError):       # not writable as TOML: the raw text then
                (workdir / "desc.toml").write_text(repr(table))
            path = "desc.toml"
        elif kind == "text":
            (workdir / "desc.toml").write_text(value)
            path = "desc.toml"
        else:
            path = value
        return ["run", path, "--out", target, *extra], target
    if name in ("info", "check"):
        return [name, rest[0]], None
    if name == "plot":
        return ["plot", rest[0], "--out", rest[1]], rest[1]
    if name == "bench":     # a small configuration first: the default table takes minutes
        return ["bench", "--config", "2:8", *rest[0]], None
    if name == "sweep":
        toml, target, extra = rest
        return ["sweep", toml, "--out", target, *extra], target
    return ["advise", rest[0]], None


def files(root: pathlib.Path) -> dict:
    """Every file and directory under ``root``: path -> (size, mtime) (None for a directory)."""
    found = {}
    for path in root.rglob("*"):
        stat = path.lstat()
        found[path] = None if path.is_dir() else (stat.st_size, stat.st_mtime_ns)
    return found


def allowed(path: pathlib.Path, target: pathlib.Path | None) -> bool:
    """A change at ``path`` is allowed inside --out, and for the directories above it."""
    if target is None:
        return False
    return path == target or target in path.parents or path in target.parents


class Expired(BaseException):
    """A command ran past LIMIT. Not an Exception: the command line's own handlers (which
    turn an OSError such as TimeoutError into a refusal, exit 2) must not swallow it."""


@contextlib.contextmanager
def time_limit(seconds):
    def expire(signum, frame):
        raise Expired(f"the command took more than {seconds} s")
    previous = signal.signal(signal.SIGALRM, expire)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


@given(example=command)
@settings(max_examples=300, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
def test_the_command_line_never_fails_uncleanly(example, template, monkeypatch):
    monkeypatch.setenv("GRANFRAME_MEMORY_BUDGET", str(BUDGET))
    with tempfile.TemporaryDirectory() as sandbox:
        sandbox = pathlib.Path(sandbox).resolve()
        shutil.copytree(template, sandbox / "work")
        workdir = sandbox / "work"
        arguments, target = argv(example, workdir)
        before = files(sandbox)
        stderr, stdout = io.StringIO(), io.StringIO()
        monkeypatch.chdir(workdir)
        with time_limit(LIMIT), contextlib.redirect_stderr(stderr), \
                contextlib.redirect_stdout(stdout):
            try:
                code = main(arguments)
            except SystemExit as exc:     # argparse: a usage error, status 2
                code = exc.code
        after = files(sandbox)
        monkeypatch.chdir(sandbox)
        event(f"{arguments[0]}: exit {code}")
        assert code in (0, 2, 3), (arguments, code, stderr.getvalue())
        assert "Traceback" not in stderr.getvalue(), (arguments, stderr.getvalue())
        if code == 2:
            assert "error: " in stderr.getvalue(), (arguments, stderr.getvalue())
        resolved = None if target is None else (workdir / target).resolve()
        changed = [p for p in set(before) | set(after) if before.get(p, "gone") != after.get(
            p, "gone") and not allowed(p, resolved)]
        assert not changed, (arguments, sorted(map(str, changed)))


def test_the_generated_commands_stay_within_their_memory_bound(template):
    """Run after the examples (same module, file order): the process's peak resident memory
    grew by less than PEAK_GROWTH over all 300 commands."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    assert peak < BASELINE["rss"] + PEAK_GROWTH, (peak, BASELINE)


#: peak resident memory before the first generated command
BASELINE = {}


def _template(root: pathlib.Path) -> pathlib.Path:
    """A work directory: user files, a finished run store, a damaged one, an empty dir,
    a sweep description and a study-like text file."""
    work = root / "template"
    work.mkdir()
    (work / "notes.txt").write_text("my notes\n")
    (work / "user").mkdir()
    (work / "user" / "results.txt").write_text("precious\n")
    (work / "empty").mkdir()
    (work / "study.txt").write_text("not a study\n")
    (work / "garbage.toml").write_text("[[[\n")
    Simulation(OLD).run(work / "old.zarr", progress=False)
    shutil.copytree(work / "old.zarr", work / "damaged.zarr")
    (work / "damaged.zarr" / "f" / "c" / "1" / "0" / "0").unlink()
    (work / "sweep.toml").write_text(tomli_w.dumps(
        {"base": NEW.to_dict(), "product": {"restitution.value": [0.5]}}))
    return work


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    work = _template(tmp_path_factory.mktemp("cli"))
    BASELINE.setdefault("rss", resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)
    return work
