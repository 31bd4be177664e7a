"""The problem a run steps (:class:`granframe.abc.Problem`), of zero or one space dimensions.

:func:`make_problem` builds it from a description; the runner, ``granframe
limits`` (:func:`time_step_limit`), ``granframe bench`` and resume use it through the
contract only; :func:`run_cost` times one step of a built problem, for the cost that
``granframe run`` and ``granframe limits`` print before a run starts.
"""

from __future__ import annotations

import math
import time

import attrs

from granframe import validators as check
from granframe.backends import available_cpus
from granframe.run.description import RunDescription, fixed_steps
from granframe.run.problems.space import SpaceProblem
from granframe.run.problems.spaces import Interval, Point, moments

__all__ = ["Interval", "Point", "RunCost", "SpaceProblem", "make_problem", "moments",
           "run_cost", "time_step_limit"]


def make_problem(description, outline: bool = False, communicator=None, partition=None):
    """The :class:`SpaceProblem` of ``description``: of one space dimension when it has a
    ``space`` section, else of zero (a space-homogeneous run). ``outline``: without the
    operator's precomputation (for :func:`time_step_limit`). A run in space is spread over
    the processes of ``communicator`` (by default :func:`granframe.parallel.world`), with
    ``partition`` the cells of each (:func:`granframe.parallel.partition`); a
    space-homogeneous one runs in one process."""
    if not isinstance(description, RunDescription):
        check.reject("make_problem", "description", description, "must be a RunDescription",
                     error=TypeError)
    return SpaceProblem(description, outline, communicator, partition)


def time_step_limit(description):
    """The explicit step limit of a run, from its description alone (no operator built).

    The same :class:`~granframe.stepping.stability.StepLimit` that
    :class:`~granframe.run.runner.Simulation` checks
    (:func:`~granframe.stepping.stability.check_time_step`): the problem is built on an
    :class:`~granframe.stepping.stability.OperatorOutline`, so the radii of the heat bath,
    the collisions and the energy dissipation are computed by the same code from f0
    sampled and projected as the runner does; a rescaled run's drift radius takes its
    cooling rate a_0 from the energy dissipation D(f0) in closed form
    (:meth:`~granframe.equations.conservative.ConservativeCorrection.dissipation`) in place
    of one evaluation of Q. With ``conservative`` set, the runner's operator dissipates
    D(f) itself and the two limits agree to round-off; otherwise they differ by the
    operator's error in D: at 2D N = 48, S = 5 with the direct method by 7e-8 for Maxwell
    molecules (T0 = 1) and 5e-6 for hard spheres (two Gaussians of T = 0.6 at
    u = (+-1, 0)), at 2D N = 32 with fast_spectral on 16 x 8 points by 1e-5 (Maxwell,
    T0 = 8, S = 10). None when the equation has no part the scheme treats explicitly. A
    space run's limit is that of the collisions in its stiffest cell
    (:class:`~granframe.equations.homogeneous.HomogeneousBoltzmann`); the transport's CFL limit is
    :meth:`~granframe.run.description.Space.transport_limit`. At 3D N = 32 it takes a few
    tenths of a second, where building the run's operator takes seconds
    (tests/test_frictions.py).

    Examples
    --------
    >>> import granframe
    >>> from granframe.run.description import RunDescription
    >>> d = RunDescription.from_toml(open("heated.toml").read())  # doctest: +SKIP
    >>> limit = granframe.time_step_limit(d)                                # doctest: +SKIP
    >>> limit.limit, limit.dominant, limit.rates                            # doctest: +SKIP
    """
    if not isinstance(description, RunDescription):
        check.reject("time_step_limit", "description", description,
                     "must be a RunDescription", error=TypeError)
    return make_problem(description, outline=True).step_limit()


@attrs.frozen
class RunCost:
    """What a run will cost on this machine, from one step timed before it starts.

    Attributes
    ----------
    step_seconds : float
        Wall time of one step and its record, timed on the run's grid and cells.
    steps : int or None
        The run's fixed steps (None for an adaptive integrator, whose error control
        sets them).
    cpus : int
        The CPUs this process may use.
    """

    step_seconds: float
    steps: int | None
    cpus: int

    @property
    def total_seconds(self) -> float | None:
        """``steps`` x ``step_seconds`` (None when the steps are not known)."""
        return None if self.steps is None else self.steps * self.step_seconds

    def text(self) -> str:
        """One line: the time per step and the run's total."""
        per_step = f"{_duration(self.step_seconds)} per step (one step timed on {self.cpus} CPUs)"
        if self.steps is None:
            return (f"estimated cost: {per_step}; the number of steps is set by the "
                    "adaptive error control")
        return (f"estimated cost: {self.steps} steps x {per_step} = "
                f"{_duration(self.total_seconds)}")

    def to_dict(self) -> dict:
        return {"step_seconds": self.step_seconds, "steps": self.steps,
                "total_seconds": self.total_seconds, "cpus": self.cpus}


def _duration(seconds: float) -> str:
    """``seconds`` as 0.012 s, 3.4 s, 12 min or 2.5 h."""
    if seconds < 60.0:
        return f"{seconds:.2g} s" if seconds < 10.0 else f"{seconds:.0f} s"
    if seconds < 3600.0:
        return f"{seconds / 60.0:.2g} min" if seconds < 600.0 else f"{seconds / 60.0:.0f} min"
    return f"{seconds / 3600.0:.2g} h"


def run_cost(problem, repeats: int = 1) -> RunCost:
    """Time the step of a built problem and estimate its run's cost from it.

    One step from f0 on a state of its own, and its record, are made first (planning and
    compilation happen there), then ``repeats`` more are timed, the fastest counting.
    The run's state is not touched, and each record takes the wall totals the step left,
    so the run that follows starts as it would without the estimate. The total is the
    fixed steps of the description times that step (:func:`fixed_steps`: the short last
    step counts as one); an adaptive run's steps are not known in advance.

    Parameters
    ----------
    problem : granframe.abc.Problem
        A problem built with its operator (:func:`make_problem`, not an outline).
    repeats : int
        Steps timed after the first one (at least 1).

    Returns
    -------
    RunCost
        The time per step, the steps and the CPUs.

    Examples
    --------
    >>> from granframe.run.problems import make_problem, run_cost
    >>> print(run_cost(make_problem(description)).text())    # doctest: +SKIP
    estimated cost: 2000 steps x 0.021 s per step (one step timed on 2 CPUs) = 42 s
    """
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        check.reject("run_cost", "repeats", repeats, "must be an integer >= 1")
    d = problem.description
    adaptive = problem.integrator.adaptive
    dt = d.time_step or d.final_time / 100.0
    state = problem.state(problem.f0)
    problem.record(problem.step(0.0, state, dt))
    best = math.inf
    for _ in range(repeats):
        started = time.perf_counter()
        problem.record(problem.step(0.0, state, dt))
        best = min(best, time.perf_counter() - started)
    if adaptive:
        steps = None
    else:
        full, last = fixed_steps(d.final_time, d.time_step)
        steps = full + (1 if last else 0)
    return RunCost(best, steps, available_cpus())
