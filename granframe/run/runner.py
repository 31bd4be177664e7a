"""Run a :class:`~granframe.run.description.RunDescription` into a store.

:class:`Simulation` builds the run's problem once (:func:`~granframe.run.problems.make_problem`:
operator precomputation included, f0 checked against the grid) and drives it through the
:class:`granframe.abc.Problem` contract; :meth:`Simulation.run` is a loop over the steps a
:class:`Stepper` yields (fixed or adaptive, from a fresh or a resumed state) and a list of
:class:`Observer` objects, each on its schedule: the problem's record after every step (one
transfer to the host), the health limits, the progress bar, the accuracy monitors, and at
the output points a commit of f with the pending records (see :mod:`granframe.run.storage`
for why a stop at any moment leaves a valid store). ``resume=True`` continues from the last
committed snapshot; the result equals that of an uninterrupted run to round-off.
"""

from __future__ import annotations

import enum
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

from granframe import validators as check
from granframe._version import __version__
from granframe.backends import available_cpus
from granframe.errors import NonFiniteError
from granframe.registry import default_registries
from granframe.run.description import COMPONENT_FAMILIES, RunDescription, fixed_steps
from granframe.run.problems import make_problem, moments
from granframe.run.storage import RECORDED_MOMENTS, RunStore, StoreExistsError, collective
from granframe.stepping.integrators import StepController, StepSizeError
from granframe.validators import distinct, reject

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
    check.existing_file("run", "source", path, "a .toml description or a .py study module")
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


def run_in_memory(description: RunDescription, *, progress: bool | None = None):
    """Run ``description`` in memory and return it as an :class:`xarray.Dataset`, equal to
    what :func:`granframe.open_run` gives for the same run on disk
    (:meth:`Simulation.run_in_memory`)."""
    return Simulation(description).run_in_memory(progress=progress)


def check_run_modes(resume: bool, overwrite: bool) -> None:
    """Refuse ``resume`` together with ``overwrite``."""
    if resume and overwrite:
        raise ValueError("run: --resume and --overwrite exclude each other: --resume "
                         "continues the store, --overwrite replaces it")


def _dataset(store: RunStore):
    """:func:`granframe.run.dataset.run_dataset` (xarray is imported on first use)."""
    from granframe.run.dataset import run_dataset

    return run_dataset(store)


class HealthError(RuntimeError):
    """A run stopped by a health check; the message says which check, when and by how much.

    ``dataset``: for a run held in memory, its contents up to the failing step (the
    snapshots the last healthy states, the moments to the failing step); None otherwise.
    """

    dataset = None


#: what to change, after each kind of health stop
UNSTABLE = ("the step is unstable, or f left the velocity grid: a smaller time_step (granframe "
            "limits prints the stability limits), a larger grid.support_radius if f reaches "
            "the faces of the box, or for a stiff collision term (small knudsen) a penalised "
            "integrator with conservative = true")
MASS_LOST = ("the collision step does not conserve mass: conservative = true conserves it "
             "exactly; otherwise a larger grid.n_modes or a smaller time_step")
RINGING = ("f rings below zero where the grid does not resolve it: a larger grid.n_modes "
           "(spacing h = 2L/N against the narrowest sqrt(T) of the run), a larger "
           "grid.support_radius if f reaches the faces of the box, or a smaller time_step if "
           "the step makes it")


