"""The contracts of granframe: what every implementation of a family provides.

One class per family that plugins extend (docs/plugins.md): collision operators, restitution
laws, quadratures, array backends and their transforms, equations, time integrators and
initial conditions. Implementations live in the topic packages (:mod:`granframe.model`,
:mod:`granframe.velocity`, :mod:`granframe.stepping`, :mod:`granframe.equations`) and in the
plugins; :mod:`granframe.testing` checks an implementation against its contract.
"""

from __future__ import annotations

import abc
import contextlib
import contextvars
import enum
import math
import time
from types import ModuleType
from typing import ClassVar

import numpy

from granframe import validators as check
from granframe.rules import antipodal_pairs, circle_rule, gauss_legendre


# -- The stiff parts of an equation ---------------------------------------------------------


class Part(enum.StrEnum):
    """The names of an equation's stiff parts (:meth:`Equation.stiffness`,
    :attr:`TimeIntegrator.explicit_parts`, :mod:`granframe.stepping.stability`).

    A :class:`enum.StrEnum`: each member is its string (``Part.LINEAR == "linear"``, and it
    formats and is stored as ``"linear"``), so plain strings of the names keep working.
    """

    #: the heat bath tau Delta_v
    LINEAR = "linear"
    #: the collision term Q/eps
    NONLINEAR = "nonlinear"
    #: the energy dissipation of Q/eps (a part of the collision term)
    DISSIPATION = "dissipation"
    #: the drift of the rescaled formulation (an imaginary spectrum)
    DRIFT = "drift"


# -- Array backends and their transforms ---------------------------------------------------

#: Supported precisions: real dtype and its complex counterpart.
PRECISIONS = {"float64": ("float64", "complex128"), "float32": ("float32", "complex64")}


