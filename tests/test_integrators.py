"""Every registered time integrator reaches its declared order; adaptive control meets its tolerance."""

import math

import numpy
import pytest

import granframe as gf
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.model.exact import heated_maxwell_temperature
from granframe.velocity.heatbath import HeatBath
from granframe.stepping.integrators import Equation, StepController, StepSizeError

INTEGRATORS = gf.default_registries().names("time_integrators")


class Bernoulli(Equation):
    """f' = -a f + b f^2 split as N = b f^2, L = -a; exact f = 1 / (b/a + (1/f0 - b/a) e^{a t})."""

    def __init__(self, a=3.0, b=1.0):
        self.a, self.b = a, b

    def nonlinear(self, t, f):
        return self.b * f * f

    def linear(self, f):
        return -self.a * f

    def propagate(self, f, dt):
        return math.exp(-self.a * dt) * f

    def exact(self, t, f0):
        return 1.0 / (self.b / self.a + (1.0 / f0 - self.b / self.a) * numpy.exp(self.a * t))


def integrate(name, equation, f0, steps, final_time=1.0):
    integrator = gf.time_integrator(name)
    f, dt = f0.copy(), final_time / steps
    for i in range(steps):
        f = integrator.step(equation, i * dt, f, dt)
    return f


def observed_orders(name, equation, steps):
    """log2 of successive error ratios against the exact solution at t = 1."""
    f0 = numpy.array([0.5, 1.0, 2.0])
    errors = [numpy.abs(integrate(name, equation, f0, n) - equation.exact(1.0, f0)).max()
              for n in steps]
    return numpy.log2(numpy.array(errors[:-1]) / numpy.array(errors[1:]))


def test_the_built_in_schemes_are_registered():
    assert {"forward_euler", "ssp_rk2", "ssp_rk3", "rk4", "if_rk4", "dopri54",
            "penalised_euler", "penalised_ars222"} <= set(INTEGRATORS)


@pytest.mark.parametrize("name", INTEGRATORS)
def test_observed_order_on_a_problem_with_known_solution(name):
    observed = observed_orders(name, Bernoulli(), (20, 40, 80))
    order = gf.time_integrator(name).order
    assert numpy.all(numpy.abs(observed - order) < 0.25), (order, observed)


@pytest.mark.parametrize("name", INTEGRATORS)
def test_self_convergence_on_the_heated_collision_problem(name):
    """d_t f = Q(f,f) + 0.1 Delta f (2D Maxwell molecules, e = 0.5) from T0 = 8 to t = 1:
    successive differences with dt = 1/4, 1/8, 1/16 (penalised: 1/16 ... 1/64) shrink by
    2^order."""
    grid = gf.VelocityGrid(2, 32, 10.0)
    op = gf.collision_operator("fast_spectral", grid, gf.collision_kernel("maxwell"),
                               gf.restitution_law("constant", value=0.5),
                               backend=gf.array_backend("numpy", threads=1), radial_points=16,
                               sphere=gf.CircleTrapezoid(8))
    equation, f0 = HomogeneousBoltzmann(op, heat_bath=0.1), grid.maxwellian(temperature=8.0)
    # the penalised schemes reach their order once dt r < ~0.1 (r = 2 here): IMEX order
    # reduction at dt r ~ 1 gives 0.55 for penalised_euler with dt = 1/4 ... 1/16
    steps = (16, 32, 64) if name.startswith("penalised") else (4, 8, 16)
    solutions = [integrate(name, equation, f0, n) for n in steps]
    d1 = numpy.abs(solutions[0] - solutions[1]).max()
    d2 = numpy.abs(solutions[1] - solutions[2]).max()
    order = gf.time_integrator(name).order
    assert abs(math.log2(d1 / d2) - order) < 0.4, (order, d1, d2)


