"""Run a :class:`~granframe.run.description.RunDescription` into a store.

:class:`Simulation` builds every object once (operator precomputation
included) and checks f0 against the grid; :meth:`Simulation.run` steps to
``final_time``, computes the moments after every step, checks the health
limits, and commits a snapshot of f with the pending moment records on the
output schedule (see :mod:`granframe.run.storage` for why a stop at any moment
leaves a valid store). ``resume=True`` continues from the last committed
snapshot; the result equals that of an uninterrupted run to round-off.
"""

from __future__ import annotations

import importlib.util
import math
import re
import pathlib
import platform
import sys
import time
import traceback
from typing import Callable

import attrs
import numpy
import tqdm
import zarr

from granframe._version import __version__
from granframe.backends import available_cpus
from granframe.run.description import _FAMILIES, RunDescription
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.errors import NonFiniteError
from granframe.model.initial import check_fits, check_projection
from granframe.stepping.integrators import StepController, StepSizeError
from granframe.memory import check_run_memory
from granframe.stepping.stability import check_time_step
from granframe.registry import default_registries
from granframe.equations.rescaled import RescaledBoltzmann
from granframe.run.storage import SCALAR_MOMENTS, RunStore, StoreExistsError
from granframe.validators import reject

_RUN_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")


@attrs.frozen
class Study:
    """What ``granframe run`` runs: named descriptions (a single run is named ''), and a report.

    ``report(stores, out)``, when given, draws the study's figures from the stores
    (name -> path) of runs that finished or were stopped by a health check (their status
    says which) into the folder ``out`` and returns a JSON-ready summary.
    """

    runs: dict = attrs.field()
    report: Callable | None = None

    @runs.validator
    def _check_names(self, attribute, value):
        """Each run is written to OUT/<name>.zarr: a name is one plain path component."""
        if "" in value and len(value) > 1:
            reject("Study", "runs", list(value), "must name every run when there are several "
                   "(the unnamed run '' is a study's only run)")
        for name in value:
            if name != "" and not (isinstance(name, str) and _RUN_NAME.fullmatch(name)):
                reject("Study", "runs", name, "must be run names of letters, digits, '.', "
                       "'_' and '-' that start with a letter or digit (each is written to "
                       "OUT/<name>.zarr)")


def line_in(exc: BaseException, source) -> int | None:
    """The line of the file ``source`` where ``exc`` was raised (for a syntax error, its
    line), the innermost if there are several; None when it was not raised there."""
    if isinstance(exc, SyntaxError):
        return exc.lineno
    lines = [frame.lineno for frame in traceback.extract_tb(exc.__traceback__)
             if pathlib.Path(frame.filename).resolve() == pathlib.Path(source).resolve()]
    return lines[-1] if lines else None