def health_problem(record: dict, mass0: float, health) -> str | None:
    """What is wrong with the state behind ``record`` and what to change, or None (see
    :class:`Health`)."""
    values = [record["mass"], record["kinetic_energy"], record["min_f"]]
    if not all(math.isfinite(v) for v in values):
        return f"f is not finite (NaN or Inf); {UNSTABLE}"
    if record["mass"] <= 0.0:
        return f"the mass is not positive ({record['mass']:.6g}); {UNSTABLE}"
    drift = abs(record["mass"] / mass0 - 1.0)
    if drift > health.mass_tolerance:
        shown, limit = distinct(drift, health.mass_tolerance)
        return (f"mass drift |mass/mass(0) - 1| = {shown} exceeds health.mass_tolerance = "
                f"{limit}; {MASS_LOST}")
    if record["negative_mass_fraction"] > health.positivity_tolerance:
        shown, limit = distinct(record["negative_mass_fraction"], health.positivity_tolerance)
        return (f"loss of positivity: negative mass share {shown} exceeds "
                f"health.positivity_tolerance = {limit} (min f = {record['min_f']:.3g}); "
                f"{RINGING}")
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
    #: the resolution warnings of the last output point
    #: (:func:`granframe.velocity.estimators.resolution_report`)
    warnings: tuple = ()
    #: a run held in memory (``out`` None): its contents, as :func:`granframe.open_run`
    #: gives them for a store on disk
    dataset: object = attrs.field(default=None, repr=False, eq=False)
    #: the accuracy warnings of the last output point (:mod:`granframe.run.monitors`)
    accuracy_warnings: tuple = ()


def _stored_warnings(progress: dict) -> dict:
    """The resolution and the accuracy warnings of the last output point, as a run's
    progress entry stores them: the two warning fields of :class:`RunResult`."""
    return {"warnings": tuple(progress.get("resolution", {}).get("warnings", ())),
            "accuracy_warnings": tuple(progress.get("accuracy", {}).get("warnings", ()))}


class Records:
    """Records waiting for the next commit: the step, its time and size, and ``names``
    of each step's record (by default the moments of :data:`RECORDED_MOMENTS`; a
    problem's :attr:`~granframe.abc.Problem.record_names`)."""

    def __init__(self, names=RECORDED_MOMENTS):
        self.names = tuple(names)
        self.columns = self._empty()

    def _empty(self):
        return {name: [] for name in ("step_time", "step", "dt") + self.names}

    def add(self, step: int, t: float, dt: float, record: dict) -> None:
        self.columns["step_time"].append(t)
        self.columns["step"].append(step)
        self.columns["dt"].append(dt)
        for name in self.names:
            self.columns[name].append(record[name])

    def take(self) -> dict:
        taken, self.columns = self.columns, self._empty()
        return taken


@attrs.define
class RunState:
    """Where a run stands: f at step ``step`` and time ``t``, and what a commit records.

    The :class:`Stepper` advances it in place; the observers read it (the
    :class:`RecordObserver` leaves the step's record in ``record``).
    """

    f: object
    t: float
    step: int
    #: the mass the run must hold: the initial mass plus what entered through the ends of
    #: a space run (nothing but round-off through a wall; an open end's inflow and outflow,
    #: :class:`~granframe.space.boundaries.Reservoir`), added after every step
    mass0: float
    #: the step size proposed next (an adaptive scheme's trial step; time_step otherwise)
    dt_next: float | None
    #: the steps a run was resumed at, and the commits it rolled back past
    resumes: list
    rollbacks: list
    #: wall seconds of the earlier sessions of a resumed run
    wall_before: float = 0.0
    started: float = attrs.field(factory=time.perf_counter)
    #: the size of the last step, and its moments
    dt: float = 0.0
    record: dict | None = None
    #: the resolution indicators of f at the last output point
    resolution: dict | None = None
    #: the accuracy monitors (:meth:`AccuracyMonitors.report`) at the last output point
    accuracy: dict | None = None

    def progress(self, status: str, **extra) -> dict:
        """The progress entry of a commit made now."""
        return {"status": status, "step": self.step, "time": self.t, "mass0": self.mass0,
                "dt_next": self.dt_next, "resumes": self.resumes,
                **({"rollbacks": self.rollbacks} if self.rollbacks else {}),
                **({"resolution": self.resolution} if self.resolution else {}),
                **({"accuracy": self.accuracy} if self.accuracy else {}),
                "wall_seconds": self.wall_before + time.perf_counter() - self.started, **extra}


class Stopped(Exception):
    """A step or a health check stopped the run; the message says why (see :class:`HealthError`)."""


