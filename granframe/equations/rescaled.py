r"""Free cooling in self-similar variables: the rescaled formulation of Filbet and Rey.

Without a heat bath the inelastic gas cools, and f concentrates towards a Dirac mass
at its mean velocity u: T(t) -> 0 (Haff's law T ~ t^{-2} for hard spheres). On a fixed
grid the spectral solution first loses resolution, then positivity
(``studies/free_cooling.py`` shows when). Writing

.. math:: f(t, v) = \omega(s)^d\, g\big(s,\ u + \omega(s)(v - u)\big),
          \qquad \frac{dt}{ds} = \omega(s)^{\kappa},\quad \kappa = \lambda + 2\gamma,

with the kernel |v - v_*|^\lambda E^\gamma, the collision operator scales as
Q(f, f)(v) = \omega^{d - \kappa} Q(g, g)(\xi) for a speed-independent restitution
coefficient, and g solves

.. math:: \partial_s g = \frac{1}{\varepsilon} Q(g, g)
          - a\, \nabla_\xi \cdot \big((\xi - u)\, g\big), \qquad a = \frac{d \ln \omega}{ds}.

The anti-drift term spreads g at the rate f concentrates. Here a is the constant
a_0 that keeps the energy of g stationary at s = 0,

.. math:: a_0 = \frac{\int Q(g_0, g_0) |\xi - u|^2 d\xi / \varepsilon}
                     {\int \nabla_\xi\cdot((\xi - u) g_0) |\xi - u|^2 d\xi},

evaluated with the discrete operators. Then \omega = e^{a_0 s}, and t(s) is known in
closed form: t = (e^{\kappa a_0 s} - 1)/(\kappa a_0), or t = s for \kappa = 0. For
Maxwell molecules (\kappa = 0) a(g) is independent of g and a_0 is the exact
cooling rate. For \kappa > 0 the temperature of g is attracted to the homogeneous
cooling state (HCS) whose cooling rate is a_0, since a hotter g cools faster.
Then T(t) = T_g(s) / (1 + \kappa a_0 t)^{2/\kappa}: Haff's law, with T_g(s)
converging to the HCS. For \kappa < 0 that state repels, and such kernels are
refused.

A space run takes one scale for the whole interval or rectangle,
f(t, x, v) = \omega^d g(s, x, \omega v) about a gas at rest along every space axis: the
transport becomes \omega^{\kappa - 1} \xi \cdot \nabla_x g (:meth:`Rescaling.transport_time`;
:class:`RescaledBoltzmann` with ``transport_axes``). Its mean velocity is read with the node
-L of each space axis as its two halves, as the fields read it (a sine's data then have
u = 0 along those axes to round-off).

References: F. Filbet, T. Rey, "A rescaling velocity method for dissipative kinetic
equations. Applications to granular media", J. Comput. Phys. 248 (2013) 177-199;
the review (Carrillo, Hu, Ma, Rey), section 3, Test 3.
"""

from __future__ import annotations

import math

import attrs
import numpy

from granframe import validators as check
from granframe.abc import Part
from granframe.backends import to_host
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.model.restitution import is_elastic
from granframe.velocity.moments import FieldMoments