def test_heat_bath_propagator_is_exact():
    """exp(t tau Delta) of a Maxwellian of temperature T is the Maxwellian of T + 2 tau t."""
    grid = gf.VelocityGrid(2, 64, 6.0)
    heat = HeatBath(grid, 0.1, gf.array_backend())
    result = heat.propagate(grid.maxwellian(temperature=1.3), 2.5)
    expected = grid.maxwellian(temperature=1.3 + 2 * 0.1 * 2.5)
    assert numpy.abs(result - expected).max() < 1e-12 * expected.max()


def test_integrating_factor_rk4_is_exact_for_the_linear_part():
    """With N = 0 the IF scheme is exp(dt L) itself, whatever dt (explicit RK4 is not)."""

    class Linear(Bernoulli):
        def nonlinear(self, t, f):
            return 0.0 * f

    equation, f0 = Linear(a=50.0), numpy.array([1.0])
    assert abs(integrate("if_rk4", equation, f0, 2)[0] - math.exp(-50.0)) < 1e-15
    assert abs(integrate("rk4", equation, f0, 2)[0]) > 1e3   # beyond its stability limit


@pytest.mark.parametrize("tolerance", [1e-4, 1e-6, 1e-8])
def test_adaptive_error_control_meets_the_tolerance(tolerance):
    equation, f0 = Bernoulli(), numpy.array([0.5, 1.0, 2.0])
    integrator, controller = gf.time_integrator("dopri54"), StepController(tolerance)
    t, f, dt, steps = 0.0, f0.copy(), 0.01, 0
    while t < 1.0:
        f, t, _, dt = controller.advance(integrator, equation, t, f, dt, 1.0, numpy)
        steps += 1
    error = numpy.abs(f - equation.exact(1.0, f0)).max() / numpy.abs(f0).max()
    assert t == 1.0 and error <= 10 * tolerance, (error, steps)
    assert steps < 20 * tolerance ** (-1 / 5), steps   # step count grows like tol^(-1/5)


def test_adaptive_step_size_underflow_is_reported():
    class Blowup(Bernoulli):
        def nonlinear(self, t, f):
            return numpy.full_like(f, numpy.nan)

    with pytest.raises(StepSizeError, match="step size fell"):
        StepController(1e-6).advance(gf.time_integrator("dopri54"), Blowup(), 0.0,
                                     numpy.array([1.0]), 0.1, 1.0, numpy)


# -- penalised (asymptotic-preserving) schemes ------------------------------------------------
PENALISED = ["penalised_euler", "penalised_ars222"]


class PenalisedBernoulli(Bernoulli):
    """Bernoulli with a relaxation toward the constant 1 at rate 10 (3x the problem's own
    rate): the penalised schemes keep their order with the implicit part active, once
    dt r < 0.1 (at dt r ~ 1 IMEX schemes lose order, as expected)."""

    def relaxation(self, f):
        return 10.0, numpy.ones_like(f)


@pytest.mark.parametrize("name", PENALISED)
def test_penalised_order_with_active_penalisation(name):
    observed = observed_orders(name, PenalisedBernoulli(), (160, 320, 640))
    assert numpy.all(numpy.abs(observed - gf.time_integrator(name).order) < 0.25), observed


class Relaxing(Equation):
    """y' = -lam y, penalised with rate beta toward 0: the stability function at dt beta."""

    def __init__(self, lam, beta):
        self.lam, self.beta = lam, beta

    def nonlinear(self, t, f):
        return -self.lam * f

    def linear(self, f):
        return 0.0

    def propagate(self, f, dt):
        return f

    def relaxation(self, f):
        return self.beta, 0.0 * f


@pytest.mark.parametrize("name", PENALISED)
def test_penalised_schemes_are_stable_for_any_stiffness(name):
    """|R| <= 1 for every mode lam in [0, beta] and dt beta up to 1e6 (explicit RK4 needs
    dt lam <= 2.79); the first-order scheme damps by |1 - lam/beta| in the stiff limit."""
    integrator = gf.time_integrator(name)
    for ratio in numpy.linspace(0.0, 1.0, 11):
        for stiffness in (1.0, 10.0, 1e2, 1e4, 1e6):
            amplification = integrator.step(Relaxing(ratio, 1.0), 0.0, numpy.array([1.0]),
                                             stiffness)[0]
            assert abs(amplification) <= 1.0 + 1e-12, (ratio, stiffness, amplification)
            if name == "penalised_euler" and stiffness == 1e6:
                assert amplification == pytest.approx(1.0 - ratio, abs=1e-5)