class Reached(enum.Enum):
    """What a step reached: nothing to write, an output point, or the last one."""

    STEP = "step"
    OUTPUT = "output"
    FINAL = "final"


class Stepper:
    """The steps of a run from a :class:`RunState` (a fresh or a resumed one) to its end.

    Fixed steps land on the step indices of the output points; an adaptive scheme's
    :class:`StepController` shortens the step that would pass an output time. Fixed
    steps put t = step * time_step (not a sum), so a resumed run takes exactly the
    steps of an uninterrupted one; when final_time is not a whole multiple of
    time_step, the last step is shortened to end on it exactly
    (:func:`~granframe.run.description.fixed_steps`) and its size is given to the
    integrator, so schemes that cache factors of dt (exp(dt L)) use the short one.

    Parameters
    ----------
    problem : granframe.abc.Problem
        Its :meth:`~granframe.abc.Problem.step` takes the fixed steps; an adaptive scheme
        (its ``integrator.adaptive``) is driven on its ``integrator`` and ``equation``.
    targets : list
        The output points after t = 0 (:meth:`Simulation.output_points`): step indices for
        fixed steps, times for adaptive ones.
    time_step : float or None
        dt of a fixed-step scheme.
    tolerance : float or None
        Error tolerance of an adaptive scheme.
    final_time : float or None
        Where a fixed-step run ends (its last step may be shorter than ``time_step``);
        None: at the last target, a whole number of steps.
    """

    def __init__(self, problem, targets, time_step, tolerance, final_time=None):
        self.problem = problem
        self.adaptive = problem.integrator.adaptive
        self.targets, self.time_step = targets, time_step
        self.controller = StepController(tolerance) if self.adaptive else None
        self.full_steps, self.final_time = math.inf, final_time
        if not self.adaptive and final_time is not None:
            self.full_steps = fixed_steps(final_time, time_step)[0]

    def _fixed_step(self, step: int) -> tuple[float, float]:
        """(dt, t at its end) of fixed step number ``step`` (1 first): a full step ends at
        step * time_step, the short last one at final_time."""
        if step <= self.full_steps:
            return self.time_step, step * self.time_step
        return self.final_time - self.full_steps * self.time_step, self.final_time

    def _before(self, state: RunState, target) -> bool:
        return state.t < target if self.adaptive else state.step < target

    def steps(self, state: RunState):
        """Advance ``state`` step by step, yielding what each step :class:`Reached`.

        Raises :class:`Stopped` when a stage is not finite or the adaptive step size
        falls to round-off (``state`` is then the last step's).
        """
        remaining = [x for x in self.targets if self._before(state, x)]
        for target in remaining:
            while self._before(state, target):
                self._advance(state, target)
                if self._before(state, target):
                    yield Reached.STEP
                else:
                    yield Reached.FINAL if target == remaining[-1] else Reached.OUTPUT

    def _advance(self, state: RunState, target) -> None:
        try:
            if self.adaptive:
                problem = self.problem
                state.f, state.t, state.dt, state.dt_next = self.controller.advance(
                    problem.integrator, problem.equation, state.t, state.f, state.dt_next,
                    target, problem.backend.xp)
            else:
                dt, t_end = self._fixed_step(state.step + 1)
                state.f = self.problem.step(state.t, state.f, dt)
        except (NonFiniteError, StepSizeError) as exc:   # a stage blew up, or dt fell to
            problem = (f"{exc}; {UNSTABLE}" if isinstance(exc, StepSizeError)  # round-off
                       else f"f is not finite (NaN or Inf) within the step; {UNSTABLE}")
            raise Stopped(f"health check failed at step {state.step + 1}, t = {state.t:.6g}: "
                          f"{problem}") from exc
        state.step += 1
        if not self.adaptive:
            state.dt, state.t = dt, t_end