class ArrayBackend:
    """Interface of an array backend.

    Attributes
    ----------
    name : str
        Registry name.
    xp : module
        NumPy-compatible array namespace used by operators for every array.

    Methods ``fftn``, ``ifftn``, ``rfftn`` and ``irfftn`` follow the
    :mod:`numpy.fft` conventions (unnormalised forward, 1/n inverse) over the
    given ``axes``; ``asarray`` moves data onto the backend's device,
    ``to_numpy`` back to host memory, and ``synchronize`` waits for queued
    work (a no-op on the CPU) so that timings are honest.

    For hot loops, :meth:`real_fft` returns a reusable :class:`RealFFT` with
    its own buffers, and ``concurrency`` says how many such pipelines the
    backend runs well side by side (CPU threads, each pipeline with
    single-threaded transforms; 1 on a GPU).

    Spectral operators multiply spectra by separable (per-axis) phase factors
    many times per evaluation. :meth:`separable_product` and
    :meth:`lowrank_accumulate` are those element-wise steps, written here once
    in ``xp``; a backend may override them with fused kernels (one pass over
    memory instead of several) that must give the same result to round-off.
    """

    name: str
    xp: ModuleType
    concurrency: int = 1
    #: Bytes of spectra an operator pipeline transforms in one batch (the fast operator's
    #: batch size aims at it). On a CPU a batch should stay in cache: 3D, 2 pipelines,
    #: 1 MiB -> 4 MiB took N = 16 from 3.6 to 3.1 ms and N = 32 from 30 to 25 ms, and
    #: larger batches fell out of cache. A GPU backend sets it large, so that each
    #: transform and kernel launch covers many pairs.
    batch_bytes: int = 4 * 2 ** 20

    def real_fft(self, shape, axes, threads: int = 1, precision: str = "float64") -> "RealFFT":
        """A planned real transform pair over ``axes`` of arrays of ``shape``, in
        ``precision`` (a key of :data:`PRECISIONS`)."""
        return RealFFT(self, tuple(shape), tuple(axes), precision=precision)

    def asarray(self, a, dtype=None):
        return self.xp.asarray(a, dtype=dtype)

    def to_numpy(self, a) -> numpy.ndarray:
        return numpy.asarray(a)

    def synchronize(self) -> None:
        """Block until queued work is done (no-op on CPU backends)."""

    def elapsed(self, function) -> float:
        """Seconds one call of ``function`` takes, its queued work included (host clock and
        :meth:`synchronize`; a device backend may time with device events instead)."""
        start = time.perf_counter()
        function()
        self.synchronize()
        return time.perf_counter() - start

    #: whether the arrays live in device memory, where every copy to the host (``float``
    #: of a reduction, a check's flag) waits for the queued work: such copies are kept out
    #: of the steps of a run
    on_device: bool = False

    def device_memory(self) -> int | None:
        """Bytes of device memory the backend holds; None for host backends."""
        return None

    def for_process(self, local_rank: int) -> "ArrayBackend":
        """The backend of the process ``local_rank`` among the processes of a run on this
        host (:attr:`Communicator.local_rank`): a device backend gives each process its own
        device (local rank modulo the devices); a host backend is shared as it is."""
        return self

    def separable_product(self, out, spectrum, head, tail):
        r"""Batch of spectra times separable factors, into ``out``.

        .. math:: \mathrm{out}_{d,b,i,j} = S_{d,i,j}\, h_{b,i}\, t_{b,j}

        with ``spectrum`` S of shape (D, I, J), ``head`` h (B, I), ``tail`` t
        (B, J) and ``out`` (D, B, I, J), all complex: every one of D spectra
        (distributions) times every one of B factors. Without the leading D axis
        (S of shape (I, J), ``out`` (B, I, J)) it is the case D = 1. Returns ``out``.
        """
        self.xp.multiply(spectrum[..., None, :, :], tail[:, None, :], out=out)
        out *= head[:, :, None]
        return out

    def lowrank_accumulate(self, acc, heads, tails, values):
        r"""Add low-rank-weighted batches of spectra into per-group accumulators.

        .. math:: \mathrm{acc}_{d,q,i,j} \mathrel{+}= \sum_{b \in q} \Big(\sum_t
           H_{b,i,t} T_{b,t,j}\Big) V_{d,b,i,j}

        with ``acc`` (D, Q, I, J), ``heads`` H (B, I, R), ``tails`` T (B, R, J) and
        ``values`` V (D, B, I, J), all complex: the weights are shared by the D
        distributions. Group q holds the consecutive batch entries
        b = q B/Q, ..., (q+1) B/Q - 1. Without the leading D axis (``acc`` (Q, I, J),
        ``values`` (B, I, J)) it is the case D = 1. ``values`` may be overwritten.
        Returns ``acc``.
        """
        values *= self.xp.matmul(heads, tails)
        groups, rows, cols = acc.shape[-3:]
        acc += values.reshape(values.shape[:-3] + (groups, -1, rows, cols)).sum(axis=-3)
        return acc

    def fftn(self, a, axes=None):
        raise NotImplementedError

    def ifftn(self, a, axes=None):
        raise NotImplementedError

    def rfftn(self, a, axes=None):
        raise NotImplementedError

    def irfftn(self, a, s, axes=None):
        raise NotImplementedError


class RealFFT:
    """Planned real-to-complex transform pair with buffers, reused across calls.

    Write the real input into ``real`` and call :meth:`forward`, or the
    half spectrum into ``spectrum`` and call :meth:`inverse`. Both return the
    result array, which may be a buffer of the plan (valid until the next
    call) or a new array; either may overwrite its input. Both directions are
    *unnormalised*: ``forward`` gives X_k = sum_j x_j exp(-2 pi i j.k/N) and
    ``inverse`` gives x_j = sum_k X_k exp(+2 pi i j.k/N), i.e. numpy's
    ``irfftn`` times the number of points; callers fold the 1/N^d into their
    own factors instead of paying an extra pass. This generic version calls
    the backend's ``rfftn``/``irfftn``; backends with real planners (FFTW,
    cuFFT) override it. The buffers have the real and complex dtypes of
    ``precision``; the backend's transforms must preserve them.
    """

    def __init__(self, backend: ArrayBackend, shape: tuple, axes: tuple, zeros=None,
                 precision: str = "float64"):
        zeros = backend.xp.zeros if zeros is None else zeros   # e.g. an aligned allocator
        self.backend, self.shape, self.axes = backend, shape, axes
        half = list(shape)
        half[axes[-1]] = shape[axes[-1]] // 2 + 1
        real, complex_ = PRECISIONS[precision]
        self.real = zeros(shape, dtype=real)
        self.spectrum = zeros(tuple(half), dtype=complex_)
        self._sizes = tuple(shape[a] for a in axes)

    def forward(self):
        return self.backend.rfftn(self.real, axes=self.axes)

    def inverse(self):
        return self.backend.irfftn(self.spectrum, s=self._sizes, axes=self.axes) * self._count

    @property
    def _count(self) -> int:
        return int(numpy.prod(self._sizes))


