"""Velocity grid of the Fourier spectral method and the moments of f on it.

The conventions follow section 2 of the review (Carrillo, Hu, Ma, Rey):
f is supported (approximately) in the ball B_S, the relative velocity g is
truncated to B_R with R = 2S, and f is periodised on the box
D_L = [-L, L]^d with

    L >= (3 + sqrt(2)) S / 2                      (anti-aliasing bound, [FPT05])

and approximated by the truncated Fourier series

    f_N(v) = sum_{k=-N/2}^{N/2-1} fhat_k exp(i pi k.v / L).
"""

from __future__ import annotations

import functools
import math
import warnings

import attrs
import numpy

from granframe import validators as check
from granframe.abc import Grid
from granframe.velocity.moments import FieldMoments
from granframe.errors import AliasingWarning

#: Factor c in the anti-aliasing bound L >= c S of the review, c = (3 + sqrt 2)/2.
ANTI_ALIASING_FACTOR = (3.0 + math.sqrt(2.0)) / 2.0


#: Range of the velocity scales S, L and R: |v|^4 (the kurtosis), h^d and 1/h^d must stay
#: finite in float64 for every grid of up to 2^16 points per axis.
SCALE_RANGE = (1e-50, 1e50)


@attrs.frozen
class VelocityGrid(Grid):
    """Uniform periodic velocity grid of ``n_modes**dimension`` points.

    Parameters
    ----------
    dimension : int
        Velocity dimension d, 2 or 3.
    n_modes : int
        Number N of Fourier modes (and grid points) per axis; even, 4 <= N <= 65536.
    support_radius : float
        Radius S of the ball that (approximately) contains the support of f;
        1e-50 <= S <= 1e50, and so must L and R be, so that h^d, the temperature and
        the fourth moments stay within floating-point range.
    half_width : float, optional
        Half width L of the periodic box [-L, L]^d. Defaults to the
        anti-aliasing bound (3 + sqrt 2) S / 2 of [FPT05].
    truncation_radius : float, optional
        Radius R of the ball B_R to which the relative velocity is truncated.
        Defaults to R = 2S.
    allow_aliasing : bool
        Must be ``True`` to accept ``half_width`` below the anti-aliasing bound
        or ``truncation_radius`` below 2S; an :class:`AliasingWarning` is then
        issued. Without it such values raise :class:`ValueError`.

    Notes
    -----
    Grid points are v_j = -L + j h, j = 0, ..., N-1, with spacing h = 2L/N, so
    that v = 0 is the point j = N/2. With this choice the Fourier coefficient
    fhat_k = (2L)^{-d} int_{D_L} f(v) exp(-i pi k.v/L) dv is, by the
    rectangle rule (spectrally accurate for periodic f),
    fhat_k = (-1)^{k_1+...+k_d} DFT(f)_k / N^d.

    References
    ----------
    .. [FPT05] F. Filbet, L. Pareschi, G. Toscani, "Accurate numerical methods
       for the collisional motion of (heated) granular flows", J. Comput. Phys.
       202 (2005).
    """

    dimension: int = attrs.field(converter=check.to_int, validator=check.integer(choices=(2, 3)))
    n_modes: int = attrs.field(converter=check.to_int,
                               validator=check.integer(lower=4, upper=2 ** 16, even=True))
    support_radius: float = attrs.field(
        converter=check.to_float, validator=check.real(SCALE_RANGE[0], SCALE_RANGE[1]))
    half_width: float = attrs.field(default=None, converter=check.to_float,
                                    validator=check.optional_positive)
    truncation_radius: float = attrs.field(default=None, converter=check.to_float,
                                           validator=check.optional_positive)
    allow_aliasing: bool = attrs.field(default=False, validator=check.boolean, kw_only=True)

    def __attrs_post_init__(self):
        S = self.support_radius
        bound = ANTI_ALIASING_FACTOR * S
        if self.half_width is None:
            object.__setattr__(self, "half_width", bound)
        if self.truncation_radius is None:
            object.__setattr__(self, "truncation_radius", 2.0 * S)
        for name in ("half_width", "truncation_radius"):
            value = getattr(self, name)
            if not SCALE_RANGE[0] <= value <= SCALE_RANGE[1]:
                check.reject("VelocityGrid", name, value, f"must be within [{SCALE_RANGE[0]:g}, "
                             f"{SCALE_RANGE[1]:g}] (velocities outside it overflow the moments)")
        override = "pass allow_aliasing=True to accept it knowingly"
        problems = []
        if self.half_width < bound * (1.0 - 1e-12):
            problems.append((
                "half_width", self.half_width,
                f"must be >= (3+sqrt(2))/2 * support_radius = {bound:.6g} to avoid aliasing"))
        if self.truncation_radius < 2.0 * S * (1.0 - 1e-12):
            problems.append((
                "truncation_radius", self.truncation_radius,
                f"must be >= 2 * support_radius = {2.0 * S:.6g} so that no collision "
                "between particles in the support is cut off"))
        for name, value, allowed in problems:
            if not self.allow_aliasing:
                check.reject("VelocityGrid", name, value, f"{allowed}; {override}")
            warnings.warn(f"VelocityGrid: {name} = {value!r} is below the safe bound: "
                          f"{allowed}. Results may be aliased.", AliasingWarning, stacklevel=3)

    # -- geometry -------------------------------------------------------------------
    @property
    def spacing(self) -> float:
        """Grid spacing h = 2L/N."""
        return 2.0 * self.half_width / self.n_modes

    @property
    def cell_volume(self) -> float:
        """Volume h^d of one grid cell (the rectangle-rule weight)."""
        return self.spacing ** self.dimension

    @property
    def shape(self) -> tuple[int, ...]:
        return (self.n_modes,) * self.dimension

    @property
    def safe_half_width(self) -> float:
        """The anti-aliasing bound (3 + sqrt 2) S / 2."""
        return ANTI_ALIASING_FACTOR * self.support_radius

    def points(self, xp=numpy):
        """1-D grid points v_j = -L + j h, j = 0..N-1, in namespace ``xp``."""
        return -self.half_width + self.spacing * xp.arange(self.n_modes, dtype=xp.float64)

    def wavenumbers(self, xp=numpy):
        """Integer Fourier indices k in DFT order (0, 1, ..., N/2-1, -N/2, ..., -1).

        The physical frequency of mode k is pi k / L.
        """
        n = self.n_modes
        return xp.concatenate([xp.arange(n // 2), xp.arange(-n // 2, 0)]).astype(xp.float64)

    @property
    def half_shape(self) -> tuple[int, ...]:
        """Shape of a real-to-complex (rfft) spectrum: N^{d-1} x (N/2 + 1)."""
        return (self.n_modes,) * (self.dimension - 1) + (self.n_modes // 2 + 1,)

    def half_wavenumbers(self):
        """Integer wavenumbers of each axis of the rfft layout (NumPy arrays).

        Axes 0..d-2 in DFT order (0, ..., N/2-1, -N/2, ..., -1), the last axis 0..N/2.
        """
        n = self.n_modes
        return [self.wavenumbers()] * (self.dimension - 1) + [numpy.arange(n // 2 + 1.0)]

    def half_wavenumber_squared(self):
        """|k|^2 on the rfft layout (NumPy array of shape ``half_shape``)."""
        d = self.dimension
        return sum(numpy.reshape(k, [-1 if i == j else 1 for j in range(d)]) ** 2
                   for i, k in enumerate(self.half_wavenumbers()))

    def nyquist_mask(self):
        """True on the rfft layout where some |k_i| = N/2 (modes that are not real-representable)."""
        mask = numpy.zeros(self.half_shape, dtype=bool)
        for axis in range(self.dimension):
            index = [slice(None)] * self.dimension
            index[axis] = self.n_modes // 2
            mask[tuple(index)] = True
        return mask

    def without_nyquist(self, half):
        """``half`` (a NumPy array whose last axes have the rfft layout ``half_shape``) with
        its Nyquist modes set to zero, in place; returned. The one place where the modes
        the spectral operators do not evolve are removed: from f (:meth:`project`), the
        heat-bath symbol and the drift's derivative symbols."""
        half[..., self.nyquist_mask()] = 0.0
        return half

    def project(self, f):
        """f without its Nyquist modes (NumPy): the space the spectral operators work in.

        Neither the collision operators nor the heat bath act on the modes with some
        |k_i| = N/2, so a Nyquist part of f0 would stay frozen for the whole run (for
        discontinuous data, a checkerboard over the whole box). Mass is unchanged.
        """
        self.check_shape(f)
        axes = tuple(range(self.dimension))
        spectrum = self.without_nyquist(numpy.fft.rfftn(f, axes=axes))
        return numpy.fft.irfftn(spectrum, s=self.shape, axes=axes)

    def mesh(self, xp=numpy):
        """Sparse (broadcastable) coordinate arrays v_1, ..., v_d of shape N^d."""
        v = self.points(xp)
        return tuple(
            xp.reshape(v, tuple(self.n_modes if a == b else 1 for b in range(self.dimension)))
            for a in range(self.dimension))

    def speed_squared(self, xp=numpy):
        """|v|^2 on the grid, shape N^d."""
        return functools.reduce(lambda a, b: a + b, (c * c for c in self.mesh(xp)))

    # -- moments ----------------------------------------------------------------------
    def check_shape(self, f):
        """Refuse an f that is not an array (NumPy or the backend's) of the grid's shape."""
        if not hasattr(f, "shape") or not hasattr(f, "dtype"):
            check.reject("VelocityGrid", "f", f, f"must be an array of the grid shape "
                         f"{self.shape} (NumPy, or the backend's), not a "
                         f"{type(f).__name__}", error=TypeError)
        if tuple(f.shape) != self.shape:
            check.reject("VelocityGrid", "f.shape", tuple(f.shape),
                         f"must equal the grid shape {self.shape}")

    def mass(self, f, xp=numpy) -> float:
        """rho = int f dv, by the rectangle rule h^d sum_j f_j."""
        self.check_shape(f)
        return float(xp.sum(f)) * self.cell_volume

    def momentum(self, f, xp=numpy):
        """rho u = int v f dv, a length-d NumPy array."""
        self.check_shape(f)
        return numpy.array([float(xp.sum(c * f)) for c in self.mesh(xp)]) * self.cell_volume

    def _nonzero_mass(self, f, xp) -> float:
        """rho, refused when it is zero (the moments below divide by it)."""
        rho = self.mass(f, xp)
        if rho == 0.0:
            check.reject("VelocityGrid", "mass of f", rho, "must be nonzero: the mass is zero, "
                         "and the bulk velocity, temperature, kurtosis and Sonine a2 divide by it")
        return rho

    def bulk_velocity(self, f, xp=numpy):
        """u = (int v f dv) / rho (refused for a zero mass)."""
        return self.momentum(f, xp) / self._nonzero_mass(f, xp)

    def kinetic_energy(self, f, xp=numpy) -> float:
        """E = int |v|^2/2 f dv (the review's E(f), section 1)."""
        self.check_shape(f)
        return 0.5 * float(xp.sum(self.speed_squared(xp) * f)) * self.cell_volume

    def _central_moment(self, f, power: int, xp) -> float:
        u = self.bulk_velocity(f, xp)
        c2 = functools.reduce(lambda a, b: a + b,
                              ((c - float(ui)) ** 2 for c, ui in zip(self.mesh(xp), u)))
        return float(xp.sum(c2 ** (power // 2) * f)) * self.cell_volume

    def temperature(self, f, xp=numpy) -> float:
        """T = int |v - u|^2 f dv / (d rho) (refused for a zero mass)."""
        return self._central_moment(f, 2, xp) / (self.dimension * self._nonzero_mass(f, xp))

    def kurtosis(self, f, xp=numpy) -> float:
        """kappa = rho int |v-u|^4 f / (int |v-u|^2 f)^2; (d+2)/d for a Maxwellian.

        Refused for a zero mass, and for a zero second moment (all mass at v = u).
        """
        m2 = self._central_moment(f, 2, xp)
        if m2 == 0.0:
            check.reject("VelocityGrid", "int |v - u|^2 f dv", m2, "must be nonzero: the "
                         "kurtosis divides by its square (all of f sits at v = u)")
        return self.mass(f, xp) * self._central_moment(f, 4, xp) / m2 ** 2

    def sonine_a2(self, f, xp=numpy) -> float:
        """Second Sonine coefficient a2 = d/(d+2) kappa - 1 (0 for a Maxwellian)."""
        return self.dimension / (self.dimension + 2.0) * self.kurtosis(f, xp) - 1.0

    def _peculiar_velocity(self, f, xp):
        """The components of c = v - u on the grid (refused for a zero mass)."""
        u = self.bulk_velocity(f, xp)
        return [c - float(ui) for c, ui in zip(self.mesh(xp), u)]

    def pressure_tensor(self, f, xp=numpy):
        """P_ij = int (v - u)_i (v - u)_j f dv, a d x d NumPy array (refused for a zero mass).

        By the rectangle rule, P_ij = h^d sum_j c_i c_j f_j with c = v_j - u; its trace is
        d rho T, and P = rho T I for a Maxwellian.
        """
        c = self._peculiar_velocity(f, xp)
        d = self.dimension
        pressure = numpy.empty((d, d))
        for i in range(d):
            for j in range(i, d):
                pressure[i, j] = pressure[j, i] = float(xp.sum(c[i] * c[j] * f))
        return pressure * self.cell_volume

    def heat_flux(self, f, xp=numpy):
        """q_i = (1/2) int (v - u)_i |v - u|^2 f dv, a length-d NumPy array (refused for a
        zero mass).

        By the rectangle rule, q_i = (h^d / 2) sum_j c_i |c|^2 f_j with c = v_j - u; q = 0
        for any f that is even about u (a Maxwellian, an anisotropic Gaussian).
        """
        c = self._peculiar_velocity(f, xp)
        c2f = functools.reduce(lambda a, b: a + b, (ci * ci for ci in c)) * f
        return 0.5 * numpy.array([float(xp.sum(ci * c2f)) for ci in c]) * self.cell_volume

    def moments(self, f, xp=numpy) -> dict:
        """Every moment the runner records of f, from one pass over f and one transfer to
        the host: :meth:`granframe.velocity.moments.FieldMoments.distribution` (the moment
        service of every run, its basis made once per grid and namespace), with the node
        -L at -L as in :meth:`momentum`.

        Returns
        -------
        dict
            ``mass``, ``momentum`` (a length-d NumPy array), ``bulk_velocity``,
            ``kinetic_energy``, ``temperature``, ``kurtosis``, ``sonine_a2``, ``min_f``,
            ``negative_mass_fraction`` (int max(-f, 0) / int |f|), as floats, and
            ``pressure_tensor`` (d x d) and ``heat_flux`` (length d) as NumPy arrays.
            Where the single-moment methods refuse (a zero mass, a zero second central
            moment) the value is NaN.

        Notes
        -----
        They equal :meth:`mass`, :meth:`momentum`, :meth:`temperature`,
        :meth:`pressure_tensor`, :meth:`heat_flux`, ... to round-off relative to the raw
        moments: a central moment of order n loses about (|u|^2 / T)^{n/2} of relative
        accuracy to cancellation, nothing at u = 0.
        """
        self.check_shape(f)
        return _moment_service(self, xp).distribution(f)

    def maxwellian(self, density=1.0, velocity=None, temperature=1.0, xp=numpy):
        """M(v) = rho (2 pi T)^{-d/2} exp(-|v-u|^2/(2T)) sampled on the grid."""
        u = numpy.zeros(self.dimension) if velocity is None else numpy.asarray(velocity, float)
        if u.shape != (self.dimension,):
            check.reject("VelocityGrid.maxwellian", "velocity", velocity,
                         f"must have {self.dimension} components")
        for name, value in (("density", density), ("temperature", temperature)):
            if not check.is_real(value) or not (0.0 < float(value) < math.inf):
                check.reject("VelocityGrid.maxwellian", name, value, "must be a positive real number")
        c2 = functools.reduce(lambda a, b: a + b,
                              ((c - float(ui)) ** 2 for c, ui in zip(self.mesh(xp), u)))
        return (density * (2.0 * math.pi * temperature) ** (-self.dimension / 2)
                * xp.exp(-c2 / (2.0 * temperature)))


@functools.lru_cache(maxsize=16)
def _moment_service(grid: VelocityGrid, xp) -> FieldMoments:
    """The moment service of ``grid`` in the namespace ``xp``, its basis made once."""
    return FieldMoments(grid, 1.0, xp)