class Observer:
    """What a run does besides stepping, each on its own schedule.

    The run loop (:meth:`Simulation.run`) calls every observer's :meth:`after_step`
    after each step, in order, then :meth:`at_output` at each output point, and
    :meth:`close` when the run ends however it ends.
    """

    def after_step(self, state: RunState) -> None:
        """Called after every step."""

    def at_output(self, state: RunState, final: bool) -> None:
        """Called at every output point (``final``: the last of the run)."""

    def close(self) -> None:
        """Called once, when the run ends (finished, stopped or interrupted)."""


class RecordObserver(Observer):
    """After every step: the problem's record of the state
    (:meth:`~granframe.abc.Problem.record`, one transfer to the host) into
    ``state.record`` and the records waiting for the next commit."""

    def __init__(self, problem, records: "Records"):
        self.problem, self.records = problem, records

    def after_step(self, state):
        state.record = self.problem.record(state.f)
        self.records.add(state.step, state.t, state.dt, state.record)


class HealthObserver(Observer):
    """After every step: the health limits (:func:`health_problem`) on the step's moments."""

    def __init__(self, health):
        self.health = health

    def after_step(self, state):
        entered = state.record.get("wall_mass")
        if entered is not None:      # what crossed the ends: an open end's (Reservoir) inflow
            state.mass0 += float(numpy.sum(entered))
        problem = health_problem(state.record, state.mass0, self.health)
        if problem is not None:
            raise Stopped(f"health check failed at step {state.step}, t = {state.t:.6g}: "
                          f"{problem}")


class AccuracyObserver(Observer):
    """The accuracy monitors (:mod:`granframe.run.monitors`): after every step the drifts
    of momentum and temperature (from the step's record, no pass over f); at every output
    point the problem's :meth:`~granframe.abc.Problem.report`: the resolution indicators
    (which the next commit keeps in ``state.resolution``) and the monitors of the shape of
    f (edge shares, spectral tail), whose report goes into ``state.accuracy``. With
    ``health.stop_on_accuracy`` a monitor above ``health.accuracy_tolerance`` stops the
    run."""

    def __init__(self, problem, monitors):
        self.problem, self.monitors = problem, monitors

    def _stop(self, state, problem):
        if problem is not None:
            state.accuracy = self.monitors.report()
            raise Stopped(f"health check failed at step {state.step}, t = {state.t:.6g}: "
                          f"{problem}")

    def after_step(self, state):
        monitors = self.monitors
        self._stop(state, monitors.update(monitors.drifts(state.record, state.t),
                                          state.step, state.t))

    def at_output(self, state, final):
        state.resolution, problem = self.problem.report(state, state.record, self.monitors)
        state.accuracy = self.monitors.report()
        self._stop(state, problem)


class ProgressObserver(Observer):
    """After every step: the progress bar (t, step, and the problem's
    :meth:`~granframe.abc.Problem.progress_text`: T and the mass drift).

    ``show`` None shows it on a terminal only.
    """

    def __init__(self, state: RunState, final_time: float, show: bool | None, text):
        self.text = text
        self.bar = tqdm.tqdm(total=final_time, initial=state.t,
                             disable=None if show is None else not show, unit="t",
                             dynamic_ncols=True,
                             bar_format="{l_bar}{bar}| t={n:.4g}/{total:.4g} "
                                        "[{elapsed}<{remaining}]{postfix}")

    def after_step(self, state):
        # t = step * dt may pass final_time by round-off (3 * 0.1 > 0.3): the bar stops at
        # its total instead of warning that it clamps
        self.bar.update(min(state.t, self.bar.total) - self.bar.n)
        self.bar.set_postfix_str(f"step {state.step}, "
                                 f"{self.text(state.record, state.mass0)}", refresh=False)

    def close(self):
        self.bar.close()