# -- Restitution laws ----------------------------------------------------------------------

class RestitutionLaw(abc.ABC):
    """A restitution coefficient e(r) of the relative speed r = |v - v_*|.

    An implementation provides :meth:`_evaluate`, vectorised over a NumPy array of speeds,
    with values in [0, 1] of the array's shape, and sets ``is_constant`` when e does not
    depend on r (operators then evaluate it once). :meth:`__call__` refuses speeds that
    are negative or not finite before calling it. The framework checks a law where it is
    built by name (values in [0, 1], finite, of the input's shape, at zero, small and
    large speeds) and where an operator receives it (:class:`CollisionOperator`).
    """

    is_constant: bool = False

    def __call__(self, speed):
        speed = numpy.asarray(speed, dtype=float)
        if speed.size and not (numpy.all(numpy.isfinite(speed)) and speed.min() >= 0.0):
            check.reject(type(self).__name__, "speed", speed,
                         "relative speeds must be finite and >= 0")
        with numpy.errstate(divide="ignore", over="ignore", invalid="ignore"):
            return self._evaluate(speed)

    @abc.abstractmethod
    def _evaluate(self, speed):
        """e at the speeds ``speed`` (a float array, finite and >= 0), an array of its shape."""


# -- Quadratures ---------------------------------------------------------------------------

class Quadrature(abc.ABC):
    """A quadrature rule; radial rules provide ``rule(radius)``, surface rules subclass
    :class:`SurfaceQuadrature`.

    An implementation provides ``kind``, :attr:`degree` and :attr:`n_points`; a radial
    rule (``kind = "radial"``) provides ``rule(radius)``, the nodes and weights on
    [0, radius]. The framework checks a rule where it is built by name: finite nodes and
    weights, ``n_points`` of them, and for surface rules unit nodes and weights summing
    to |S^{d-1}|.

    Attributes
    ----------
    kind : {"radial", "circle", "sphere"}
        The domain: an interval [0, R], S^1, or S^2.
    degree : int
        Highest total degree of polynomials integrated exactly.
    n_points : int
        Number of nodes.
    """

    kind: ClassVar[str]

    @property
    @abc.abstractmethod
    def degree(self) -> int:
        """Highest total degree of polynomials the rule integrates exactly."""

    @property
    @abc.abstractmethod
    def n_points(self) -> int:
        """Number of nodes."""


class SurfaceQuadrature(Quadrature):
    """A rule on the unit sphere S^{d-1}: ``nodes()`` (M, d), ``weights()`` (M,).

    An implementation provides ``dimension`` and :meth:`_rule`, returning unit nodes of
    shape (M, d) and weights of shape (M,) that sum to |S^{d-1}| (2 pi, 4 pi).
    """

    #: Dimension d of the ambient space (2 for the circle, 3 for the sphere).
    dimension: ClassVar[int]

    def nodes(self):
        return self._rule()[0]

    def weights(self):
        return self._rule()[1]

    @property
    def is_antipodal(self) -> bool:
        """True when -ghat is a node of equal weight for every node ghat."""
        _, w_plus, w_minus = antipodal_pairs(*self._rule())
        return bool(numpy.allclose(w_plus, w_minus, rtol=1e-12, atol=0.0))

    @abc.abstractmethod
    def _rule(self):
        """``(nodes, weights)``: unit nodes (M, d) and weights (M,) summing to |S^{d-1}|."""


# -- Initial conditions --------------------------------------------------------------------

class InitialCondition(abc.ABC):
    """f0 on a velocity grid."""

    @abc.abstractmethod
    def sample(self, grid) -> numpy.ndarray:
        """f0 at the grid points, shape ``grid.shape``."""

    @property
    def intended_mass(self) -> float | None:
        """The mass f0 carries on the whole space, or ``None`` when not known."""
        return None