@attrs.frozen
class Rescaling:
    r"""The map between the rescaled run (s, \xi, g) and the physical one (t, v, f).

    Parameters
    ----------
    rate : float
        a_0 = d ln \omega / ds.
    degree : float
        \kappa = \lambda + 2\gamma, the homogeneity of the kernel: dt/ds = \omega^\kappa.
    velocity : tuple of float
        The mean velocity u, a fixed point of the rescaling.
    """

    rate: float
    degree: float
    velocity: tuple = attrs.field(converter=tuple)

    def scale(self, s):
        r"""\omega(s) = exp(a_0 s)."""
        return numpy.exp(self.rate * numpy.asarray(s, dtype=float))

    def physical_time(self, s):
        r"""t(s) = (e^{\kappa a_0 s} - 1)/(\kappa a_0), or s when \kappa a_0 = 0."""
        s = numpy.asarray(s, dtype=float)
        growth = self.degree * self.rate
        return s if growth == 0.0 else numpy.expm1(growth * s) / growth

    def rescaled_time(self, t):
        r"""s(t), the inverse of :meth:`physical_time`."""
        t = numpy.asarray(t, dtype=float)
        growth = self.degree * self.rate
        return t if growth == 0.0 else numpy.log1p(growth * t) / growth

    def transport_time(self, s: float, duration: float) -> float:
        r"""The time of free transport that ``duration`` of s, from s, stands for in a
        rescaled space run: \int_s^{s + \Delta s} \omega^{\kappa - 1} d\sigma.

        With f(t, x, v) = \omega^d g(s, x, \omega v) (mean velocity 0 along the space axes),
        v \cdot \nabla_x f becomes \omega^{\kappa - 1} \xi \cdot \nabla_x g in s, so the
        transport of g over [s, s + \Delta s] is that of the unscaled equation over this
        time: \Delta s itself for hard spheres (\kappa = 1), else
        e^{(\kappa - 1) a_0 s} (e^{(\kappa - 1) a_0 \Delta s} - 1) / ((\kappa - 1) a_0).
        """
        slope = (self.degree - 1.0) * self.rate
        if slope == 0.0:
            return float(duration)
        return float(math.exp(slope * s) * math.expm1(slope * duration) / slope)

    def temperature(self, s, rescaled_temperature):
        r"""T(t(s)) = T_g(s) / \omega(s)^2."""
        return numpy.asarray(rescaled_temperature) / self.scale(s) ** 2

    def physical_fields(self, s, density, velocity, temperature, pressure_tensor,
                        heat_flux) -> dict:
        r"""The fields of f(t(s), x, .) from those of g(s, x, .) (arrays over records and
        cells, ``s`` the records' times): with v = u + (\xi - u)/\omega,

        .. math:: \rho_f = \rho_g,\quad u_f = u + (u_g - u)/\omega,\quad
                  P_f = P_g/\omega^2,\quad T_f = T_g/\omega^2,\quad
                  q_f = q_g/\omega^3,

        and the kinetic energy of every cell \rho_f |u_f|^2/2 + tr P_f / 2; returns
        ``density``, ``velocity``, ``temperature``, ``pressure_tensor``, ``heat_flux``
        and ``energy_density``."""
        omega = self.scale(s).reshape((-1,) + (1,) * (numpy.ndim(density) - 1))
        d = numpy.shape(velocity)[-1]
        mean = numpy.asarray(self.velocity, dtype=float)[:d]
        density = numpy.asarray(density, dtype=float)
        velocity = mean + (numpy.asarray(velocity, dtype=float) - mean) / omega[..., None]
        pressure = numpy.asarray(pressure_tensor, dtype=float) / omega[..., None, None] ** 2
        trace = numpy.trace(pressure, axis1=-2, axis2=-1)
        return {"density": density, "velocity": velocity,
                "temperature": numpy.asarray(temperature, dtype=float) / omega ** 2,
                "pressure_tensor": pressure,
                "heat_flux": numpy.asarray(heat_flux, dtype=float) / omega[..., None] ** 3,
                "energy_density": 0.5 * density * (velocity ** 2).sum(axis=-1) + 0.5 * trace}

    def physical(self, grid, g, s):
        r"""f(t(s), .) on its own grid: returns ``(axes, f)``.

        The physical velocities of the grid points \xi_j are v_j = u + (\xi_j - u)/\omega
        on each axis, and f = \omega^d g there.
        """
        omega = float(self.scale(s))
        points = grid.points()
        axes = [u + (points - u) / omega for u in self.velocity]
        return axes, omega ** grid.dimension * numpy.asarray(g)

    def to_dict(self) -> dict:
        return {"rate": self.rate, "degree": self.degree, "velocity": list(self.velocity)}

    @classmethod
    def from_store(cls, store) -> "Rescaling":
        """The map stored with a rescaled run (a :class:`~granframe.run.storage.RunStore`)."""
        data = store.metadata.get("rescaling")
        if data is None:
            check.reject("Rescaling", "store", str(store.path), "must hold a rescaled run")
        return cls(**data)

    def history(self, store) -> dict:
        r"""The physical history of a rescaled run's records, by name.

        ``s`` and ``time`` (t(s)), ``scale`` (\omega), ``temperature`` (T = T_g/\omega^2),
        ``rescaled_temperature`` (T_g) and the scale-free ``kurtosis``, ``sonine_a2``,
        ``negative_mass_fraction``.
        """
        group = store.group
        s = group["step_time"][:]
        rescaled = group["temperature"][:]
        return {"s": s, "time": self.physical_time(s), "scale": self.scale(s),
                "temperature": self.temperature(s, rescaled), "rescaled_temperature": rescaled,
                **{name: group[name][:] for name in ("kurtosis", "sonine_a2",
                                                     "negative_mass_fraction")}}


