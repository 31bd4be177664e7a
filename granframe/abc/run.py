"""The contracts of a run: the problem the runner steps, the processes that step it
together and their messages, and the deferral of host-copying checks within a step.

:mod:`granframe.run.problems` implements :class:`Problem`, :mod:`granframe.parallel` the
serial :class:`Communicator` and the plugin ``granframe_mpi`` MPI's. Imported from
:mod:`granframe.abc`.
"""

from __future__ import annotations

import abc
import contextlib
import contextvars

import numpy

from granframe.abc.arrays import ArrayBackend
from granframe.abc.operators import CollisionOperator
from granframe.abc.stepping import TimeIntegrator
from granframe.abc.velocity import Grid


# -- Host-copying checks, deferred within a step ----------------------------------------------

_DEFERRED = contextvars.ContextVar("granframe_deferred_checks", default=None)


@contextlib.contextmanager
def deferred_checks(everywhere: bool = False):
    """Within it, a check of an operand that would copy a device array to the host (the
    operators' finiteness check of f) is not made on a backend whose arrays live on a
    device (:attr:`~granframe.abc.ArrayBackend.on_device`): a run steps inside it, and its
    health check of each step's record (one transfer) finds a non-finite f instead.

    ``everywhere``: on every backend. A run spread over processes steps so: a check that
    raised in one process only would leave the others waiting for its messages, where the
    health check of the record, reduced over all processes, stops them all at one step."""
    token = _DEFERRED.set("everywhere" if everywhere else "device")
    try:
        yield
    finally:
        _DEFERRED.reset(token)


def checks_deferred(backend) -> bool:
    """Whether a host-copying check of an operand on ``backend`` is left out here
    (:func:`deferred_checks`)."""
    mode = _DEFERRED.get()
    return mode == "everywhere" or (mode == "device"
                                    and bool(getattr(backend, "on_device", False)))


def checked_energy_factors(kernel, energy, backend):
    """phi(E) = E^gamma of ``kernel`` at every energy of the backend array ``energy``, on
    the backend. Each E is refused by name unless positive and finite
    (:meth:`CollisionKernel.energy_factor`) where the operand checks are made; within a
    run's step (:func:`checks_deferred`) that check, which copies E to the host, is left
    out, and a non-positive E gives a NaN that the run's health check reports."""
    if not checks_deferred(backend):
        for value in backend.to_numpy(energy):
            kernel.energy_factor(float(value))
    return kernel.energy_factors(energy)


# -- Processes: a run spread over several ------------------------------------------------------


class Pending(abc.ABC):
    """Messages posted by :meth:`Communicator.start`, in flight until :meth:`wait`."""

    @abc.abstractmethod
    def wait(self) -> None:
        """Return once every message is complete: the receive buffers hold the data and
        the send buffers may be written again."""


class Communicator(abc.ABC):
    """The processes that run one problem together, and the messages between them.

    A space run owns a contiguous range of cells in each process
    (:class:`granframe.space.domain.Domain`); the processes exchange the ghost cells of
    the ends of their ranges point to point (:meth:`start`) and reduce the totals of
    each step in one collective call (:meth:`allgather`). A serial run is the case of one
    process (:class:`granframe.parallel.SerialCommunicator`); the plugin ``mpi`` gives
    MPI's (docs/scaling.md). Every call except :meth:`start` and :meth:`abort` is
    collective: all processes make it, in the same order.

    Attributes
    ----------
    rank, size : int
        This process's number, 0 <= rank < size, and the number of processes.
    local_rank, local_size : int
        Its number among the processes on the same host (which device it takes), and
        their number (who share the host's memory).
    """

    rank: int = 0
    size: int = 1
    local_rank: int = 0
    local_size: int = 1

    @abc.abstractmethod
    def start(self, sends, receives) -> Pending:
        """Post non-blocking messages and return at once.

        ``sends`` and ``receives`` are lists of ``(peer, tag, array)``: a contiguous array
        of the run's backend (device memory included) sent to, or received in place from,
        process ``peer``; a receive matches the send of the same tag from that peer."""

    @abc.abstractmethod
    def allgather(self, vector) -> numpy.ndarray:
        """The host vectors of every process, stacked in rank order: shape (size, n)
        for a float64 vector of length n (the same n everywhere)."""

    @abc.abstractmethod
    def allgather_object(self, value) -> list:
        """A picklable value of every process, as a list in rank order."""

    @abc.abstractmethod
    def bcast(self, value, root: int = 0):
        """Process ``root``'s picklable value, in every process."""

    def abort(self, code: int) -> None:
        """End every process of the run with exit status ``code`` (after an error in one
        process that the others, waiting for its messages, would never learn of)."""
        raise SystemExit(code)


# -- Problems: what a run steps --------------------------------------------------------------