# -- Equations and time integrators --------------------------------------------------------

class Equation(abc.ABC):
    """df/dt = N(t, f) + L f with L linear and cheap to exponentiate."""

    @abc.abstractmethod
    def nonlinear(self, t: float, f):
        """N(t, f)."""

    @abc.abstractmethod
    def linear(self, f):
        """L f."""

    @abc.abstractmethod
    def propagate(self, f, dt: float):
        """exp(dt L) f."""

    def __call__(self, t: float, f):
        """The whole right-hand side N(t, f) + L f."""
        return self.nonlinear(t, f) + self.linear(f)

    def stiffness(self, f) -> dict:
        """Estimated spectral radii of the parts of the equation at f, by part name
        (``linear``, ``nonlinear``, ``dissipation``): what explicit step limits are
        computed from (:mod:`granframe.stepping.stability`). None known by default."""
        return {}

    def relaxation(self, f):
        r"""A relaxation P(f) = r (M[f] - f) that penalised schemes treat implicitly.

        Returns ``(r, M)``: a rate r >= 0 of the size of the stiff part's Lipschitz
        constant and a target M[f] that P leaves invariant, M[f + s (M[f] - f)] = M[f]
        for every s, so that the implicit stage f = g + a dt P(f) has the explicit
        solution (g + a dt r M[g]) / (1 + a dt r). The default, ``(0.0, f)``, has no
        penalisation: the penalised schemes are then their explicit parts.
        """
        return 0.0, f


class TimeIntegrator(abc.ABC):
    """One step f(t) -> f(t + dt) of a one-step method.

    Attributes
    ----------
    order : int
        Classical order p: the global error is O(dt^p).
    adaptive : bool
        True for schemes with an embedded error estimate
        (:class:`AdaptiveIntegrator`); the runner then controls the step.
    explicit_parts : frozenset of str
        Which stiff parts of an equation (:meth:`Equation.stiffness`) the scheme
        treats explicitly, so that dt rate must stay within ``stability_interval``.
    stability_interval : float
        Extent of the scheme's (explicit part's) stability region along the negative
        real axis: stable for dt lambda in [-stability_interval, 0].
    imaginary_interval : float
        Extent along the imaginary axis: stable for dt lambda in i[-b, b] with b this
        value; 0 for schemes unstable there at any step (forward Euler, two-stage
        second-order schemes). Transport terms (the drift of the rescaled
        formulation, :mod:`granframe.equations.rescaled`) have an imaginary spectrum.
    """

    order: ClassVar[int]
    adaptive: ClassVar[bool] = False
    explicit_parts: ClassVar[frozenset] = frozenset({Part.LINEAR, Part.NONLINEAR, Part.DRIFT})
    stability_interval: ClassVar[float] = math.inf
    imaginary_interval: ClassVar[float] = 0.0

    @abc.abstractmethod
    def step(self, equation: Equation, t: float, f, dt: float):
        """Return f(t + dt); ``f`` is not modified."""


class AdaptiveIntegrator(TimeIntegrator):
    """A scheme with an embedded lower-order solution for step-size control.

    Attributes
    ----------
    embedded_order : int
        Order q of the embedded solution; the error estimate is O(dt^{q+1}).
    """

    adaptive: ClassVar[bool] = True
    embedded_order: ClassVar[int]

    @abc.abstractmethod
    def attempt(self, equation: Equation, t: float, f, dt: float):
        """Return ``(f_new, error)``: the step of order p and the difference to the embedded one."""

    def step(self, equation, t, f, dt):
        return self.attempt(equation, t, f, dt)[0]


# -- Collision kernels ---------------------------------------------------------------------

