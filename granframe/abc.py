"""The contracts of granframe: what every implementation of a family provides.

One class per family that plugins extend (docs/plugins.md): collision operators, restitution
laws, quadratures, array backends and their transforms, equations, time integrators and
initial conditions. Implementations live in the topic packages (:mod:`granframe.model`,
:mod:`granframe.velocity`, :mod:`granframe.stepping`, :mod:`granframe.equations`) and in the
plugins; :mod:`granframe.testing` checks an implementation against its contract.
"""

from __future__ import annotations

import abc
import math
import time
from types import ModuleType
from typing import ClassVar

import numpy

from granframe import validators as check


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

    def device_memory(self) -> int | None:
        """Bytes of device memory the backend holds; None for host backends."""
        return None

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

class RestitutionLaw:
    """Interface: ``law(speed) -> e`` with values in [0, 1] and ``law.is_constant``."""

    is_constant: bool = False

    def __call__(self, speed):
        speed = numpy.asarray(speed, dtype=float)
        if speed.size and not (numpy.all(numpy.isfinite(speed)) and speed.min() >= 0.0):
            check.reject(type(self).__name__, "speed", speed,
                         "relative speeds must be finite and >= 0")
        with numpy.errstate(divide="ignore", over="ignore", invalid="ignore"):
            return self._evaluate(speed)

    def _evaluate(self, speed):
        raise NotImplementedError


# -- Quadratures ---------------------------------------------------------------------------

class Quadrature:
    """Interface shared by all rules.

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
    def degree(self) -> int:
        raise NotImplementedError

    @property
    def n_points(self) -> int:
        raise NotImplementedError


class SurfaceQuadrature(Quadrature):
    """A rule on the unit sphere S^{d-1}: ``nodes()`` (M, d), ``weights()`` (M,)."""

    #: Dimension d of the ambient space (2 for the circle, 3 for the sphere).
    dimension: ClassVar[int]

    def nodes(self):
        return self._rule()[0]

    def weights(self):
        return self._rule()[1]

    @property
    def is_antipodal(self) -> bool:
        """True when -ghat is a node of equal weight for every node ghat."""
        from granframe.velocity.quadratures import antipodal_pairs

        _, w_plus, w_minus = antipodal_pairs(*self._rule())
        return bool(numpy.allclose(w_plus, w_minus, rtol=1e-12, atol=0.0))

    def _rule(self):
        raise NotImplementedError


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
    explicit_parts: ClassVar[frozenset] = frozenset({"linear", "nonlinear", "drift"})
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


# -- Collision operators -------------------------------------------------------------------

def check_arguments(owner: str, grid, kernel, restitution, backend) -> None:
    """Refuse arguments of the wrong kind (a kernel's name, None for the grid, ...), naming
    the parameter, before an operator uses them. A kernel is accepted by what it offers
    (docs/plugins.md: "an object like VariableHardSpheres")."""
    from granframe.velocity.grid import VelocityGrid

    if not isinstance(grid, VelocityGrid):
        check.reject(owner, "grid", grid, "must be a granframe.VelocityGrid", error=TypeError)
    if not all(hasattr(kernel, a) for a in ("prefactor", "speed_part", "is_isotropic")):
        check.reject(owner, "kernel", kernel, "must be a collision kernel like "
                     "granframe.VariableHardSpheres, e.g. collision_kernel('maxwell')",
                     error=TypeError)
    if not isinstance(restitution, RestitutionLaw):
        check.reject(owner, "restitution", restitution, "must be a granframe.RestitutionLaw, "
                     "e.g. restitution_law('constant', value=0.5)", error=TypeError)
    if not isinstance(backend, ArrayBackend):
        check.reject(owner, "backend", backend, "must be a granframe.ArrayBackend, e.g. "
                     "array_backend('numpy')", error=TypeError)


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


# -- the stiff parts of an equation ---------------------------------------------------------
import enum  # noqa: E402  (this section is appended after the contracts that use its names)


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