def check_rescalable(kernel, restitution, heat_bath: float, owner: str) -> float:
    r"""Refuse a scene the rescaled formulation does not hold for; return \kappa = \lambda + 2\gamma.

    It needs free cooling (no heat bath), a restitution coefficient independent of the
    relative speed (e is then the same at every scale \omega), a power-law kernel and
    \kappa >= 0.
    """
    if heat_bath != 0.0:
        check.reject(owner, "heat_bath", heat_bath,
                     "must be 0 in a rescaled run (the rescaled formulation is for free "
                     "cooling; with a heat bath f reaches a steady state on a fixed grid)")
    if not restitution.is_constant:
        check.reject(owner, "restitution", restitution,
                     "must not depend on the relative speed in a rescaled run (e would "
                     "change with the scale omega); use a constant law, or run the "
                     "unscaled equation")
    from granframe.model.kernels import VariableHardSpheres

    if not isinstance(kernel, VariableHardSpheres):
        check.reject(owner, "kernel", type(kernel).__name__,
                     "must be a power law C |g|^lambda b E^gamma (VariableHardSpheres) in a "
                     "rescaled run: the self-similar scaling needs the exact power lambda, "
                     "which a general CollisionKernel does not have")
    degree = kernel.exponent + 2.0 * kernel.energy_exponent
    if degree < 0.0:
        check.reject(owner, "kernel", kernel,
                     f"has lambda + 2 gamma = {degree:g} < 0; the rescaled formulation "
                     "needs >= 0 (its cooling state repels otherwise)")
    return degree