class Problem(abc.ABC):
    """What a run is made of: the one contract between a discretised equation and the runner.

    The runner (:class:`granframe.run.runner.Simulation`), ``granframe limits``,
    ``granframe bench`` and resume use a problem through these members only, in a
    space-homogeneous run as in a space run on any number of processes (the communicator
    and the ranges are always there); one class implements it for zero and one space
    dimensions (:class:`granframe.run.problems.SpaceProblem`).

    A run goes: :attr:`f0` (checked and projected when the problem is built) becomes the
    stepped state by :meth:`state`; each step is :meth:`step`; after it :meth:`record`
    gives what the store keeps of that step (one host transfer at most); at each output
    point :meth:`snapshot` gives f on the host, and :meth:`report` the indicators kept
    with the commit. :meth:`layout` says what the store holds.
    """

    #: the run description the problem was built from
    description: object
    #: the array backend the state lives on
    backend: "ArrayBackend"
    #: f0 on the host, checked against the grid and projected onto the evolved modes
    f0: numpy.ndarray
    #: the moments of f0 before and after that projection (kept in the store's metadata)
    projection: dict
    #: the time integrator (its ``adaptive`` flag selects fixed or controlled steps) and the
    #: equation it integrates; :meth:`step` is ``integrator.step(equation, t, state, dt)``
    integrator: "TimeIntegrator"
    equation: object
    #: the velocity grid and the collision operator (None for a collisionless space run)
    grid: "Grid"
    operator: "CollisionOperator | None"
    #: the processes that run the problem together: a serial communicator (one process)
    #: for a space-homogeneous run and a serial space run, as in a parallel run's rank 0
    communicator: "Communicator"
    #: the cells of every process, ``(start, stop)`` in rank order: ``((0, 1),)`` for a
    #: space-homogeneous run, one cell in one process
    ranges: tuple
    #: the map of a rescaled run to physical variables (kept in the store), or None
    rescaling: object

    @property
    @abc.abstractmethod
    def owned(self) -> slice:
        """The cells this process steps and commits, as indices of the store's cell axis;
        ``slice(None)``, the whole f, where the store has no cell axis (a
        space-homogeneous run: its one cell is f)."""

    @abc.abstractmethod
    def layout(self):
        """The store layout (:class:`granframe.run.storage.Layout`): coordinates, the
        snapshot array and its chunks, and the arrays recorded after every step."""

    @property
    @abc.abstractmethod
    def record_names(self) -> tuple:
        """The names of :meth:`record`'s entries that the store keeps after every step."""

    @abc.abstractmethod
    def state(self, f_host):
        """The stepped state from f on the host (f0, or a stored snapshot when resuming)."""

    @abc.abstractmethod
    def snapshot(self, state) -> numpy.ndarray:
        """f of ``state`` on the host, as the store's snapshot array holds it."""

    def resume(self, store, step: int) -> None:
        """Take up what the problem keeps besides f (none by default) from ``store``,
        whose run is resumed at ``step``: :meth:`state` then receives its last snapshot."""

    def step(self, t: float, state, dt: float):
        """One step of length ``dt`` from time ``t``; returns the new state. The operators'
        per-call checks that would copy to the host are left to the health check of the
        step's record (:func:`deferred_checks`)."""
        with deferred_checks():
            return self.integrator.step(self.equation, t, state, dt)

    @abc.abstractmethod
    def record(self, state) -> dict:
        """What the store keeps of ``state`` after a step (:attr:`record_names`), on the
        host, and ``mass``, ``kinetic_energy``, ``min_f``, ``negative_mass_fraction`` and
        ``temperature`` for the health checks and the progress bar; one device->host
        transfer at most."""

    @abc.abstractmethod
    def monitors(self, store):
        """The accuracy monitors of a run in ``store`` (a new one, or one being resumed,
        whose last commit holds their state) (:mod:`granframe.run.monitors`)."""

    @abc.abstractmethod
    def report(self, state, record: dict, monitors) -> tuple:
        """At an output point: ``(resolution, problem)``, the resolution indicators kept
        with the commit (or None), and the first accuracy monitor above its tolerance
        (a message) or None; ``monitors`` are :meth:`monitors`' and take the report."""

    @abc.abstractmethod
    def progress_text(self, record: dict, mass0: float) -> str:
        """What the progress bar shows after a step besides t and the step number."""

    @abc.abstractmethod
    def step_limit(self):
        """The explicit step limit of the problem's integrator at f0
        (:class:`granframe.stepping.stability.StepLimit`), or None when nothing is
        explicit."""

    def check_step(self) -> None:
        """Refuse a fixed time step above :meth:`step_limit` (a message naming the step,
        the limit and the schemes that would take it); by default nothing is checked."""