def load_study(source, quick: bool = False) -> Study:
    """A TOML description, or a study module defining ``runs(quick)`` or ``description(quick)``.

    A module may also define ``report(stores, out)``.
    """
    path = pathlib.Path(source)
    if not path.is_file():
        raise ValueError(f"run: parameter 'source' = '{source}' is invalid; no such file")
    if path.suffix == ".toml":
        if quick:
            raise ValueError("run: --quick applies to study modules; a TOML description runs "
                             "as written")
        return Study({"": RunDescription.from_toml(path.read_text())})
    if path.suffix != ".py":
        raise ValueError(f"run: parameter 'source' = '{source}' is invalid; must be a .toml "
                         "description or a .py study module")
    def failure(exc, what):
        """ValueError: the study's own error, with its line in the study file."""
        message = exc.msg if isinstance(exc, SyntaxError) else str(exc)
        line = line_in(exc, path)
        return ValueError(f"run: study '{source}' {what}: {type(exc).__name__}: {message}"
                          + (f" (line {line})" if line else ""))

    spec = importlib.util.spec_from_file_location(f"granframe_study_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception as exc:   # the study's code: a syntax error, a missing import, ...
        raise failure(exc, "could not be loaded") from exc
    try:
        if callable(getattr(module, "runs", None)):
            runs = module.runs(quick=quick)
        elif callable(getattr(module, "description", None)):
            runs = {"": module.description(quick=quick)}
        else:
            raise ValueError(f"run: study '{source}' defines neither runs(quick) nor "
                             "description(quick)")
    except (ValueError, TypeError):   # granframe's own messages (an invalid description)
        raise
    except Exception as exc:
        raise failure(exc, "could not make its runs") from exc
    if not isinstance(runs, dict) or not runs or not all(
            isinstance(d, RunDescription) for d in runs.values()):
        raise TypeError(f"run: study '{source}' must give RunDescriptions (runs() returns a "
                        f"non-empty dict name -> RunDescription); got {runs!r}")
    return Study(runs, getattr(module, "report", None))


def load_description(source, quick: bool = False) -> RunDescription:
    """The one description of a TOML file or single-run study module."""
    study = load_study(source, quick)
    if list(study.runs) != [""]:
        raise ValueError(f"run: '{source}' defines several runs ({', '.join(study.runs)}); "
                         "use load_study")
    return study.runs[""]


def check_run_modes(resume: bool, overwrite: bool) -> None:
    """Refuse ``resume`` together with ``overwrite``."""
    if resume and overwrite:
        raise ValueError("run: --resume and --overwrite exclude each other: --resume "
                         "continues the store, --overwrite replaces it")


class HealthError(RuntimeError):
    """A run stopped by a health check; the message says which check, when and by how much."""


def _safe(function) -> float:
    try:
        return float(function())
    except (ZeroDivisionError, OverflowError, ValueError):
        return math.nan


def moments(grid, f, xp) -> dict:
    """Mass, momentum, temperature, energy, min f, negative-mass share, kurtosis, a2 of f."""
    absolute = float(xp.sum(xp.abs(f)))
    return {
        "mass": _safe(lambda: grid.mass(f, xp)),
        "momentum": grid.momentum(f, xp),
        "temperature": _safe(lambda: grid.temperature(f, xp)),
        "kinetic_energy": _safe(lambda: grid.kinetic_energy(f, xp)),
        "min_f": float(xp.min(f)),
        "negative_mass_fraction": _safe(lambda: float(xp.sum(xp.maximum(-f, 0.0))) / absolute),
        "kurtosis": _safe(lambda: grid.kurtosis(f, xp)),
        "sonine_a2": _safe(lambda: grid.sonine_a2(f, xp)),
    }


def health_problem(record: dict, mass0: float, health) -> str | None:
    """What is wrong with the state behind ``record``, or None (see :class:`Health`)."""
    values = [record["mass"], record["kinetic_energy"], record["min_f"]]
    if not all(math.isfinite(v) for v in values):
        return "f is not finite (NaN or Inf)"
    if record["mass"] <= 0.0:
        return f"the mass is not positive ({record['mass']:.6g})"
    drift = abs(record["mass"] / mass0 - 1.0)
    if drift > health.mass_tolerance:
        return (f"mass drift |mass/mass(0) - 1| = {drift:.3g} exceeds mass_tolerance = "
                f"{health.mass_tolerance:g}")
    if record["negative_mass_fraction"] > health.positivity_tolerance:
        return (f"loss of positivity: negative mass share {record['negative_mass_fraction']:.3g} "
                f"exceeds positivity_tolerance = {health.positivity_tolerance:g} "
                f"(min f = {record['min_f']:.3g})")
    return None


@attrs.frozen
class RunResult:
    """What a run did: its store, final status, steps, simulated time and wall time."""

    store: str
    status: str
    steps: int
    time: float
    snapshots: int
    wall_seconds: float


class _Records:
    """Moment records waiting for the next commit."""

    def __init__(self):
        self.columns = self._empty()

    @staticmethod
    def _empty():
        return {name: [] for name in ("step_time", "step", "dt", "momentum") + SCALAR_MOMENTS}

    def add(self, step: int, t: float, dt: float, record: dict) -> None:
        self.columns["step_time"].append(t)
        self.columns["step"].append(step)
        self.columns["dt"].append(dt)
        for name in ("momentum",) + SCALAR_MOMENTS:
            self.columns[name].append(record[name])

    def take(self) -> dict:
        taken, self.columns = self.columns, self._empty()
        return taken


class Simulation:
    """Everything a run needs, built once from a description.

    f0 is checked against the grid (:func:`check_fits`) and projected onto the
    Nyquist-free modes the operators evolve (:meth:`VelocityGrid.project`).
    """

    def __init__(self, description: RunDescription):
        if not isinstance(description, RunDescription):
            raise TypeError(f"Simulation: parameter 'description' = {description!r} is invalid; "
                            "must be a RunDescription")
        self.description = d = description
        self.grid = d.grid
        check_run_memory(d)   # before anything of the grid's size is allocated
        self.backend = d.build("backend")
        self.operator = d.build("operator", grid=d.grid, kernel=d.build("kernel"),
                                restitution=d.build("restitution"), backend=self.backend)
        self.integrator = d.build("integrator")
        initial = d.build("initial")
        sampled = initial.sample(d.grid)
        check_fits(d.grid, sampled, initial, d.health.edge_tolerance,
                   d.health.initial_mass_tolerance)
        self.f0 = d.grid.project(sampled)
        #: moments of f0 before and after the projection (stored with the run)
        self.projection = check_projection(d.grid, sampled, self.f0, initial,
                                           d.health.projection_tolerance,
                                           d.health.projection_kurtosis_tolerance)
        if d.rescaled:
            self.equation = RescaledBoltzmann(self.operator, self.backend.asarray(self.f0),
                                              d.knudsen)
        else:
            self.equation = HomogeneousBoltzmann(self.operator, d.heat_bath, d.knudsen)
        if d.health.step_limit and not self.integrator.adaptive:
            registries = default_registries()
            schemes = [(name, registries.get("time_integrators", name).factory)
                       for name in registries.names("time_integrators")]
            check_time_step(self.integrator, d.integrator.name, self.equation, self.f0,
                            d.time_step, schemes)

    def provenance(self) -> dict:
        """Versions and plugins behind this run (stored with it)."""
        registries = default_registries()
        plugins = {}
        for field, family in _FAMILIES.items():
            name = (self.backend.name if field == "backend"
                    else getattr(self.description, field).name)
            plugins[field] = f"{name} ({registries.get(family, name).source})"
        return {"granframe": __version__, "backend_config": repr(self.backend), **plugins,
                "python": sys.version.split()[0], "numpy": numpy.__version__,
                "zarr": zarr.__version__, "host": platform.node(), "cpus": available_cpus()}

    # -- schedule ---------------------------------------------------------------------
    def _targets(self):
        """Output points after t = 0: step indices (fixed step) or times (adaptive)."""
        d = self.description
        interval = d.output.snapshot_interval
        if not self.integrator.adaptive:
            total = round(d.final_time / d.time_step)
            every = total if interval is None else round(interval / d.time_step)
            return sorted(set(range(every, total, every)) | {total})
        count = 0 if interval is None else int(math.floor(d.final_time / interval * (1 + 1e-12)))
        times = [k * interval for k in range(1, count + 1)] if count else []
        return sorted({t for t in times if t < d.final_time * (1 - 1e-12)} | {d.final_time})

    # -- running ----------------------------------------------------------------------
    def run(self, out, *, resume: bool = False, overwrite: bool = False,
            progress: bool | None = None, rollback: bool = False, protect=()) -> RunResult:
        """Run to ``final_time`` writing the store ``out`` (see the module notes).

        ``resume`` continues the run in ``out`` (``rollback``: from its last intact
        commit when the last one is damaged, see :meth:`RunStore.resume`); ``overwrite``
        replaces a granframe store at ``out`` (never anything else, nor a store holding a
        path of ``protect``). ``progress`` None shows a progress bar on a terminal only.
        A Ctrl-C leaves the store with status 'interrupted', ready to resume.
        """
        check_run_modes(resume, overwrite)
        d, grid, backend = self.description, self.grid, self.backend
        xp = backend.xp
        start_wall = time.perf_counter()
        description = d.to_dict()
        store = None
        if not (resume and RunStore.exists(out)):
            rescaling = getattr(self.equation, "rescaling", None)
            try:
                store = RunStore.create(
                    out, description, d.to_toml(), grid, self.provenance(), overwrite=overwrite,
                    protect=protect, projection=self.projection,
                    rescaling=None if rescaling is None else rescaling.to_dict())
            except StoreExistsError:
                if not resume:
                    raise         # else: another writer made it meanwhile; continue it
        if store is None:
            store = RunStore.resume(out, description, rollback=rollback)
            state = store.progress
            if state["status"] == "finished":
                store.close()
                return RunResult(str(out), "already finished", state["step"], state["time"],
                                 store.snapshot_count, state.get("wall_seconds", 0.0))
            f_host, t = store.last_snapshot()
            f, step, mass0 = backend.asarray(f_host), int(state["step"]), float(state["mass0"])
            dt_next = state.get("dt_next")
            resumes = state.get("resumes", []) + [step]
            rollbacks = state.get("rollbacks", [])
            wall_before = float(state.get("wall_seconds", 0.0))
        else:
            f, t, step = backend.asarray(self.f0), 0.0, 0
            try:
                record = moments(grid, f, xp)
                # adaptive schemes without a first trial step start from 1% of the run
                mass0, dt_next = record["mass"], d.time_step or d.final_time / 100
                resumes, rollbacks, wall_before = [], [], 0.0
                first = _Records()
                first.add(0, 0.0, 0.0, record)
                store.commit([(0.0, self.f0)], first.columns,
                             {"status": "running", "step": 0, "time": 0.0, "mass0": mass0,
                              "dt_next": dt_next, "resumes": resumes})
                store.publish()
            except BaseException:
                store.discard()      # never in place: the path holds what it held before
                raise

        def state(status, **extra):
            """The progress entry of a commit made now."""
            return {"status": status, "step": step, "time": t, "mass0": mass0,
                    "dt_next": dt_next, "resumes": resumes,
                    **({"rollbacks": rollbacks} if rollbacks else {}),
                    "wall_seconds": wall_before + time.perf_counter() - start_wall, **extra}

        adaptive = self.integrator.adaptive
        targets = [x for x in self._targets() if (x > step if not adaptive else x > t)]
        controller = StepController(d.tolerance) if adaptive else None
        records = _Records()
        bar = tqdm.tqdm(total=d.final_time, initial=t, disable=None if progress is None
                        else not progress, unit="t", dynamic_ncols=True,
                        bar_format="{l_bar}{bar}| t={n:.4g}/{total:.4g} [{elapsed}<{remaining}]"
                                   "{postfix}")
        try:
            for target in targets:
                while (step < target) if not adaptive else (t < target):
                    try:
                        if adaptive:
                            f, t, dt, dt_next = controller.advance(
                                self.integrator, self.equation, t, f, dt_next, target, xp)
                        else:
                            f = self.integrator.step(self.equation, t, f, d.time_step)
                    except (NonFiniteError, StepSizeError) as exc:   # a stage blew up, or
                        problem = (exc if isinstance(exc, StepSizeError)   # dt fell to round-off
                                   else "f is not finite (NaN or Inf) within the step")
                        self._fail(store, records, state, f"health check failed at step "
                                   f"{step + 1}, t = {t:.6g}: {problem}")
                    step += 1
                    if not adaptive:
                        dt, t = d.time_step, step * d.time_step
                    record = moments(grid, f, xp)
                    records.add(step, t, dt, record)
                    problem = health_problem(record, mass0, d.health)
                    if problem is not None:
                        self._fail(store, records, state,
                                   f"health check failed at step {step}, t = {t:.6g}: {problem}")
                    bar.update(t - bar.n)
                    bar.set_postfix_str(f"step {step}, T={record['temperature']:.6g}, mass drift "
                                        f"{record['mass'] / mass0 - 1:+.1e}", refresh=False)
                done = target == targets[-1]
                store.commit([(t, backend.to_numpy(f))], records.take(),
                             state("finished" if done else "running"))
        except KeyboardInterrupt:
            # the last commit stays what a resume continues from; only its status changes
            # (a commit that already said finished or failed stays so)
            if store.progress.get("status") == "running":
                store.mark("interrupted")
            raise
        finally:
            bar.close()
            store.close()
        return RunResult(str(out), "finished", step, t, store.snapshot_count,
                         store.progress["wall_seconds"])

    @staticmethod
    def _fail(store, records, state, message):
        """Write the moments up to the failing step, mark the store failed, raise HealthError.

        The snapshots stay the last healthy states; the moments show how it failed.
        """
        store.commit([], records.take(), state("failed", message=message))
        raise HealthError(message)