class CollisionKernel(abc.ABC):
    r"""A collision kernel B(|g|, cos theta, E) = C s(|g|) b(cos theta) phi(E).

    C is :meth:`prefactor`, s the speed part, b the angular part and phi the energy
    factor of the kinetic energy E = int |v|^2/2 f dv. The operators, the step limits
    and the run planner read a kernel only through these members.

    An implementation must provide :meth:`prefactor`, :meth:`speed_part` (finite and
    >= 0, vectorised in any array namespace ``xp``) and :attr:`speed_exponent`, an upper
    bound lambda of its growth: s(r) <= s_1 max(1, r)^lambda for some constant s_1
    (the power of a power law; growth and cost estimates use it). The other members
    have defaults: isotropic scattering (b = 1), no energy dependence, not Maxwell
    molecules, and numerical angular integrals, maxima and Maxwellian averages of s. A
    kernel with an angular part overrides :meth:`angular_part` and sets
    ``is_isotropic`` False; one whose speed part is constant sets ``is_maxwellian``.
    The framework checks a kernel where it is built by name: positive finite values of
    the speed and angular parts and of the prefactor, and an isotropy flag that agrees
    with the angular part; operators accept only instances of this class.

    Attributes
    ----------
    is_isotropic : bool
        True when b is constant (operators then skip the angular quadrature).
    is_maxwellian : bool
        True when s is constant (Maxwell pseudo-molecules; exact laws exist).
    energy_exponent : float
        gamma of phi(E) = E^gamma (0: no energy dependence); :meth:`energy_factor`
        computes phi.
    """

    is_isotropic: bool = True
    is_maxwellian: bool = False
    energy_exponent: float = 0.0

    @abc.abstractmethod
    def prefactor(self, dimension: int) -> float:
        """The constant C used in dimension ``dimension`` (2 or 3), > 0."""

    @abc.abstractmethod
    def speed_part(self, speed, xp=numpy):
        """s(|g|) at the speeds ``speed`` (an array of ``xp``), an array of its shape."""

    @property
    @abc.abstractmethod
    def speed_exponent(self) -> float:
        """An upper bound lambda of the growth of s: s(r) <= s_1 max(1, r)^lambda."""

    def angular_part(self, cos_theta):
        """b(cos theta) for a NumPy array of cos theta in [-1, 1]; 1 by default."""
        return numpy.ones_like(numpy.asarray(cos_theta, dtype=float))

    def angular_integral(self, dimension: int, weight=None) -> float:
        """int_{S^{d-1}} b(cos theta) w(cos theta) dsigma (w = 1 when ``weight`` is None).

        In 2D the trapezoidal rule on 2048 equispaced angles (the largest
        :class:`~granframe.velocity.quadratures.CircleTrapezoid`; spectral for smooth b); in
        3D 2 pi times the 200-point Gauss-Legendre rule in cos theta. |S^{d-1}| for b = 1.
        """
        if dimension == 2:
            nodes, w = circle_rule(2048)
            t = nodes[:, 0]
        else:
            nodes, w = gauss_legendre(200, 2.0)
            t, w = nodes - 1.0, 2 * math.pi * w
        values = self.angular_part(t) * (1.0 if weight is None else weight(t))
        return float(w @ values)

    def largest_speed_part(self, radius: float) -> float:
        """max s(r) over r in [0, ``radius``] (relative speeds are cut at the grid's R);
        by default the largest of 257 equispaced samples."""
        return float(numpy.max(self.speed_part(numpy.linspace(0.0, radius, 257))))

    def mean_speed_part(self, dimension: int, temperature: float) -> float:
        r"""<s(|g|)> over the relative velocities g of two particles of a Maxwellian at
        ``temperature``: g is Maxwellian at 2T, |g| has the density proportional to
        r^{d-1} exp(-r^2/(4T)). By default a 64-point Gauss-Legendre rule on
        [0, 18 sqrt(T)] (the density is below e^-80 beyond)."""
        if not (temperature > 0.0 and math.isfinite(temperature)):
            check.reject(type(self).__name__, "temperature", temperature,
                         "must be positive and finite")
        r, w = gauss_legendre(64, 18.0 * math.sqrt(temperature))
        density = w * r ** (dimension - 1) * numpy.exp(-r * r / (4.0 * temperature))
        return float(density @ self.speed_part(r) / density.sum())

    def mean_speed_parts(self, dimension: int, temperature, xp=numpy):
        r""":meth:`mean_speed_part` at every temperature of an array of ``xp`` (one per cell
        of a space run), in ``xp``: no transfer to the host. By default the same 64-point
        Gauss-Legendre rule on [0, 18 sqrt(T)], in the variable x = r / (18 sqrt T) whose
        weights x^{d-1} exp(-81 x^2) do not depend on T."""
        x, w = gauss_legendre(64, 1.0)
        density = w * x ** (dimension - 1) * numpy.exp(-81.0 * x * x)
        speeds = 18.0 * xp.sqrt(temperature)[..., None] * xp.asarray(x)
        return self.speed_part(speeds, xp) @ xp.asarray(density / density.sum())

    def energy_factors(self, energy):
        """phi(E) = E^gamma at every energy of an array (positive, checked by the caller)."""
        return 1.0 if self.energy_exponent == 0.0 else energy ** self.energy_exponent

    def energy_factor(self, energy: float) -> float:
        """phi(E) = E^gamma for the kinetic energy E = int |v|^2/2 f dv."""
        if self.energy_exponent == 0.0:
            return 1.0
        if not (energy > 0.0 and math.isfinite(energy)):
            check.reject(type(self).__name__, "energy", energy,
                         "must be positive and finite when energy_exponent != 0")
        return energy ** self.energy_exponent

    def __call__(self, speed, cos_theta, energy: float = 1.0, *, dimension: int):
        """B(|g|, cos theta, E) = C s(|g|) b(cos theta) phi(E)."""
        return (self.prefactor(dimension) * self.speed_part(numpy.asarray(speed, dtype=float))
                * self.angular_part(cos_theta) * self.energy_factor(energy))


