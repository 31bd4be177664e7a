r"""Direct simulation Monte Carlo (DSMC) of the steady normal shock of elastic hard spheres:
an independent reference for the spectral solver's shock profiles.

Nothing here comes from granframe: only NumPy (and :mod:`math`). The scheme is Bird's
(G. A. Bird, *Molecular Gas Dynamics and the Direct Simulation of Gas Flows*, Clarendon
Press, Oxford 1994; "Bird 1994" below, whose chapter 12 treats the normal shock):
simulated particles, each with a position x and three velocity components, move freely
for a time step and then collide in pairs inside their cells by the no-time-counter (NTC)
scheme.

Units and conventions (granframe's): unit particle mass, Boltzmann constant 1 (T is the
energy per unit mass per velocity dimension, p = n T), three velocity dimensions. The
upstream gas has n_1 = 1, T_1 = 1 and the speed u_1 = M c_1 towards +x, c_1 = sqrt(5/3);
lengths are in units of the upstream hard-sphere mean free path

    lambda_1 = 1 / (sqrt(2) n_1 pi sigma_d^2) = 1,   i.e. pi sigma_d^2 = 1/sqrt(2)

(``CROSS_SECTION``), so that nothing depends on the sphere diameter sigma_d; times are in
lambda_1/sqrt(T_1). In granframe's variables (3D hard-sphere kernel |g|/(4 pi), Q/eps)
pi sigma_d^2 = 1/eps, so lambda_1 = eps/sqrt(2) at n_1 = 1.

**Collisions** (NTC, Bird 1994). A simulated particle stands for 1/a real ones per unit
cross-section, a = ``particles_per_cell``/dx the simulated particles per unit length at
n = 1. In a cell of width dx holding N particles the step draws

    M_cand = 1/2 N (N - 1) sigma_T g_max dt / (a dx)

candidate pairs (the fraction by a uniform random number), each uniform among the cell's
distinct pairs, and accepts each with probability |g|/g_max: sigma_T = pi sigma_d^2 is
the hard-sphere total cross-section and g_max the largest relative speed met so far in
the cell (raised when a larger one turns up, like Bird's (sigma_T c_r)_max). Bird 1994
writes N Nbar (Nbar the cell's mean count) for N (N - 1); both have the mean Nbar^2 when
the counts are Poisson, as in a dilute gas, and N (N - 1) needs no running mean. An
accepted pair keeps its centre-of-mass velocity and relative speed, and the relative
velocity takes a direction uniform on the sphere (hard spheres scatter isotropically):
momentum and energy are conserved to round-off. Candidates that share a particle are
processed in rounds (first those whose particles no earlier candidate uses, then the
others with the updated velocities): Bird's one-at-a-time processing of the candidates in
a permuted order, vectorised.

**The shock.** The domain [0, L] is at rest in the shock's frame, and both ends are
inflow reservoirs: every step the upstream Maxwellian (n_1, u_1, T_1) at x = 0 and the
downstream Rankine-Hugoniot Maxwellian (n_2, u_2, T_2) at x = L send in the mean number
of particles of their one-sided fluxes (the fraction carried to the next step), with the
flux-weighted normal velocities (:class:`InflowSampler`) and a random fraction of the
step's flight; particles that leave are removed. Nothing fixes a shock's position between
two such reservoirs: it random-walks with the inflow noise. So every step the particle
count N is held at a target N* by moving all particles by s = (N - N*)/(a (n_2 - n_1))
(the shock's displacement when its plateaus are uniform) and filling the gap s leaves at
an inflow end from that end's reservoir; N* is reset once, after half the transient, so
that the density midpoint sits at ``centre`` x L. After the transient the cell sums of 1,
v_x, v_x^2, |v|^2 and the collisions are accumulated every step into ``batches`` equal
batches; the profiles are n, u, T = (<|v|^2> - u^2)/3 and T_xx = <v_x^2> - u^2 per cell,
and the collision rate per particle.

**Thickness and its error.** lambda_1/delta, delta = (n_2 - n_1)/max dn/dx, is read off
the time-averaged profile by one least-squares polynomial through the points around the
midpoint (:func:`maximum_slope`: the largest of local slopes would be biased upwards by
the noise). Its statistical error is that of batch means, the standard deviation of the
16 batches' values over 4; the jackknife over the batches gives a second error and an
estimate of the estimator's bias (both in :class:`ShockResult`).

**Checks** in :class:`ShockResult`: dx over the shortest local mean free path
1/(sqrt(2) n pi sigma_d^2) = 1/n of the sampled profile (Bird's rule: below 1/3) and dt
times the largest measured collision rate per particle; the ends of the profile against
Rankine-Hugoniot; the difference of the later and earlier halves of the batches (a
transient left over).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy

#: ratio of specific heats of a monatomic gas
GAMMA = 5.0 / 3.0

#: the hard-sphere total cross-section pi sigma_d^2 for which lambda_1 = 1 at n_1 = 1
CROSS_SECTION = 1.0 / math.sqrt(2.0)

#: points of the tabulated inverse cumulative distribution of the inflow normal speeds
INFLOW_TABLE = 20001


# -- Equilibrium theory: Rankine-Hugoniot, fluxes, rates --------------------------------


def rankine_hugoniot(mach: float, gamma: float = GAMMA) -> dict:
    r"""The two states of the steady normal shock in its own frame, upstream n_1 = T_1 = 1.

    Landau & Lifshitz, *Fluid Mechanics*, section 89:
    n_2/n_1 = (gamma + 1) M^2 / ((gamma - 1) M^2 + 2),
    p_2/p_1 = (2 gamma M^2 - (gamma - 1)) / (gamma + 1), T_2 = p_2 / n_2, u_1 = M sqrt(gamma),
    u_2 = u_1 n_1 / n_2.

    Parameters
    ----------
    mach : float
        The upstream Mach number M > 1.
    gamma : float
        The ratio of specific heats (5/3).

    Returns
    -------
    dict
        ``n1``, ``T1``, ``u1``, ``n2``, ``T2``, ``u2``, ``p2``.
    """
    mach = float(mach)
    if not (mach > 1.0 and math.isfinite(mach)):
        raise ValueError(f"rankine_hugoniot: parameter 'mach' = {mach!r} is invalid; must be "
                         "a finite number > 1")
    n2 = (gamma + 1.0) * mach ** 2 / ((gamma - 1.0) * mach ** 2 + 2.0)
    p2 = (2.0 * gamma * mach ** 2 - (gamma - 1.0)) / (gamma + 1.0)
    u1 = mach * math.sqrt(gamma)
    return {"n1": 1.0, "T1": 1.0, "u1": u1, "n2": n2, "T2": p2 / n2, "u2": u1 / n2, "p2": p2}


def mean_relative_speed(temperature: float) -> float:
    r"""<|g|> = 4 sqrt(T/pi) of two particles of unit mass from one Maxwellian at T.

    g = v - v_* is Maxwellian with variance 2T per component (reduced mass 1/2), so its
    mean magnitude is sqrt(8 (2T) / pi) = 4 sqrt(T / pi).
    """
    return 4.0 * math.sqrt(temperature / math.pi)


def collision_frequency(density: float, temperature: float) -> float:
    r"""The equilibrium hard-sphere collision frequency per particle,
    nu = n pi sigma_d^2 <|g|> = n sigma_T 4 sqrt(T/pi) (lambda_1 = 1 units)."""
    return density * CROSS_SECTION * mean_relative_speed(temperature)


def one_sided_flux(density: float, velocity: float, temperature: float) -> float:
    r"""Particles per unit area and time crossing a plane towards +x from the Maxwellian
    (n, u along x, T): n [sqrt(T/(2 pi)) exp(-s^2) + (u/2) (1 + erf s)], s = u/sqrt(2T)
    (Bird 1994, eq. 4.22). The flux towards -x is this with u -> -u."""
    s = velocity / math.sqrt(2.0 * temperature)
    return density * (math.sqrt(temperature / (2.0 * math.pi)) * math.exp(-s * s)
                      + 0.5 * velocity * (1.0 + math.erf(s)))


class InflowSampler:
    r"""Normal speeds w > 0 of the particles a Maxwellian (u along the inflow direction, T)
    sends across a plane: density proportional to w exp(-(w - u)^2 / (2T)).

    With xi = w / sqrt(2T) and s = u / sqrt(2T) the cumulative distribution is exact,

        F(xi) = [exp(-s^2) - exp(-(xi - s)^2) + sqrt(pi) s (erf(xi - s) + erf(s))] / Z,
        Z = exp(-s^2) + sqrt(pi) s (1 + erf s),

    and it is inverted by linear interpolation on ``INFLOW_TABLE`` points up to
    xi = max(s, 0) + 7 (the mass beyond is below 1e-20).
    """

    def __init__(self, velocity: float, temperature: float):
        self.scale = math.sqrt(2.0 * temperature)
        s = velocity / self.scale
        xi = numpy.linspace(0.0, max(s, 0.0) + 7.0, INFLOW_TABLE)
        erf = numpy.frompyfunc(math.erf, 1, 1)
        cdf = (math.exp(-s * s) - numpy.exp(-(xi - s) ** 2)
               + math.sqrt(math.pi) * s * (erf(xi - s).astype(float) + math.erf(s)))
        cdf /= cdf[-1]
        cdf[0] = 0.0
        self.xi, self.cdf = xi, numpy.maximum.accumulate(cdf)

    def __call__(self, rng, count: int):
        return self.scale * numpy.interp(rng.random(count), self.cdf, self.xi)


def maxwellian(rng, count: int, velocity: float, temperature: float):
    """``count`` velocities (count, 3) of the Maxwellian with mean (velocity, 0, 0)."""
    v = rng.standard_normal((count, 3)) * math.sqrt(temperature)
    v[:, 0] += velocity
    return v


# -- Collisions: the no-time-counter scheme -------------------------------------------------


def _first_uses(first, second, particles: int):
    """True for the pairs k whose two particles appear in no pair before k."""
    both = numpy.empty(2 * first.size, dtype=numpy.intp)
    both[0::2], both[1::2] = first, second
    position = numpy.arange(both.size)
    earliest = numpy.full(particles, both.size, dtype=numpy.intp)
    numpy.minimum.at(earliest, both, position)
    seen = earliest[both] == position
    return seen[0::2] & seen[1::2]


def collide(rng, velocities, starts, counts, gmax, coefficient: float, dt: float,
            tally=None) -> int:
    r"""One NTC collision step (Bird 1994) in every cell, in place (module docstring).

    Parameters
    ----------
    rng : numpy.random.Generator
    velocities : ndarray (n, 3) or (n, 4)
        The particles' velocities (the last three columns: rows (x, v_x, v_y, v_z) do),
        sorted by cell: cell c holds rows ``starts[c] : starts[c] + counts[c]``. Changed
        in place.
    starts, counts : ndarray of int
        Each cell's first row and particle count.
    gmax : ndarray of float
        Each cell's running maximum relative speed g_max; raised in place to any larger
        relative speed met among the candidates.
    coefficient : float
        sigma_T / (a dx): candidate pairs per cell are 1/2 N (N-1) coefficient g_max dt.
    dt : float
        The time step.
    tally : ndarray of int, optional
        Collisions per cell, incremented in place.

    Returns
    -------
    int
        The number of collisions.
    """
    expected = 0.5 * counts * (counts - 1.0) * coefficient * gmax * dt
    candidates = numpy.floor(expected + rng.random(counts.size)).astype(numpy.intp)
    candidates[counts < 2] = 0
    total = int(candidates.sum())
    if total == 0:
        return 0
    cell = numpy.repeat(numpy.arange(counts.size), candidates)
    size, start = counts[cell], starts[cell]
    first = (rng.random(total) * size).astype(numpy.intp)
    second = (rng.random(total) * (size - 1)).astype(numpy.intp)
    second += second >= first
    first += start
    second += start
    done = 0
    pending = numpy.arange(total)
    while pending.size:
        free = _first_uses(first[pending], second[pending], velocities.shape[0])
        now, pending = pending[free], pending[~free]
        i, j, c = first[now], second[now], cell[now]
        vi = numpy.take(velocities, i, axis=0)[:, -3:]
        vj = numpy.take(velocities, j, axis=0)[:, -3:]
        g = vi - vj
        speed = numpy.sqrt(numpy.einsum("ij,ij->i", g, g))
        accept = rng.random(now.size) * gmax[c] < speed
        numpy.maximum.at(gmax, c, speed)
        if not accept.any():
            continue
        i, j, c, speed = i[accept], j[accept], c[accept], speed[accept]
        centre = 0.5 * (vi[accept] + vj[accept])
        cos_theta = 2.0 * rng.random(i.size) - 1.0
        sin_theta = numpy.sqrt(1.0 - cos_theta ** 2)
        phi = 2.0 * math.pi * rng.random(i.size)
        half = 0.5 * speed[:, None] * numpy.stack(
            (sin_theta * numpy.cos(phi), sin_theta * numpy.sin(phi), cos_theta), axis=1)
        velocities[i, -3:] = centre + half
        velocities[j, -3:] = centre - half
        done += i.size
        if tally is not None:
            numpy.add.at(tally, c, 1)
    return done


# -- The shock ------------------------------------------------------------------------------


@dataclass
class ShockSettings:
    """The numerical settings of one DSMC shock run (lengths in lambda_1, times in
    lambda_1/sqrt(T_1)).

    Attributes
    ----------
    mach : float
        Upstream Mach number.
    length : float or None
        Domain length L (None: :func:`default_length`).
    cells_per_path : float
        Cells per downstream mean free path lambda_2 = lambda_1 n_1/n_2 (the shortest
        anywhere in the shock): dx = lambda_2 / cells_per_path (3: Bird's lambda/3).
    particles_per_cell : float
        Simulated particles in a cell at the upstream density (n_2/n_1 times more
        downstream).
    dt_fraction : float
        dt = dt_fraction / nu_2, nu_2 the downstream collision frequency (the largest).
    transient, sampling : float or None
        Durations of the transient and of the sampling (None: :func:`default_times`).
    batches : int
        Equal batches of the sampling period (batch means).
    centre : float
        Where the density midpoint is held, as a fraction of L from the upstream end.
    seed : int
    """

    mach: float
    length: float | None = None
    cells_per_path: float = 3.0
    particles_per_cell: float = 60.0
    dt_fraction: float = 0.2
    transient: float | None = None
    sampling: float | None = None
    batches: int = 16
    centre: float = 0.45
    seed: int = 1


def default_length(mach: float) -> float:
    """L in lambda_1: 30 at M = 1.5, 26.5 at M = 2, 24 from M = 2.36 on (at least six
    density thicknesses). At M = 1.5, 2 and 3 the ends of the sampled profiles agree with
    Rankine-Hugoniot to 0.2 %, and lambda_1/delta stayed within its error bars with
    L = 45, 38 and 28."""
    return float(max(24.0, 30.0 - 7.0 * (mach - 1.5)))


def default_times(mach: float, length: float) -> tuple[float, float]:
    """(transient, sampling): the transient 3 L/u_2 (three passages of the downstream gas;
    the step profile it starts from has settled by then), the sampling 40 L/u_2."""
    u2 = rankine_hugoniot(mach)["u2"]
    return 3.0 * length / u2, 40.0 * length / u2


@dataclass
class ShockResult:
    """The time-averaged profiles of a DSMC shock run and lambda_1/delta.

    Attributes
    ----------
    settings : dict
        The run's :class:`ShockSettings`, with the length and times used.
    state : dict
        :func:`rankine_hugoniot`.
    dx, dt : float
        Cell width and time step.
    x : ndarray
        Cell centres, from the density midpoint (normalised density 1/2).
    density, velocity, temperature, temperature_xx, collision_rate : ndarray
        n, u, T, T_xx and the collisions per particle and unit time in each cell.
    batch_density : ndarray (batches, cells)
        n of each batch.
    inverse_thickness, inverse_thickness_error : float
        lambda_1/delta and its batch-means standard error.
    batch_inverse_thickness : ndarray
        lambda_1/delta of each batch.
    jackknife_error, jackknife_bias : float
        The jackknife's (leave one batch out) error and bias of lambda_1/delta.
    cell_over_local_path : float
        max dx n: dx over the shortest local mean free path 1/n (lambda_1 = 1).
    dt_times_local_rate : float
        dt times the largest measured collision rate per particle.
    particles : float
        Mean number of simulated particles while sampling.
    steps, samples, collisions : int
        Time steps in all, steps sampled, collisions while sampling.
    seconds : float
        Wall time.
    shift_rms : float
        Root mean square of the per-step shifts holding the shock in place.
    checks : dict
        :func:`plateau_checks` (relative differences from Rankine-Hugoniot) and
        ``later_minus_earlier_half`` (with its ``_error``): the mean lambda_1/delta of the
        later half of the batches minus that of the earlier half.
    """

    settings: dict
    state: dict
    dx: float
    dt: float
    x: numpy.ndarray
    density: numpy.ndarray
    velocity: numpy.ndarray
    temperature: numpy.ndarray
    temperature_xx: numpy.ndarray
    collision_rate: numpy.ndarray
    batch_density: numpy.ndarray
    inverse_thickness: float
    inverse_thickness_error: float
    batch_inverse_thickness: numpy.ndarray
    jackknife_error: float
    jackknife_bias: float
    cell_over_local_path: float
    dt_times_local_rate: float
    particles: float
    steps: int
    samples: int
    collisions: int
    seconds: float
    shift_rms: float
    checks: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """The result as plain Python (lists for the arrays): for JSON."""
        out = {}
        for key, value in asdict(self).items():
            out[key] = value.tolist() if isinstance(value, numpy.ndarray) else value
        return out


#: the fit behind lambda_1/delta: a Chebyshev series of this degree ...
FIT_DEGREE = 10

#: ... over the points within this many first-estimate thicknesses of the midpoint ...
FIT_HALF_WIDTH = 0.8

#: ... whose slope is maximised over this inner fraction of the fit's window
FIT_INNER = 0.6


def _crossing(x, r, level: float) -> float:
    """The first x where the profile r, rising on the whole, reaches ``level`` (linear
    interpolation between the two points around it)."""
    above = numpy.nonzero(r >= level)[0]
    if above.size == 0 or above[0] == 0:
        return float(x[0] if above.size else x[-1])
    i = int(above[0])
    return float(x[i - 1] + (x[i] - x[i - 1]) * (level - r[i - 1]) / (r[i] - r[i - 1]))


def estimated_thickness(x, normalised) -> float:
    """delta from the 0.2 and 0.8 crossings of the normalised density: their distance
    over atanh(0.6) = 0.693 (exact for a tanh profile)."""
    spread = _crossing(x, normalised, 0.8) - _crossing(x, normalised, 0.2)
    return max(spread, 2.0 * float(x[1] - x[0])) / math.atanh(0.6)


def maximum_slope(x, normalised, degree: int = FIT_DEGREE,
                  half_width: float = FIT_HALF_WIDTH, inner: float = FIT_INNER):
    r"""max dr/dx of a sampled, noisy, rising profile r (0 upstream, 1 downstream).

    A Chebyshev series of ``degree`` is fitted by least squares to the points within
    ``half_width`` x delta_0 of the midpoint r = 1/2 (delta_0 from
    :func:`estimated_thickness`), and its derivative is maximised over the inner
    ``inner`` part of that window. One smooth fit through some 40 points averages the
    noise out: unlike the largest of local (Savitzky-Golay) slopes, whose maximum over
    noisy values is biased upwards by about 1-2 % at the noise of a run here, its
    error is unbiased. Its truncation error, on the Navier-Stokes profiles of M = 1.5 and
    3 sampled at dx = lambda_2/3 and on a tanh profile, is -0.06 % to -0.09 %.

    Returns
    -------
    (float, float)
        The largest slope and where it is.
    """
    x = numpy.asarray(x, dtype=float)
    r = numpy.asarray(normalised, dtype=float)
    delta = estimated_thickness(x, r)
    middle = _crossing(x, r, 0.5)
    window = numpy.abs(x - middle) <= half_width * delta
    if numpy.count_nonzero(window) < degree + 4:
        raise ValueError(f"maximum_slope: {numpy.count_nonzero(window)} points within "
                         f"{half_width:g} thicknesses of the midpoint; a fit of degree "
                         f"{degree} needs {degree + 4}")
    scale = half_width * delta
    fit = numpy.polynomial.Chebyshev.fit((x[window] - middle) / scale, r[window], degree,
                                         domain=[-1.0, 1.0])
    slope = fit.deriv()
    t = numpy.linspace(-inner, inner, 1201)
    values = slope(t)
    k = int(numpy.argmax(values))
    return float(values[k] / scale), float(middle + t[k] * scale)


def inverse_density_thickness(x, density, n1: float, n2: float) -> float:
    r"""lambda_1/delta with delta = (n_2 - n_1) / max dn/dx (lengths in lambda_1): the
    largest slope of the normalised density (n - n_1)/(n_2 - n_1) by
    :func:`maximum_slope`."""
    r = (numpy.asarray(density, dtype=float) - n1) / (n2 - n1)
    return maximum_slope(x, r)[0]


class Reservoir:
    """One end's Maxwellian reservoir: what it sends in each step, and a gap's filling.

    Parameters
    ----------
    density, velocity, temperature : float
        The Maxwellian (n, u along x, T).
    inward : float
        +1 for the end at x = 0 (particles enter moving towards +x), -1 for x = L.
    per_length : float
        a, simulated particles per unit length at n = 1.
    dt : float
        The time step.

    The mean counts (one-sided flux x a x dt per step, n a x width per gap) are made
    whole by carrying the fractions to the next call.
    """

    def __init__(self, density, velocity, temperature, inward: float, per_length: float,
                 dt: float):
        self.density, self.velocity, self.temperature = density, velocity, temperature
        self.inward = inward                                  # +1 at x = 0, -1 at x = L
        self.flux = one_sided_flux(density, inward * velocity, temperature)
        self.per_step = self.flux * per_length * dt
        self.per_length = per_length
        self.sampler = InflowSampler(inward * velocity, temperature)
        self.remainder = 0.0
        self.fill_remainder = 0.0

    def _count(self, mean: float, attribute: str) -> int:
        total = mean + getattr(self, attribute)
        count = int(total)
        setattr(self, attribute, total - count)
        return count

    def inflow(self, rng, boundary: float, dt: float):
        """Particles entering this step, rows (x, v_x, v_y, v_z): flux-weighted normal
        speeds, a random fraction of the step's flight from the boundary."""
        count = self._count(self.per_step, "remainder")
        rows = numpy.empty((count, 4))
        rows[:, 1:] = maxwellian(rng, count, 0.0, self.temperature)
        rows[:, 1] = self.inward * self.sampler(rng, count)
        rows[:, 0] = boundary + rows[:, 1] * dt * rng.random(count)
        return rows

    def fill(self, rng, low: float, high: float):
        """Equilibrium particles uniform in [low, high), rows (x, v_x, v_y, v_z)."""
        count = self._count(self.density * self.per_length * (high - low), "fill_remainder")
        rows = numpy.empty((count, 4))
        rows[:, 0] = low + (high - low) * rng.random(count)
        rows[:, 1:] = maxwellian(rng, count, self.velocity, self.temperature)
        return rows


def run_shock(settings: ShockSettings, initial=None, progress=None) -> ShockResult:
    r"""Run the DSMC of the steady shock of ``settings`` and sample its profiles.

    Parameters
    ----------
    settings : ShockSettings
    initial : tuple of arrays (x, n, u, T), optional
        A profile to start from (x measured from its density midpoint, as
        :attr:`ShockResult.x`): local Maxwellians interpolated from it, placed with the
        midpoint at ``centre`` L. By default a tanh step of width L/8 between the
        Rankine-Hugoniot states (n from it, u = n_1 u_1 / n, T linear in n).
    progress : callable, optional
        Called as progress(text) a few times during the run.

    Returns
    -------
    ShockResult
    """
    began = time.perf_counter()
    mach = float(settings.mach)
    state = rankine_hugoniot(mach)
    n1, u1, T1, n2, u2, T2 = (state[k] for k in ("n1", "u1", "T1", "n2", "u2", "T2"))
    length = float(settings.length or default_length(mach))
    transient, sampling = default_times(mach, length)
    transient = float(settings.transient if settings.transient is not None else transient)
    sampling = float(settings.sampling if settings.sampling is not None else sampling)
    dx_target = (n1 / n2) / settings.cells_per_path
    cells = math.ceil(length / dx_target)
    dx = length / cells
    per_length = settings.particles_per_cell / dx          # a: simulated per unit length at n = 1
    dt = settings.dt_fraction / collision_frequency(n2, T2)
    coefficient = CROSS_SECTION / (per_length * dx)
    rng = numpy.random.default_rng(settings.seed)
    left = Reservoir(n1, u1, T1, +1.0, per_length, dt)
    right = Reservoir(n2, u2, T2, -1.0, per_length, dt)
    target = settings.centre * length

    # initial particles: local Maxwellians of a profile
    grid = (numpy.arange(cells) + 0.5) * dx
    if initial is None:
        r = 0.5 * (1.0 + numpy.tanh((grid - target) / (length / 16.0)))
        n_init = n1 + (n2 - n1) * r
        u_init = n1 * u1 / n_init
        t_init = T1 + (T2 - T1) * r
    else:
        xi, ni, ui, ti = (numpy.asarray(a, dtype=float) for a in initial)
        n_init = numpy.interp(grid - target, xi, ni, left=n1, right=n2)
        u_init = numpy.interp(grid - target, xi, ui, left=u1, right=u2)
        t_init = numpy.interp(grid - target, xi, ti, left=T1, right=T2)
    counts = rng.poisson(n_init * per_length * dx)
    cell_of = numpy.repeat(numpy.arange(cells), counts)
    gas = numpy.empty((cell_of.size, 4))                  # rows (x, v_x, v_y, v_z)
    gas[:, 0] = (cell_of + rng.random(cell_of.size)) * dx
    gas[:, 1:] = rng.standard_normal((cell_of.size, 3)) * numpy.sqrt(t_init[cell_of])[:, None]
    gas[:, 1] += u_init[cell_of]
    cell = cell_of.astype(numpy.int32)
    wanted = float(numpy.sum(n_init) * per_length * dx)     # N*
    jump = per_length * (n2 - n1)

    gmax = 5.0 * numpy.sqrt(2.0 * numpy.maximum(t_init, T1))
    steps_transient = math.ceil(transient / dt)
    batch_steps = max(1, math.ceil(sampling / dt / settings.batches))
    steps = steps_transient + batch_steps * settings.batches
    recentre_at = steps_transient // 2
    moments = numpy.zeros((settings.batches, 5, cells))   # count, vx, vx^2, |v|^2, collisions
    warm = numpy.zeros((cells,))
    warm_steps = 0
    shifts = []
    collisions = 0
    particles = 0.0
    tally = numpy.zeros(cells, dtype=numpy.int64)
    sort_type = numpy.int16 if cells < 32000 else numpy.int32
    for step in range(steps):
        # hold the particle count N at N*, hence the shock in place: all particles move by
        # the shift s after their free flight, and the gap s leaves at an inflow end is
        # filled from that end's reservoir. Particles outside [0, L) after the flight or
        # after the shift leave; the reservoirs' particles enter, then are shifted too.
        shift = (gas.shape[0] - wanted) / jump
        if step >= steps_transient:
            shifts.append(shift)
        x = gas[:, 0]
        x += gas[:, 1] * dt
        inside = (x >= max(0.0, -shift)) & (x < min(length, length - shift))
        x += shift
        new = [left.inflow(rng, 0.0, dt), right.inflow(rng, length, dt)]
        for rows in new:
            rows[:, 0] += shift
        if shift > 0.0:
            new.append(left.fill(rng, 0.0, min(shift, length)))
        elif shift < 0.0:
            new.append(right.fill(rng, max(length + shift, 0.0), length))
        new = numpy.concatenate(new)
        new_inside = (new[:, 0] >= 0.0) & (new[:, 0] < length)
        # index by cell; the particles that left sort last (cell = cells) and are dropped
        gas = numpy.concatenate((gas, new))
        cell = numpy.minimum((gas[:, 0] * (1.0 / dx)).astype(numpy.int32), cells - 1)
        kept = numpy.concatenate((inside, new_inside))
        cell[~kept] = cells
        order = numpy.argsort(cell.astype(sort_type), kind="stable")[:numpy.count_nonzero(kept)]
        gas, cell = numpy.take(gas, order, axis=0), cell[order]
        count = numpy.bincount(cell, minlength=cells)
        starts = numpy.concatenate(([0], numpy.cumsum(count)[:-1]))
        sampling_now = step >= steps_transient
        tally[:] = 0
        collisions_now = collide(rng, gas, starts, count, gmax, coefficient, dt,
                                 tally if sampling_now else None)
        if sampling_now:
            b = (step - steps_transient) // batch_steps
            m = moments[b]
            vx = gas[:, 1].copy()
            m[0] += count
            m[1] += numpy.bincount(cell, vx, minlength=cells)
            vx *= vx
            m[2] += numpy.bincount(cell, vx, minlength=cells)
            vx += gas[:, 2] ** 2
            vx += gas[:, 3] ** 2
            m[3] += numpy.bincount(cell, vx, minlength=cells)
            m[4] += tally
            collisions += collisions_now
            particles += gas.shape[0]
        elif step >= recentre_at:
            warm += count
            warm_steps += 1
            if step == steps_transient - 1:
                # place the density midpoint of the late transient at the target
                r = (warm / (warm_steps * per_length * dx) - n1) / (n2 - n1)
                wanted += jump * (_crossing(grid, r, 0.5) - target)
        if progress is not None and (step + 1) % max(1, steps // 5) == 0:
            progress(f"M = {mach:g}: step {step + 1}/{steps}, {gas.shape[0]} particles, "
                     f"{time.perf_counter() - began:.0f} s")

    def profiles(m, samples):
        count = numpy.maximum(m[0], 1.0)
        n = m[0] / (samples * per_length * dx)
        u = m[1] / count
        txx = m[2] / count - u ** 2
        t = (m[3] / count - u ** 2) / 3.0
        rate = 2.0 * m[4] / count / dt                    # collisions per particle and time
        return n, u, t, txx, rate

    total = moments.sum(axis=0)
    b = settings.batches
    n, u, t, txx, rate = profiles(total, batch_steps * b)
    inverse = inverse_density_thickness(grid, n, n1, n2)
    batch_density = numpy.array([profiles(m, batch_steps)[0] for m in moments])
    each = numpy.array([inverse_density_thickness(grid, nb, n1, n2) for nb in batch_density])
    error = float(each.std(ddof=1) / math.sqrt(b))
    rest = numpy.array([inverse_density_thickness(
        grid, profiles(total - m, batch_steps * (b - 1))[0], n1, n2) for m in moments])
    jack_error = float(math.sqrt((b - 1) / b * numpy.sum((rest - rest.mean()) ** 2)))
    jack_bias = float((b - 1) * (rest.mean() - inverse))
    midpoint = _crossing(grid, (n - n1) / (n2 - n1), 0.5)
    seen = n > 0
    halves = each[: b // 2], each[b // 2:]
    checks = plateau_checks(grid - midpoint, n, u, t, state)
    checks["later_minus_earlier_half"] = float(halves[1].mean() - halves[0].mean())
    checks["later_minus_earlier_half_error"] = float(math.sqrt(
        halves[0].var(ddof=1) / halves[0].size + halves[1].var(ddof=1) / halves[1].size))
    return ShockResult(
        settings=asdict(settings) | {"length": length, "transient": transient,
                                     "sampling": sampling},
        state=state, dx=dx, dt=dt, x=grid - midpoint, density=n, velocity=u, temperature=t,
        temperature_xx=txx, collision_rate=rate, batch_density=batch_density,
        inverse_thickness=inverse, inverse_thickness_error=error,
        batch_inverse_thickness=each, jackknife_error=jack_error, jackknife_bias=jack_bias,
        cell_over_local_path=float(numpy.max(dx * n[seen])),
        dt_times_local_rate=float(numpy.max(rate[seen]) * dt),
        particles=particles / max(1, batch_steps * b), steps=steps,
        samples=batch_steps * b, collisions=collisions,
        seconds=time.perf_counter() - began,
        shift_rms=float(numpy.sqrt(numpy.mean(numpy.square(shifts)))) if shifts else 0.0,
        checks=checks)


def plateau_checks(x, n, u, t, state: dict, margin: float = 1.0) -> dict:
    r"""The sampled profile at its two ends against Rankine-Hugoniot: the mean of n, u, T
    over the first and the last 10 % of the domain (``margin`` lambda_1 from each
    boundary left out), relative to the RH values."""
    span = x[-1] - x[0]
    low = (x >= x[0] + margin) & (x <= x[0] + 0.1 * span + margin)
    high = (x <= x[-1] - margin) & (x >= x[-1] - 0.1 * span - margin)
    out = {}
    for name, values, key1, key2 in (("n", n, "n1", "n2"), ("u", u, "u1", "u2"),
                                     ("T", t, "T1", "T2")):
        out[f"{name}1"] = float(numpy.mean(values[low]) / state[key1] - 1.0)
        out[f"{name}2"] = float(numpy.mean(values[high]) / state[key2] - 1.0)
    return out