def _stiff_run(name, restitution, knudsen, heat_bath, dt, steps, n_modes=32):
    grid = gf.VelocityGrid(2, n_modes, 4.0)
    op = gf.collision_operator("fast_spectral", grid, gf.collision_kernel("maxwell"),
                               gf.restitution_law("constant", value=restitution),
                               backend=gf.array_backend("numpy", threads=1), radial_points=32,
                               sphere=gf.CircleTrapezoid(32))
    equation = HomogeneousBoltzmann(op, heat_bath=heat_bath, knudsen=knudsen)
    f = (grid.maxwellian(0.6, [0.8, 0.0], 0.8)
         + grid.maxwellian(0.4, [-1.2, 0.3], 0.5))                       # far from equilibrium
    rho, T0, integrator = grid.mass(f), grid.temperature(f), gf.time_integrator(name)
    worst = 0.0
    for i in range(steps):
        f = integrator.step(equation, i * dt, f, dt)
        if not numpy.all(numpy.isfinite(f)) or numpy.abs(f).max() > 1e3:
            return None
        law = heated_maxwell_temperature((i + 1) * dt, T0, restitution, heat_bath,
                                                  rho / knudsen)
        worst = max(worst, abs(grid.temperature(f) / law - 1))
    target = equation.relaxation(f)[1]
    return {"T_error": worst, "mass_drift": abs(grid.mass(f) / rho - 1),
            "distance_to_maxwellian": numpy.abs(f - target).max() / target.max()}


def test_explicit_rk4_fails_where_penalised_schemes_hold():
    """eps = 1e-4, dt = 0.01 (dt/eps = 100), elastic Maxwell molecules with heat bath, from
    two Maxwellians: RK4 blows up in its first step; the penalised schemes conserve mass to
    1e-11, approach the Maxwellian, and follow T0 + 2 tau t to 1e-5 (N = 48, where Q(M) ~ 1e-10;
    at N = 32 the discrete energy error of Q, amplified by dt/eps, gives ~2e-3)."""
    assert _stiff_run("rk4", 1.0, 1e-4, 0.1, 0.01, 3) is None
    euler = _stiff_run("penalised_euler", 1.0, 1e-4, 0.1, 0.01, 20, n_modes=48)
    ars = _stiff_run("penalised_ars222", 1.0, 1e-4, 0.1, 0.01, 20, n_modes=48)
    for result in (euler, ars):
        assert result["mass_drift"] < 1e-11 and result["T_error"] < 1e-5, result
    # per step, a mode lam of the linearised operator is damped by |1 - lam/r eps| (Euler);
    # the slowest non-conserved modes keep 1e-2 after 20 steps, ARS(2,2,2) damps them faster
    assert euler["distance_to_maxwellian"] < 2e-2, euler
    assert ars["distance_to_maxwellian"] < 1e-3, ars


def test_penalised_schemes_follow_the_stiff_inelastic_temperature_law():
    """e = 0.9, eps = 1e-2, tau = 2.375 (T_inf = 1): RK4 blows up at dt = 0.025; the
    penalised schemes follow the exact law, the second-order one with order-2 error decay."""
    assert _stiff_run("rk4", 0.9, 1e-2, 2.375, 0.025, 40) is None
    errors = {name: [_stiff_run(name, 0.9, 1e-2, 2.375, 1.0 / n, n)["T_error"]
                     for n in (20, 40)] for name in PENALISED}
    assert all(e[1] < 1e-2 for e in errors.values()), errors
    assert errors["penalised_ars222"][0] / errors["penalised_ars222"][1] > 3.0, errors