# -- Velocity grids ------------------------------------------------------------------------

class Grid(abc.ABC):
    """A velocity grid, what every ``grid`` argument of these contracts is:
    :class:`granframe.VelocityGrid` is the implementation.

    It declares no members: those of :class:`~granframe.velocity.grid.VelocityGrid` are the
    contract. It lets the core check a grid (:func:`check_arguments`) without importing the
    velocity layer, which is built on the core.
    """

    __slots__ = ()


# -- Collision operators -------------------------------------------------------------------

def check_arguments(owner: str, grid, kernel, restitution, backend) -> None:
    """Refuse arguments of the wrong kind (a kernel's name, None for the grid, ...), naming
    the parameter, before an operator uses them. A kernel is accepted by what it offers
    (the kernel against :class:`CollisionKernel`, the restitution law by
    :func:`check_restitution`)."""
    if not isinstance(grid, Grid):
        check.reject(owner, "grid", grid, "must be a granframe.VelocityGrid", error=TypeError)
    if not isinstance(kernel, CollisionKernel):
        check.reject(owner, "kernel", kernel, "must be a collision kernel (a "
                     "granframe.CollisionKernel), e.g. collision_kernel('maxwell')", error=TypeError)
    if not isinstance(restitution, RestitutionLaw):
        check.reject(owner, "restitution", restitution, "must be a granframe.RestitutionLaw, "
                     "e.g. restitution_law('constant', value=0.5)", error=TypeError)
    if not isinstance(backend, ArrayBackend):
        check.reject(owner, "backend", backend, "must be a granframe.ArrayBackend, e.g. "
                     "array_backend('numpy')", error=TypeError)
    check_restitution(owner, restitution, grid.truncation_radius)


def check_restitution(owner: str, restitution: RestitutionLaw, radius: float) -> None:
    """Refuse a restitution law whose values at a few speeds on [0, ``radius``] (the
    relative speeds an operator meets) are not finite, outside [0, 1] or not of the
    speeds' shape (e.g. a scalar), naming the law and the first bad value."""
    speeds = numpy.linspace(0.0, radius, 9)
    values = numpy.asarray(restitution(speeds))
    name = type(restitution).__name__
    if values.shape != speeds.shape:
        check.reject(owner, "restitution", restitution,
                     f"{name} must return an array of the speeds' shape {speeds.shape}, "
                     f"got shape {values.shape}")
    bad = ~(numpy.isfinite(values) & (values >= 0.0) & (values <= 1.0))
    if numpy.any(bad):
        i = int(numpy.argmax(bad))
        check.reject(owner, "restitution", restitution,
                     f"{name} must take values in [0, 1]; e({speeds[i]:.4g}) = {float(values[i])!r}")