class StorageObserver(Observer):
    """At every output point: a commit of f with the pending moment records.

    The problem's ``snapshot(f)`` is the state f as the NumPy array the store holds; its
    processes commit together (:func:`_commit`). It also writes how a run ends
    otherwise: :meth:`fail` (a health check) and :meth:`interrupt` (a Ctrl-C);
    :meth:`close` closes the store.
    """

    def __init__(self, store: RunStore, records: "Records", problem):
        self.store, self.records, self.problem = store, records, problem

    def at_output(self, state, final):
        _commit(self.store, self.problem, [(state.t, self.problem.snapshot(state.f))],
                self.records.take(), state.progress("finished" if final else "running"))

    def fail(self, state: RunState, stop: Stopped):
        """Write the moments up to the failing step, mark the store failed, raise HealthError.

        The snapshots stay the last healthy states; the moments show how it failed.
        """
        message = str(stop)
        _commit(self.store, self.problem, [], self.records.take(),
                state.progress("failed", message=message))
        error = HealthError(message)
        if self.store.path is None:
            error.dataset = _dataset(self.store)
        raise error from stop.__cause__

    def interrupt(self):
        """After a Ctrl-C: the last commit stays what a resume continues from; only its
        status changes (a commit that already said finished or failed stays so); the
        process that holds the writer lock marks it."""
        if self.store.lock is None and self.store.path is not None:
            return
        if self.store.progress.get("status") == "running":
            self.store.mark("interrupted")

    def close(self):
        self.store.close()


def _commit(store: RunStore, problem, snapshots, records: dict, progress: dict) -> None:
    """A commit of ``snapshots`` and ``records`` by all the processes of the run together,
    each its owned cells (:meth:`RunStore.commit_together`; a serial run is the case of
    one process, a space-homogeneous run that of one process owning all of f)."""
    store.commit_together(problem.communicator, problem.owned, snapshots, records, progress)


