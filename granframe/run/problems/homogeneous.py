"""The space-homogeneous problem d_t f = Q(f, f)/eps + tau Delta_v f (or its rescaled form)."""

from __future__ import annotations

from granframe.abc import Problem
from granframe.backends import NumpyBackend
from granframe.equations.conservative import ConservativeCorrection
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.equations.rescaled import RescaledBoltzmann
from granframe.memory import check_run_memory
from granframe.parallel import SerialCommunicator
from granframe.model.initial import check_fits, check_projection
from granframe.run.monitors import AccuracyMonitors
from granframe.run.problems.parts import build_operator, check_step
from granframe.run.storage import RECORDED_MOMENTS, homogeneous_layout
from granframe.stepping.stability import OperatorOutline, step_limit
from granframe.velocity.estimators import resolution_report


def moments(grid, f, xp) -> dict:
    """Mass, momentum, temperature, energy, min f, negative-mass share, kurtosis, a2,
    pressure tensor and heat flux of f.

    One fused pass over f and one transfer to the host (:meth:`VelocityGrid.moments`);
    NaN where a moment is undefined (a zero mass).
    """
    fused = grid.moments(f, xp)
    return {name: fused[name] for name in RECORDED_MOMENTS}


class HomogeneousProblem(Problem):
    """A space-homogeneous run, built once from a description (:class:`granframe.abc.Problem`).

    f0 is checked against the grid (:func:`~granframe.model.initial.check_fits`) and
    projected onto the Nyquist-free modes the operators evolve
    (:meth:`~granframe.velocity.grid.VelocityGrid.project`). With ``outline`` the operator
    is an :class:`~granframe.stepping.stability.OperatorOutline` (nothing precomputed, on
    NumPy), which is all that :meth:`step_limit` reads; f0 is then not checked.
    """

    def __init__(self, description, outline: bool = False):
        self.description = d = description
        self.grid = grid = d.grid
        if outline:
            self.backend = NumpyBackend(threads=1)
            self.operator = OperatorOutline(grid, d.build("kernel"), d.build("restitution"),
                                            self.backend)
        else:
            self.backend = d.build("backend")
            check_run_memory(d, self.backend)   # before anything of the grid's size exists
            self.operator = build_operator(d, self.backend)
        self.integrator = d.build("integrator")
        initial = d.build("initial")
        sampled = initial.sample(grid)
        if not outline:
            check_fits(grid, sampled, initial, d.health.edge_tolerance,
                       d.health.initial_mass_tolerance)
        self.f0 = grid.project(sampled)
        self.projection = None if outline else check_projection(
            grid, sampled, self.f0, initial, d.health.projection_tolerance,
            d.health.projection_kurtosis_tolerance, d.health.positivity_tolerance)
        if d.rescaled:
            dissipation = (float(ConservativeCorrection(self.operator).dissipation(self.f0))
                           if outline else None)
            self.equation = RescaledBoltzmann(self.operator, self.backend.asarray(self.f0),
                                              d.knudsen, dissipation=dissipation)
        else:
            self.equation = HomogeneousBoltzmann(self.operator, d.heat_bath, d.knudsen)

        self.rescaling = self.equation.rescaling if d.rescaled else None
        self.communicator = SerialCommunicator()
        self.ranges = ((0, 1),)

    @property
    def owned(self) -> slice:
        """slice(None): the store of a space-homogeneous run has no cell axis, its one
        cell is the whole f."""
        return slice(None)

    def layout(self):
        return homogeneous_layout(self.grid)

    @property
    def record_names(self) -> tuple:
        return RECORDED_MOMENTS

    def state(self, f_host):
        return self.backend.asarray(f_host)

    def snapshot(self, state):
        return self.backend.to_numpy(state)

    def record(self, state) -> dict:
        """The moments of f (:func:`moments`: one fused pass, one transfer)."""
        return moments(self.grid, state, self.backend.xp)

    def monitors(self, store) -> AccuracyMonitors:
        """The accuracy monitors from the store's first record (t = 0) and, for a resumed
        run, their state at its last commit."""
        group = store.group
        initial = {name: group[name][0] for name in ("mass", "momentum", "temperature")}
        return AccuracyMonitors(self.description, self.operator, initial,
                                store.progress.get("accuracy"))

    def report(self, state, record, monitors):
        """The resolution indicators of f (an FFT of f and one of |f| padded to 2N,
        :func:`~granframe.velocity.estimators.resolution_report`), then the edge shares and
        the spectral tail into the accuracy monitors."""
        xp = self.backend.xp
        resolution = resolution_report(self.grid, state.f, record["negative_mass_fraction"],
                                       self.description.health.resolution_tolerance, xp)
        problem = monitors.update(monitors.shape(state.f, record, resolution, xp),
                                  state.step, state.t)
        return resolution, problem

    def progress_text(self, record, mass0) -> str:
        return (f"T={record['temperature']:.6g}, "
                f"mass drift {record['mass'] / mass0 - 1:+.1e}")

    def step_limit(self):
        return step_limit(self.integrator, self.equation, self.f0)

    def check_step(self) -> None:
        check_step(self.description, self.integrator, self.equation, self.f0)