class CollisionOperator(abc.ABC):
    """Q_I(f, f) on a fixed grid.

    Subclasses are constructed as ``Operator(grid, kernel, restitution,
    backend, **options)``, where ``options`` carry method-specific settings
    such as quadratures, and implement :meth:`__call__`. The arguments are checked
    (:func:`check_arguments`) under the owner name ``name``.
    """

    #: Name used in error messages (the registered name of the built-in operators).
    name: str = "collision operator"

    def __init__(self, grid, kernel,
                 restitution: RestitutionLaw, backend: ArrayBackend):
        check_arguments(self.name, grid, kernel, restitution, backend)
        self.grid = grid
        self.kernel = kernel
        self.restitution = restitution
        self.backend = backend

    @classmethod
    def estimate_memory(cls, grid, kernel, restitution, backend, **options) -> int | None:
        """Bytes the operator would hold for these arguments, found without allocating
        anything large; None when not known (the default). A run adds it to its own
        estimate before building anything (:mod:`granframe.memory`)."""
        return None

    @abc.abstractmethod
    def __call__(self, f):
        """Return Q_I(f, f) sampled on the grid, an array like ``f`` in ``backend.xp``."""


# -- Space: reconstructions of cell averages and boundaries -----------------------------------


class Reconstruction(abc.ABC):
    r"""Face values of cell averages along axis 0, for the finite-volume transport in x.

    Cell j holds the average f_j of f over [x_{j-1/2}, x_{j+1/2}]. A reconstruction gives
    at each face x_{j-1/2} the value reconstructed from the cell on its left (f^-) and from
    the cell on its right (f^+); the transport takes the upwind one,
    F_{j-1/2} = c^+ f^-_{j-1/2} + c^- f^+_{j-1/2} with c the speed of each velocity node
    (:mod:`granframe.space.transport`).
    """

    #: cells each side that the face values of the outermost faces read beyond the interior
    ghost: ClassVar[int]
    #: formal order of accuracy on smooth data
    order: ClassVar[int]
    #: largest Courant number max|c| dt/dx of one transport sub-step (three-stage SSP
    #: Runge-Kutta) for which the scheme is stable (and TVD, for the limited ones)
    cfl: ClassVar[float]

    @abc.abstractmethod
    def faces(self, f, xp):
        """Face values of the cell averages ``f`` of shape (n + 2 ghost, ...).

        Returns ``(minus, plus)``, each of shape (n + 1, ...): entry i is at the face
        between cells ghost + i - 1 and ghost + i (the n interior cells are
        ``f[ghost:ghost + n]``); ``minus`` reconstructed from the left cell, ``plus``
        from the right one. Every operation is element-wise over the trailing axes
        (the velocity nodes), in the array namespace ``xp``.
        """


class CollisionModel(abc.ABC):
    r"""One level of a space run's hierarchy of collision models (docs/space.md, "The
    hierarchy"): the collision step d_t f = Q(f, f)/eps + tau Delta_v f over dt, in the
    cells a run gives it.

    A factory is called as ``factory(context, **params)``, ``context`` holding the run's
    ``equation`` (:class:`~granframe.equations.homogeneous.HomogeneousBoltzmann`: the operator, the
    Knudsen number, the heat bath), its time ``integrator`` and ``temperature``, the mass
    weighted mean temperature of f0. The levels of a hierarchy are ordered from the
    cheapest to the full operator; the last must have ``full`` true.

    :meth:`advance` runs inside a step, on the device with a GPU backend (no transfer to
    the host), and must keep every cell's mass and momentum to round-off and change its
    energy only by the collisions' dissipation (and the heat bath's work), so that the
    interfaces between levels conserve what the transport carries across them.
    """

    #: the name it is registered under
    name: ClassVar[str]
    #: True for the full collision operator (the last level of every hierarchy)
    full: ClassVar[bool] = False

    @abc.abstractmethod
    def advance(self, f, t: float, dt: float):
        """f (cells, *grid.shape) after the collision step from t to t + dt, a new array
        or ``f`` updated in place. ``converged`` (boolean per cell, on the backend), when
        the model sets it, names the cells it left as they were (no equilibrium)."""