class SelfSimilarDrift:
    r"""The drift of the rescaled formulation, div((xi - u) chi g), on f of shape
    (..., *grid.shape): any number of distributions at once (the cells of a space run).

    chi(|xi - u|) = 1 up to min(1.5 S, 0.75 L'), then cos^2 down to 0 at L' = L - max|u_j|.
    The taper is needed because (xi - u) jumps across the periodic box. Untapered, the
    spectral discretisation of the drift has eigenvalues with real part up to 2.1, 3.3 and
    4.9 a_0 per axis at N = 32, 64 and 128: growing modes at the faces. Tapered, they reach
    0.56, 0.66 and 0.73 a_0, which the collisional loss term damps. g is small where
    chi < 1, since it keeps the temperature of f0. The divergence is taken spectrally in
    conservation form, so it conserves mass exactly.

    Parameters
    ----------
    grid : VelocityGrid
    backend : ArrayBackend
    velocity : tuple of float
        u, the fixed point of the rescaling.
    """

    def __init__(self, grid, backend, velocity):
        self.grid, self.backend = grid, backend
        self.velocity = tuple(float(u) for u in velocity)
        mesh = [c - u for c, u in zip(grid.mesh(), self.velocity)]
        radius = numpy.sqrt(sum(c * c for c in mesh))
        outer = grid.half_width - max(abs(u) for u in self.velocity)
        inner = min(1.5 * grid.support_radius, 0.75 * outer)
        ramp = numpy.clip((radius - inner) / (outer - inner), 0.0, 1.0)
        taper = numpy.cos(0.5 * math.pi * ramp) ** 2
        self._field = [backend.asarray(taper * c) for c in mesh]
        d = grid.dimension
        factor = math.pi / grid.half_width / float(grid.n_modes) ** d
        derivative = []
        for axis, k in enumerate(grid.half_wavenumbers()):
            symbol = numpy.reshape(1j * factor * k, [-1 if j == axis else 1 for j in range(d)])
            symbol = grid.without_nyquist(numpy.broadcast_to(symbol, grid.half_shape).copy())
            derivative.append(backend.asarray(symbol))
        self._derivative = derivative
        #: |xi - u|^2 h^d on the nodes: the weight of the energy balance that fixes a_0
        self.energy_weight = backend.asarray(radius ** 2 * grid.cell_volume)
        # bound on the spectral radius of the discrete drift per unit rate: sum over axes
        # of max |chi (xi_j - u_j)| times the largest evolved wavenumber
        k_max = math.pi / grid.half_width * (grid.n_modes // 2 - 1)
        self.unit_radius = k_max * sum(float(numpy.max(numpy.abs(taper * c))) for c in mesh)
        self._plans = {}

    def __call__(self, g):
        r"""div((xi - u) chi g) of every distribution in g, spectrally:
        IDFT(sum_j i k_j pi/L DFT((xi_j - u_j) chi g)) over the last d axes."""
        shape = tuple(g.shape)
        fft = self._plans.get(shape)
        if fft is None:
            d = self.grid.dimension
            fft = self._plans[shape] = self.backend.real_fft(
                shape, tuple(range(len(shape) - d, len(shape))), threads=1)
        total = None
        for field, symbol in zip(self._field, self._derivative):
            fft.real[...] = field * g
            term = fft.forward() * symbol
            total = term if total is None else total + term
        fft.spectrum[...] = total
        return fft.inverse().copy()


#: Largest mean velocity along a space axis, relative to the thermal speed, of the cells of
#: a rescaled space run: 1e-10 admits the round-off of f0's samples (a sine's mean) and
#: refuses any flow, whose transport would not scale with the velocities.
DRIFT_TOLERANCE = 1e-10


class RescaledBoltzmann(HomogeneousBoltzmann):
    r"""d_s g = Q(g, g)/eps - a_0 div((xi - u) chi g): free cooling in self-similar
    variables, for one distribution or a batch (the cells of a space run).

    See the module notes for the formulation and :class:`SelfSimilarDrift` for the
    tapered drift chi. One scale \omega(s) = e^{a_0 s} for the whole batch, about the mean
    velocity u of all its distributions, and a_0 the rate that keeps the total energy of
    g stationary at s = 0,

    .. math:: a_0 = \frac{\sum_c \int Q(g_c, g_c) |\xi - u|^2 d\xi / \varepsilon}
                         {\sum_c \int \nabla_\xi\cdot((\xi - u)\chi g_c) |\xi - u|^2 d\xi},

    each sum over every distribution in order (the cells of every process in rank order:
    the same a_0 on any number of processes). u is the mean velocity with the node -L at
    -L, except along the ``transport_axes`` first axes of a space run, where it must
    vanish (to :data:`DRIFT_TOLERANCE` of the thermal speed, the node -L as its halves,
    as the transport carries it), so that the transport stays
    \omega^{\kappa - 1} \xi \cdot \nabla_x g (:meth:`Rescaling.transport_time`). Mass is
    conserved exactly, momentum and energy to the accuracy of the collision operator;
    the drift moves a distribution's momentum towards (1 - a_0 ds) of its deviation from
    u, so a collision step keeps only the mass (with the conservative correction,
    :attr:`invariants`) against round-off.

    Parameters
    ----------
    operator : CollisionOperator
        Its restitution law must not depend on the relative speed (e is the same at
        every scale), and its kernel must have lambda + 2 gamma >= 0.
    initial : array
        g(0) = f0 (backend array), one distribution or a batch (..., *grid.shape): the
        owned cells of a space run; fixes u and a_0.
    knudsen, penalty : float
        As for :class:`~granframe.equations.homogeneous.HomogeneousBoltzmann`.
    dissipation : float, array or None
        int Q(g0, g0) |xi - u|^2 dxi (before the 1/eps) of each distribution of
        ``initial``; None: from the operator, one batched evaluation of Q.
        :func:`granframe.run.problems.time_step_limit` gives it in closed form, to have
        the step limit without the operator.
    communicator : Communicator or None
        The processes whose batches together are all the cells (None: this batch alone).
    transport_axes : int
        The space dimensions of the run (0: space-homogeneous), the velocity axes along
        which u must vanish.
    """

    def __init__(self, operator, initial, knudsen: float = 1.0, penalty: float = 2.0,
                 dissipation=None, communicator=None, transport_axes: int = 0):
        owner = "RescaledBoltzmann"
        degree = check_rescalable(operator.kernel, operator.restitution, 0.0, owner)
        super().__init__(operator, 0.0, knudsen, penalty)
        grid = operator.grid
        if transport_axes > 1:      # the node -L of every space axis read as its halves
            self.moments = FieldMoments(grid, 1.0, operator.backend.xp,
                                        tuple(range(transport_axes)))
        gather = ((lambda part: [part]) if communicator is None
                  else communicator.allgather_object)
        flat = initial.reshape((-1,) + tuple(grid.shape))
        mean = self._mean_velocity(flat, gather, transport_axes, owner)
        check_drift_velocity(operator.kernel, mean, owner, "initial")
        self.drift = SelfSimilarDrift(grid, operator.backend, mean)
        dissipation = (self._weighted(operator(flat)) if dissipation is None
                       else numpy.asarray(dissipation, dtype=float).reshape(-1))
        transport = self._weighted(self.drift(flat))
        dissipation = numpy.concatenate(gather(dissipation))
        transport = numpy.concatenate(gather(transport))
        rate = rescaling_rate(float(dissipation.sum()) / self.knudsen, float(transport.sum()),
                              is_elastic(operator.restitution, grid), owner)
        self.rescaling = Rescaling(rate, degree, mean)
        self._drift_radius = rate * self.drift.unit_radius
        self.invariants = ("mass",) if self.invariants else ()

    def _mean_velocity(self, flat, gather, transport_axes: int, owner: str) -> tuple:
        """u of all the distributions (the class notes), refused where it does not vanish
        along the transport axes: both readings of the node -L from one raw product."""
        raw = to_host(self.moments.raw(flat))
        halves, periodic = (self.moments.fields_of(self.moments.central(raw, node))
                            for node in ("halves", "periodic"))
        rho = numpy.concatenate(gather(halves[0]))
        along, across = (numpy.concatenate(gather(part[0][:, None] * part[1]))
                         for part in (halves, periodic))
        heat = numpy.concatenate(gather(halves[0] * halves[3]))
        thermal = math.sqrt(float(heat.sum() / rho.sum()))
        for axis in range(transport_axes):
            value = float(along[:, axis].sum() / rho.sum())
            if not abs(value) <= DRIFT_TOLERANCE * thermal:
                name = "u_1" if axis == 0 else f"u_{axis + 1}"
                along_axes = "x" if transport_axes == 1 else "x and y"
                check.reject(owner, "initial", f"f0 with mean velocity {name} = {value:.6g}",
                             f"must have mean velocity 0 along {along_axes} (to "
                             f"{DRIFT_TOLERANCE:g} of the thermal speed {thermal:.6g}) in a "
                             "rescaled space run: the transport of g is then "
                             "omega^(kappa - 1) xi . grad_x g; take the frame that moves "
                             "with the gas")
        return ((0.0,) * transport_axes
                + tuple(float(m) for m in across[:, transport_axes:].sum(axis=0) / rho.sum()))

    def _weighted(self, f):
        """int f |xi - u|^2 dxi of every distribution of f (B, *grid.shape), on the host."""
        d = self.operator.grid.dimension
        axes = tuple(range(f.ndim - d, f.ndim))
        return to_host(self.operator.backend.xp.sum(f * self.drift.energy_weight, axis=axes))

    def divergence(self, g):
        r"""div((xi - u) chi g) (:class:`SelfSimilarDrift`)."""
        return self.drift(g)

    def nonlinear(self, t, g):
        drift = self.drift(g) * self.rescaling.rate
        return super().nonlinear(t, g) - drift

    def stiffness(self, g) -> dict:
        """The rates of :class:`HomogeneousBoltzmann` and the drift's, a_0 sum_j max|chi (xi_j -
        u_j)| k_max, a bound on the (imaginary) spectrum of the discrete drift term."""
        return {**super().stiffness(g), Part.DRIFT: self._drift_radius}


def check_drift_velocity(kernel, velocity, owner: str, name: str) -> None:
    """Refuse a mean velocity u != 0 with an energy factor E^gamma in the kernel (E then
    does not scale with omega)."""
    if kernel.energy_exponent != 0.0 and any(abs(u) > 1e-12 for u in velocity):
        check.reject(owner, name, f"f0 with mean velocity {tuple(velocity)}",
                     "must have mean velocity 0 when the kernel has an energy factor E^gamma "
                     "(E = int |v|^2/2 f then does not scale with omega)")


def rescaling_rate(dissipation: float, transport: float, elastic: bool, owner: str) -> float:
    r"""a_0 = dissipation / transport (the module notes), refused unless finite and >= 0:
    the rate of the rescaling, the discrete operator's dissipation of f0 over the drift's
    energy weight (not the cooling rate of a Maxwellian in closed form,
    :func:`granframe.theory.cooling.maxwellian_cooling_rate`); 0 for an ``elastic`` gas
    (:func:`~granframe.model.restitution.is_elastic`), whose dissipation is round-off of
    either sign."""
    rate = 0.0 if elastic or not transport else dissipation / transport
    if not (math.isfinite(rate) and rate >= 0.0):
        check.reject(owner, "initial", "f0",
                     f"gives the cooling rate a_0 = {rate:.6g}; it must be finite and "
                     ">= 0 (f0 must have positive temperature)")
    return rate