class Simulation:
    """A run of the problem a description asks for, built once.

    The problem (:func:`~granframe.run.problems.make_problem`: space-homogeneous, or in
    space for a description with a ``space`` section) holds everything the run steps; the
    simulation drives it through the :class:`granframe.abc.Problem` contract only. The
    problem's public members (``grid``, ``backend``, ``operator``, ``f0``, ``equation``,
    ``integrator``, ``projection``, a space run's ``domain``, ...) are read through the
    simulation. A fixed time
    step above the explicit stability limit at f0 is refused here.

    A space run launched on several processes (``mpiexec -n 4 granframe run ...``) is
    spread over them (docs/scaling.md): each steps and writes the cells it owns, and they
    write one store together. ``communicator`` (:class:`granframe.abc.Communicator`):
    the processes, by default those of :func:`granframe.parallel.world`; ``partition``:
    the cells of each process (:func:`granframe.parallel.partition`), by default even.
    """

    def __init__(self, description: RunDescription, communicator=None, partition=None):
        if not isinstance(description, RunDescription):
            raise TypeError(f"Simulation: parameter 'description' = {description!r} is invalid; "
                            "must be a RunDescription")
        self.description = description
        self.problem = make_problem(description, communicator=communicator,
                                    partition=partition)
        self.problem.check_step()

    @property
    def communicator(self):
        """The processes of the run (a serial communicator for one process)."""
        return self.problem.communicator

    def __getattr__(self, name):
        """The problem's public members, read through the simulation for convenience
        (``simulation.f0``, ``simulation.domain`` in a notebook or a test); granframe's own
        code reads ``simulation.problem``, the runner through the
        :class:`granframe.abc.Problem` contract only."""
        if name.startswith("_") or "problem" not in self.__dict__:
            raise AttributeError(name)
        return getattr(self.__dict__["problem"], name)

    def provenance(self) -> dict:
        """Versions and plugins behind this run (stored with it)."""
        registries = default_registries()
        plugins = {}
        for field, family in COMPONENT_FAMILIES.items():
            name = (self.problem.backend.name if field == "backend"
                    else getattr(self.description, field).name)
            plugins[field] = f"{name} ({registries.get(family, name).source})"
        return {"granframe": __version__, "backend_config": repr(self.problem.backend), **plugins,
                "python": sys.version.split()[0], "numpy": numpy.__version__,
                "zarr": zarr.__version__, "host": platform.node(), "cpus": available_cpus(),
                **self._processes()}

    def _processes(self) -> dict:
        """The processes of a space run and the cells (start, stop) of each, for the
        provenance (a resumed run may use others); nothing for one process."""
        ranges = self.problem.ranges
        if len(ranges) == 1:
            return {}
        return {"processes": len(ranges), "ranges": [list(r) for r in ranges],
                "communicator": repr(self.communicator)}

    # -- schedule ---------------------------------------------------------------------
    def output_points(self):
        """Output points after t = 0: step indices (fixed step) or times (adaptive).

        A fixed-step run's last point is its last step, a short one when final_time is
        not a whole multiple of time_step (:func:`~granframe.run.description.fixed_steps`).
        """
        d = self.description
        interval = d.output.snapshot_interval
        if not self.problem.integrator.adaptive:
            full, last = fixed_steps(d.final_time, d.time_step)
            total = full + (1 if last else 0)
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

        The :class:`Stepper` yields the steps; the observers (moments, health, progress
        bar, storage) act on them, each on its schedule.

        ``out`` None holds the run in memory (:meth:`run_in_memory`): the same steps,
        checks and records, in a store no file backs; the result's ``dataset`` holds it.
        """
        if out is None and resume:
            reject("Simulation.run", "resume", resume, "needs a store on disk to continue "
                   "(out = None holds a run in memory, from t = 0)")
        communicator = self.communicator
        if out is None and communicator.size > 1:
            reject("Simulation.run", "out", out, f"must be a path on disk for a run on "
                   f"{communicator.size} processes (they write one store together; a store "
                   "in memory is one process's)")
        check_run_modes(resume, overwrite)
        started = time.perf_counter()
        store, state = self._open(out, resume, overwrite, rollback, protect, started)
        if state is None:
            progress_entry = store.progress
            store.close()
            return RunResult(str(out), "already finished", progress_entry["step"],
                             progress_entry["time"], store.snapshot_count,
                             progress_entry.get("wall_seconds", 0.0),
                             **_stored_warnings(progress_entry))
        d = self.description
        stepper = Stepper(self.problem, self.output_points(), d.time_step, d.tolerance,
                          d.final_time)
        observers = self._observers(store, state, progress)
        storage = observers[-1]
        try:
            try:
                for reached in stepper.steps(state):
                    for observer in observers:
                        observer.after_step(state)
                    if reached is not Reached.STEP:
                        for observer in observers:
                            observer.at_output(state, reached is Reached.FINAL)
            except Stopped as stop:
                storage.fail(state, stop)
        except KeyboardInterrupt:
            storage.interrupt()
            raise
        finally:
            for observer in observers:
                observer.close()
        final = communicator.bcast(store.progress)      # process 0's, which wrote it
        return RunResult("memory" if out is None else str(out), "finished", state.step,
                         state.t, int(final["snapshots"]), final["wall_seconds"],
                         dataset=_dataset(store) if out is None else None,
                         **_stored_warnings(final))

    def _observers(self, store, state, progress) -> list:
        """What the run does besides stepping, in order; the :class:`StorageObserver` last."""
        d, problem = self.description, self.problem
        records = Records(problem.record_names)
        if self.communicator.rank != 0:     # one progress bar: process 0's
            progress = False
        return [RecordObserver(problem, records), HealthObserver(d.health),
                ProgressObserver(state, d.final_time, progress, problem.progress_text),
                AccuracyObserver(problem, problem.monitors(store)),
                StorageObserver(store, records, problem)]

    def run_in_memory(self, *, progress: bool | None = None):
        """Run to ``final_time`` in memory and return the run as an :class:`xarray.Dataset`.

        For notebooks: nothing is written to disk, and the dataset equals what
        :func:`granframe.open_run` gives for the same run written to a store (the same
        variables, coordinates and attributes; only the creation time and the wall
        seconds differ). The steps, the health checks and the resolution indicators are
        those of :meth:`run`; a health check that fails raises :class:`HealthError`, whose
        ``dataset`` holds the run up to the failing step.

        Examples
        --------
        >>> import granframe
        >>> from granframe.run.description import RunDescription
        >>> d = RunDescription.from_toml(open("heated.toml").read())  # doctest: +SKIP
        >>> ds = granframe.Simulation(d).run_in_memory()                       # doctest: +SKIP
        >>> ds.temperature.plot()                                              # doctest: +SKIP
        """
        return self.run(None, progress=progress).dataset

    def _open(self, out, resume, overwrite, rollback, protect, started):
        """The store of the run and the state it starts from: a new store with the moments
        of f0 committed, or the store being resumed and its last snapshot. The state is
        None when the resumed run is already finished.

        Process 0 creates or resumes the store and holds its writer lock; the others open
        it once it is ready (what process 0 met, a refusal included, is raised in all)."""
        d = self.description
        description = d.to_dict()
        problem, communicator = self.problem, self.communicator
        first = communicator.rank == 0
        opened = []

        def create():
            try:
                opened.append(RunStore.create(
                    out, description, d.to_toml(), d.grid, self.provenance(),
                    overwrite=overwrite, protect=protect, projection=problem.projection,
                    rescaling=None if problem.rescaling is None else problem.rescaling.to_dict(),
                    layout=problem.layout()))
            except StoreExistsError:
                if not resume:
                    raise         # else: another writer made it meanwhile; continue it
                return False, None
            return True, opened[0].path       # staged beside out; None in memory

        if not (resume and collective(communicator, lambda: RunStore.exists(out))):
            created, path = collective(communicator, create)
            if created:
                store = opened[0] if first else RunStore.open(path, "r+", complete=False)
                return self._first_commit(store, started)

        def resume_store():
            self._check_chunks(out)
            opened.append(RunStore.resume(out, description, rollback=rollback))
            return opened[0].progress

        entry = collective(communicator, resume_store)
        store = opened[0] if first else RunStore.open(out, "r+", complete=False)
        if entry["status"] == "finished":
            return store, None
        f_host, t = store.last_snapshot(cells=problem.owned)
        problem.resume(store, int(entry["step"]))
        return store, RunState(problem.state(f_host), t, int(entry["step"]),
                               float(entry["mass0"]), entry.get("dt_next"),
                               entry.get("resumes", []) + [int(entry["step"])],
                               entry.get("rollbacks", []),
                               float(entry.get("wall_seconds", 0.0)), started)

    def _check_chunks(self, out) -> None:
        """Refuse to resume a space run whose store's chunks along x do not fall on the
        boundaries of the processes' cells (a store made with another ``block_cells``),
        before anything is written."""
        if len(self.problem.ranges) == 1 or not RunStore.exists(out):
            return
        space = RunStore.open(out, complete=False).metadata.get("space") or {}
        self.problem.space.check_chunks(space, out)

    def _first_commit(self, store, started):
        """Commit f0 and its moments to a new store and publish it: the store (opened at its
        final path) and the state at t = 0. Every process commits its cells."""
        d, problem, communicator = self.description, self.problem, self.communicator
        try:
            f = problem.state(problem.f0)
            record = problem.record(f)
            # adaptive schemes without a first trial step start from 1% of the run
            state = RunState(f, 0.0, 0, record["mass"], d.time_step or d.final_time / 100,
                             [], [], 0.0, started)
            first = Records(problem.record_names)
            first.add(0, 0.0, 0.0, record)
            f0 = problem.f0[problem.owned]
            _commit(store, problem, [(0.0, f0)], first.columns,
                    {"status": "running", "step": 0, "time": 0.0, "mass0": state.mass0,
                     "dt_next": state.dt_next, "resumes": state.resumes})
            path = collective(communicator, lambda: (store.publish(), store.path)[1])
        except BaseException:
            if communicator.rank == 0:
                store.discard()      # never in place: the path holds what it held before
            raise
        if communicator.rank != 0:
            store = RunStore.open(path, "r+", complete=False)
        return store, state