class Boundary(abc.ABC):
    r"""What happens at one end of the interval: a wall, or the link of a periodic interval.

    An implementation sees its wall as the left one, at x = 0 with the domain at x > 0:
    the core maps the right wall to it by the exact reflection v_1 -> -v_1 of the velocity
    nodes (:func:`granframe.space.transport.reflect`), so that the velocities that leave
    the wall into the domain are always those with v_1 > 0.

    :meth:`ghosts` and :meth:`emit` are told the time ``t`` at which the wall acts (the
    stage time of the transport) and ``side``, which wall it is in the lab frame: "left"
    (x = 0) or "right" (x = ell). A wall that moves along x with lab velocity U has the
    normal velocity +U in its own frame on the left and -U on the right (the reflection
    reverses v_1). Both run inside a time step, on the device with a GPU backend: they
    must not copy device arrays to the host (no ``float()`` of an array, no branching on
    array values) and should keep their constant arrays per grid and array namespace
    rather than copy them from the host on every call.
    """

    #: the two ends are one (a periodic interval): both must be periodic, and the core
    #: fills the ghost cells from the other end; :meth:`ghosts` and :meth:`emit` are unused
    periodic: ClassVar[bool] = False

    #: the period in t of what the wall does (:meth:`ghosts`, :meth:`emit`), a finite
    #: float > 0 for a wall that acts periodically in time (a property of its parameters,
    #: or a class attribute); None for one that does not depend on t, or not periodically.
    #: The conformance kit checks a wall at times spread over its period.
    period: float | None = None

    #: what the boundary does commutes with the scaling v -> omega v of the velocities
    #: (no temperature, speed or time of its own): a rescaled space run
    #: (:mod:`granframe.equations.rescaled`) admits only such boundaries
    scale_free: ClassVar[bool] = False

    def check(self, grid) -> None:
        """Refuse a velocity grid the boundary does not fit (a wall velocity of the wrong
        dimension), with a message naming the parameter."""

    @abc.abstractmethod
    def ghosts(self, inside, grid, xp, *, t: float = 0.0, side: str = "left"):
        """Ghost cells beyond the wall from the cells next to it, at time ``t``.

        ``inside``: the first g cells from the wall inwards, shape (g, *grid.shape), in
        the wall's own frame (the right wall's reflected). Returns g ghost cells, ordered
        from the wall outwards, of the same shape. They feed the reconstruction of the
        faces near the wall; the flux through the wall itself is set by :meth:`emit`.
        ``side``: "left" or "right", the wall in the lab frame.
        """

    @abc.abstractmethod
    def emit(self, incoming, grid, xp, *, t: float = 0.0, side: str = "left"):
        """The face values at the wall at time ``t``.

        ``incoming``: f at the wall reconstructed from inside, shape (*grid.shape), in the
        wall's own frame (the right wall's reflected); the values at v_1 < 0 (moving into
        the wall) are what arrives. Returns the values at the wall for every node: those
        at v_1 > 0 are what the wall sends into the domain (the others are not used). Zero
        net mass flux means sum_{v_1 > 0} v_1 out = sum_{v_1 < 0} |v_1| incoming on the
        grid, at every t. ``side``: "left" or "right", the wall in the lab frame.
        """


# -- Problems: what a run steps --------------------------------------------------------------

_DEFERRED = contextvars.ContextVar("granframe_deferred_checks", default=None)


@contextlib.contextmanager
def deferred_checks(everywhere: bool = False):
    """Within it, a check of an operand that would copy a device array to the host (the
    operators' finiteness check of f) is not made on a backend whose arrays live on a
    device (:attr:`ArrayBackend.on_device`): a run steps inside it, and its health check
    of each step's record (one transfer) finds a non-finite f instead.

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


class Problem(abc.ABC):
    """What a run is made of: the one contract between a discretised equation and the runner.

    The runner (:class:`granframe.run.runner.Simulation`), ``granframe limits``,
    ``granframe bench`` and resume use a problem through these members only, in a
    space-homogeneous run as in a space run on any number of processes (the communicator
    and the ranges are always there); the space-homogeneous and the space problems
    implement it (:mod:`granframe.run.problems`).

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
