"""Exact solutions and scales of the one-dimensional space-inhomogeneous problem (docs/space.md).

- the free-molecular steady state between two diffuse walls (no collisions), in closed form
  and on a velocity grid;
- free transport d_t f + c d_x f = 0: a periodic sine, and specular walls by the method
  of images;
- the mean free path and the Knudsen number of the kernels in granframe's conventions;
- the energy a vibrating wall adds per arriving particle.

The Riemann problem of the Euler equations (the hydrodynamic limit eps -> 0) is
:mod:`granframe.theory.euler`.

Temperature, pressure and heat flux follow granframe's conventions: T = int |v-u|^2 f dv
/ (d rho), p = rho T, q_i = int (v-u)_i |v-u|^2 f dv / 2.
"""

from __future__ import annotations

import math
import numbers

import numpy

from granframe import validators as check
from granframe.theory.cells import gauss_cell_averages


def _positive(owner, name, value):
    if not check.is_real(value) or not (0.0 < float(value) < math.inf):
        check.reject(owner, name, value, "must be a positive finite real number")
    return float(value)


def _check_dimension(owner, dimension):
    if not check.is_integer(dimension) or dimension not in (2, 3):
        check.reject(owner, "dimension", dimension, "must be 2 or 3")


# -- Free-molecular flow between two diffuse walls -------------------------------------------


def _walls_arguments(owner, T1, T2, density):
    return (_positive(owner, "T1", T1), _positive(owner, "T2", T2),
            _positive(owner, "density", density))


def free_molecular_walls(dimension: int, T1: float, T2: float, density: float) -> dict:
    r"""Steady free-molecular state between diffuse walls at rest at temperatures T1 (x = 0)
    and T2 (x = ell), full accommodation, no collisions.

    f = n1 M_{T1}(v) for v_1 > 0 and n2 M_{T2}(v) for v_1 < 0, uniform in x, with the
    unit-density Maxwellians M_T = (2 pi T)^{-d/2} exp(-|v|^2/(2T)). Half-range moments
    of M_T: int_{v_1>0} M_T = 1/2, int_{v_1>0} v_1 M_T = sqrt(T/(2 pi)),
    int_{v_1>0} v_1^2 M_T = int_{v_1>0} v_2^2 M_T = T/2,
    int_{v_1>0} v_1 |v|^2 M_T = (d+1) T^{3/2} / sqrt(2 pi). Zero net mass flux gives
    n1 sqrt(T1) = n2 sqrt(T2), the mean density n1 + n2 = 2 rho; so, with
    s_i = sqrt(T_i),

        n1 = 2 rho s2 / (s1 + s2),   n2 = 2 rho s1 / (s1 + s2),   u = 0,
        P = rho sqrt(T1 T2) I        (isotropic: P_11 = P_22 = (n1 T1 + n2 T2)/2),
        T = sqrt(T1 T2)              (in 2D and 3D alike),
        q_1 = (d+1) rho sqrt(T1 T2) (s1 - s2) / sqrt(2 pi),   q_2 = q_3 = 0.

    The heat flux runs from the hot wall to the cold one (q_1 > 0 when T1 > T2).
    This is the free-molecular (Knudsen) limit of the plane heat-transfer problem; see
    e.g. Y. Sone, Molecular Gas Dynamics, Birkhauser, 2007.

    Returns
    -------
    dict
        ``n1``, ``n2``, ``rho``, ``u`` (length d), ``T``, ``P`` (d x d), ``P11``, ``q``
        (length d), ``q1``.
    """
    owner = "free_molecular_walls"
    _check_dimension(owner, dimension)
    T1, T2, rho = _walls_arguments(owner, T1, T2, density)
    s1, s2 = math.sqrt(T1), math.sqrt(T2)
    temperature = s1 * s2
    q1 = (dimension + 1) * rho * temperature * (s1 - s2) / math.sqrt(2.0 * math.pi)
    q = numpy.zeros(dimension)
    q[0] = q1
    return {"n1": 2.0 * rho * s2 / (s1 + s2), "n2": 2.0 * rho * s1 / (s1 + s2), "rho": rho,
            "u": numpy.zeros(dimension), "T": temperature,
            "P": rho * temperature * numpy.eye(dimension), "P11": rho * temperature,
            "q": q, "q1": q1}


def free_molecular_walls_grid(grid, T1: float, T2: float, density: float, rest=None) -> dict:
    r"""The free-molecular state of :func:`free_molecular_walls` on a velocity grid.

    The discrete steady state of the transport with diffuse walls that emit a multiple of
    the grid-sampled Maxwellian M_{T_w}: f_j = n1 M_{T1}(v_j) at the nodes with v_1 > 0
    (j = N/2+1 .. N-1 along v_1), f_j = n2 M_{T2}(v_j) at those with v_1 < 0
    (j = 1 .. N/2-1); the two sets are mirror images. The node j = 0, which the periodic
    grid shares between v_1 = -L and +L, moves both ways at L/2
    (:func:`granframe.space.transport.upwind_speeds`): each wall emits into it, and it
    holds here the mean (n1 M_{T1} + n2 M_{T2})/2 of the two emissions. (In a run it holds
    a profile between them, linear in x for the upwind reconstruction, whose mean over
    the cells this is; both are of relative size exp(-L^2 / (2 max T_w)).) The nodes
    v_1 = 0 (j = N/2) carry no flux, are not reached by the walls and keep whatever they
    hold: ``rest``. The discrete sums fix n1 and n2:

        n1 F(T1) = n2 F(T2),   F(T) = h^d sum_v c^+ M_T(v_j)        (zero mass flux),
        n1 m(T1) + n2 m(T2) + m_rest = rho,   m(T) = h^d sum_v M_T(v_j) over the nodes of
        c^+ > 0 except j = 0, plus half of j = 0                      (grid mass),

    with the sums over the transverse nodes too (the half-range sums over v_1 < 0 equal
    those over v_1 > 0 by the mirror symmetry).

    With the default ``rest`` the node v_1 = 0 holds half of each half-range state, so each
    half-range sum is the trapezoidal rule on [0, L] in v_1, whose end v_1 = 0 is the kink
    of the half-range data: the grid moments differ from :func:`free_molecular_walls` by
    O(h^2). In 2D with T1 = 1, T2 = 2 and S = 6 the relative difference of q_1 is 4.98e-2,
    1.16e-2, 2.84e-3, 7.08e-4 at N = 32, 64, 128, 256 (of T and P_11: 5.40e-3, 1.25e-3,
    3.08e-4, 7.66e-5); with S = 8 and N = 32, 9.71e-2 (q_1) and 1.05e-2 (T).

    Parameters
    ----------
    grid : VelocityGrid
    T1, T2, density : float
        Wall temperatures and the grid mass rho = h^d sum_j f_j of the state, > 0.
    rest : None or array_like
        Values at the nodes v_1 = 0. ``None``: the average (n1 M_{T1} + n2 M_{T2})/2 of the
        two half-range states there (n1, n2 then solve the 2 x 2 system with
        m_rest = (n1 r(T1) + n2 r(T2))/2, r(T) the grid mass of M_T on them). An array of
        the grid's shape: its values at j = N/2 along v_1 are kept (the initial data of a
        run, which the discrete solver leaves there unchanged), so the result is the state
        a run from that data converges to.

    Returns
    -------
    dict
        ``f`` (the grid's shape), ``n1``, ``n2``, and the grid moments of f
        (:meth:`VelocityGrid.moments`): ``rho``, ``u``, ``T``, ``P``, ``P11``, ``q``, ``q1``.
    """
    owner = "free_molecular_walls_grid"
    T1, T2, rho = _walls_arguments(owner, T1, T2, density)
    positive, negative, shared, resting = nodes = _half_range_nodes(grid)
    m1, m2 = grid.maxwellian(1.0, None, T1), grid.maxwellian(1.0, None, T2)
    n1, n2, kept = _walls_grid_densities(owner, grid, rho, rest, m1, m2, nodes)
    f = numpy.where(positive, n1 * m1, numpy.where(negative, n2 * m2, kept))
    f = numpy.where(shared, 0.5 * (n1 * m1 + n2 * m2), f)
    moments = grid.moments(f)
    return {"f": f, "n1": float(n1), "n2": float(n2), "rho": moments["mass"],
            "u": moments["bulk_velocity"], "T": moments["temperature"],
            "P": moments["pressure_tensor"], "P11": float(moments["pressure_tensor"][0, 0]),
            "q": moments["heat_flux"], "q1": float(moments["heat_flux"][0])}


def _half_range_nodes(grid):
    """Masks of the grid's shape of its v_1 nodes: v_1 > 0 (j > N/2), v_1 < 0
    (0 < j < N/2), the node -L that moves both ways (j = 0) and v_1 = 0 (j = N/2)."""
    n = grid.n_modes
    index = numpy.broadcast_to(numpy.arange(n).reshape((-1,) + (1,) * (grid.dimension - 1)),
                               grid.shape)
    positive = index > n // 2
    negative = (index > 0) & (index < n // 2)
    shared = index == 0
    resting = index == n // 2
    return positive, negative, shared, resting


def _walls_grid_densities(owner, grid, rho, rest, m1, m2, nodes):
    """n1, n2 of :func:`free_molecular_walls_grid` from zero mass flux and the grid mass,
    and the values ``kept`` at the nodes v_1 = 0 (``rest`` checked, or the default)."""
    from granframe.space.transport import upwind_speeds

    positive, negative, shared, resting = nodes
    h = grid.cell_volume
    c_plus, c_minus = (numpy.broadcast_to(c, grid.shape) for c in upwind_speeds(grid))
    flux1 = h * float(numpy.sum(c_plus * m1))          # emitted by the left wall
    flux2 = h * float(numpy.sum(-c_minus * m2))        # by the right one
    mass1 = h * (float(numpy.sum(m1[positive])) + 0.5 * float(numpy.sum(m1[shared])))
    mass2 = h * (float(numpy.sum(m2[negative])) + 0.5 * float(numpy.sum(m2[shared])))
    if rest is None:
        matrix = numpy.array([[flux1, -flux2],
                              [mass1 + 0.5 * h * float(numpy.sum(m1[resting])),
                               mass2 + 0.5 * h * float(numpy.sum(m2[resting]))]])
        n1, n2 = numpy.linalg.solve(matrix, [0.0, rho])
        kept = 0.5 * (n1 * m1 + n2 * m2)
    else:
        kept = numpy.asarray(rest, dtype=float)
        if kept.shape != grid.shape:
            check.reject(owner, "rest", rest, f"must be None or an array of the grid's "
                         f"shape {grid.shape}")
        remaining = rho - h * float(numpy.sum(kept[resting]))
        n1 = remaining * flux2 / (flux2 * mass1 + flux1 * mass2)
        n2 = n1 * flux1 / flux2
        if not n1 > 0.0:
            check.reject(owner, "rest (grid mass at the nodes v_1 = 0)", rho - remaining,
                         f"must be below density = {rho:.6g}; the moving nodes would need "
                         "a negative mass")
    return n1, n2, kept


def _couette_arguments(owner, temperature, velocity, density, accommodation):
    temperature = _positive(owner, "temperature", temperature)
    if not check.is_real(velocity) or not math.isfinite(float(velocity)):
        check.reject(owner, "velocity", velocity, "must be a finite real number (the speed U "
                     "of the walls relative to each other)")
    density = _positive(owner, "density", density)
    if not check.is_real(accommodation) or not 0.0 < float(accommodation) <= 1.0:
        check.reject(owner, "accommodation", accommodation, "must be a real number in (0, 1]: "
                     "between specular walls (0) the gas keeps its initial shear")
    return temperature, float(velocity), density, float(accommodation)


def free_molecular_couette(dimension: int, temperature: float, velocity: float,
                           density: float, accommodation: float = 1.0) -> dict:
    r"""Steady free-molecular plane Couette flow: no collisions, between Maxwell walls at
    the same temperature T_w with accommodation alpha, the wall at x = 0 moving along v_2
    with -U/2 and the wall at x = ell with +U/2.

    Each wall sends back a (1 - alpha) share of what arrives specularly and an alpha share
    diffusely, as the half-range Maxwellian of its own velocity (Maxwell 1879). Neither
    reflection changes the profile in v_1, so f is uniform in x, and
    f = rho (2 pi T_w)^{-1/2} e^{-v_1^2/(2T_w)} t^±(v_t) on v_1 ≷ 0 (the two streams carry
    the same mass flux rho sqrt(T_w/(2 pi)), so each has the density rho) with unit-mass
    tangential profiles t^± that satisfy

    .. math:: t^+ = (1 - \alpha)\, t^- + \alpha\, m_{-U/2},\qquad
              t^- = (1 - \alpha)\, t^+ + \alpha\, m_{+U/2},
              \qquad t^\pm = \frac{m_{\mp U/2} + (1 - \alpha)\, m_{\pm U/2}}{2 - \alpha},

    m_w the tangential Maxwellian of temperature T_w and mean w along v_2. The streams'
    mean tangential velocities are -+ alpha U / (2 (2 - alpha)); with the half-range moments
    int_{v_1>0} v_1 M dv_1 = sqrt(T_w / (2 pi)), int_{v_1>0} v_1^2 M dv_1 = T_w / 2 of the
    unit Maxwellian M in v_1,

    .. math:: P_{12} = \rho \sqrt{\frac{T_w}{2\pi}}\,\bigl(\bar v_2^+ - \bar v_2^-\bigr)
              = -\frac{\alpha}{2 - \alpha}\, \rho\, U \sqrt{\frac{T_w}{2\pi}},\qquad
              P_{11} = \rho\, T_w,\qquad P_{22} = \rho\,(T_w + U^2/4),

    P_33 = rho T_w (3D), u = 0, T = T_w + U^2 / (4d), q = 0 (both t^± have the second
    moment T_w + U^2/4 about 0, and the two streams' odd moments cancel). The pressure on
    each wall is P_11 = rho T_w and the tangential momentum flux P_12, the same at every x:
    through the wall at x = 0 the gas receives P_12 per unit time, through the wall at
    x = ell -P_12, and the shear stress on the walls is -+P_12 (a drag against each
    wall's motion). With alpha = 1 this is the free-molecular limit of Couette flow (C.
    Cercignani, Rarefied Gas Dynamics, Cambridge University Press, 2000, ch. 6; Y. Sone,
    Molecular Gas Dynamics, Birkhauser, 2007, sec. 4.2); the factor alpha / (2 - alpha)
    is that of Maxwell's boundary condition between two plates (J. C. Maxwell, Phil.
    Trans. R. Soc. 170 (1879) 231-256).

    Parameters
    ----------
    dimension : int
        d, 2 or 3.
    temperature, velocity, density : float
        T_w > 0, U (finite) and rho > 0, the mean density.
    accommodation : float
        alpha in (0, 1], the same at both walls.

    Returns
    -------
    dict
        ``rho``, ``u`` (length d), ``T``, ``P`` (d x d), ``P11``, ``P12``, ``q`` (length d),
        ``stream_velocity`` (the mean v_2 of the stream leaving the wall at x = 0), and
        ``wall_momentum``: (2, d), the momentum that enters the gas through the walls at
        x = 0 and ell per unit time ((P_11, P_12, 0) and its negative; what the store
        records as ``wall_momentum`` / ``dt``).
    """
    owner = "free_molecular_couette"
    _check_dimension(owner, dimension)
    T, U, rho, alpha = _couette_arguments(owner, temperature, velocity, density, accommodation)
    return _couette_state(dimension, T, U, rho, alpha)


def _couette_state(dimension, T, U, rho, alpha):
    """:func:`free_molecular_couette`'s closed form, from its checked arguments."""
    shear = -alpha / (2.0 - alpha) * rho * U * math.sqrt(T / (2.0 * math.pi))
    P = rho * T * numpy.eye(dimension)
    P[0, 1] = P[1, 0] = shear
    P[1, 1] += 0.25 * rho * U * U
    flux = numpy.zeros(dimension)
    flux[:2] = P[0, 0], shear
    return {"rho": rho, "u": numpy.zeros(dimension), "T": T + U * U / (4.0 * dimension),
            "P": P, "P11": rho * T, "P12": shear, "q": numpy.zeros(dimension),
            "stream_velocity": -alpha * U / (2.0 * (2.0 - alpha)),
            "wall_momentum": numpy.stack([flux, -flux])}


def free_molecular_couette_grid(grid, temperature: float, velocity: float, density: float,
                                accommodation: float = 1.0, rest=None) -> dict:
    r"""The free-molecular Couette flow of :func:`free_molecular_couette` on a velocity grid:
    the discrete steady state of the transport between two grid walls
    :class:`~granframe.space.boundaries.Diffuse` (temperature T_w, velocities -U/2 at
    x = 0 and +U/2 at x = ell, accommodation alpha).

    With A_i = exp(-v_{1,i}^2 / (2 T_w)) on the v_1 nodes and m_w(v_t) =
    exp(-|v_t - w e_2|^2 / (2 T_w)) normalised to h^{d-1} sum_t m_w = 1 on the tangential
    nodes, the state is f = n A_i t^+(v_t) on the nodes with v_1 > 0 and n A_i t^-(v_t) on
    those with v_1 < 0, t^± = (m_{-+U/2} + (1 - alpha) m_{±U/2}) / (2 - alpha) as in the
    continuum. It is steady on the grid: the wall's emission alpha Phi M_w / sum_v c^+ M_w
    Delta v + (1 - alpha) f_in(Rv) is n A_i t^+ at every leaving node, because
    Phi = sum_v |c^-| f_in Delta v = n h sum_{c^- < 0} |c^-| A and the reflection maps
    |c^-| A onto c^+ A node by node (the same v_1 profile leaves as arrives). The node -L,
    which moves both ways, holds the mean n A(L) (t^+ + t^-)/2 of the two walls' emissions
    (in a run a profile between them, of relative size exp(-L^2 / (2 T_w))); the nodes
    v_1 = 0 carry no flux and keep ``rest`` (None: the same mean, n A(0) (t^+ + t^-)/2).
    n follows from the grid mass h^d sum f = rho.

    The moments are taken as the recorded fields count them
    (:class:`~granframe.velocity.moments.FieldMoments`: the node -L as its two halves). The
    wall momentum per unit time is the flux of the state through each wall,
    h^d sum_v v_1 v f (the node -L, whose two halves cancel, left out): (P_11, P_12, 0)
    through the wall at x = 0 and its negative through the other, since u = 0. The
    half-range sums in v_1 are the trapezoidal rule on [0, L] of integrands with a kink at
    v_1 = 0 (their end value v_1 = 0 carries no flux), so P_12 and P_11 differ from the
    continuum's by O(h^2) on a fixed box.

    Parameters
    ----------
    grid : VelocityGrid
    temperature, velocity, density : float
        T_w > 0, U and the grid mass rho = h^d sum_j f_j of the state, > 0.
    accommodation : float
        alpha in (0, 1].
    rest : None or array_like
        Values at the nodes v_1 = 0: None (see above) or an array of the grid's shape whose
        values there are kept (the initial data of a run).

    Returns
    -------
    dict
        ``f`` (the grid's shape), ``n``, the fields ``rho``, ``u``, ``T``, ``P``, ``P11``,
        ``P12``, ``q``, and ``wall_momentum`` (2, d) as in :func:`free_molecular_couette`.
    """
    from granframe.velocity.moments import FieldMoments

    owner = "free_molecular_couette_grid"
    T, U, rho, alpha = _couette_arguments(owner, temperature, velocity, density, accommodation)
    normal, plus, minus, unit, resting = _couette_unit_state(grid, T, U, alpha)
    n, f = _couette_grid_scale(owner, grid, rho, rest, normal, plus, minus, unit, resting)
    fields = FieldMoments(grid, 1.0)(f[None])
    P, u, mass = fields["pressure_tensor"][0], fields["velocity"][0], fields["density"][0]
    flux = P[0] + mass * u[0] * u                       # h^d sum_v v_1 v f
    return {"f": f, "n": float(n), "rho": float(mass), "u": u,
            "T": float(fields["temperature"][0]), "P": P,
            "P11": float(P[0, 0]), "P12": float(P[0, 1]), "q": fields["heat_flux"][0],
            "wall_momentum": numpy.stack([flux, -flux])}


def _couette_unit_state(grid, T, U, alpha):
    """A_i (shaped (N, 1, ..., 1)), t^+, t^- of :func:`free_molecular_couette_grid`, its
    state for n = 1 (0 at v_1 = 0) and the mask of the nodes v_1 = 0."""
    n_modes, d = grid.n_modes, grid.dimension
    points = grid.points()
    along = (-1,) + (1,) * (d - 1)
    normal = numpy.exp(-points ** 2 / (2.0 * T)).reshape(along)
    tangential = grid.mesh()[1:]

    def profile(w):
        m = numpy.exp(-((tangential[0] - w) ** 2 + sum(c * c for c in tangential[1:]))
                      / (2.0 * T))
        return m / (m.sum() * grid.spacing ** (d - 1))

    left, right = profile(-0.5 * U), profile(0.5 * U)
    plus = (left + (1.0 - alpha) * right) / (2.0 - alpha)
    minus = (right + (1.0 - alpha) * left) / (2.0 - alpha)
    index = numpy.arange(n_modes).reshape(along)
    unit = numpy.where(index > n_modes // 2, normal * plus,
                       numpy.where(index == n_modes // 2, 0.0,
                                   normal * numpy.where(index == 0, 0.5 * (plus + minus),
                                                        minus)))
    unit = numpy.broadcast_to(unit, grid.shape)
    resting = numpy.broadcast_to(index == n_modes // 2, grid.shape)
    return normal, plus, minus, unit, resting


def _couette_grid_scale(owner, grid, rho, rest, normal, plus, minus, unit, resting):
    """n and f of :func:`free_molecular_couette_grid` from the grid mass rho, with ``rest``
    (checked) or the default at the nodes v_1 = 0."""
    h = grid.cell_volume
    if rest is None:
        n = rho / (h * float(unit.sum()) + h * float(numpy.sum(normal[grid.n_modes // 2]
                                                               * 0.5 * (plus + minus))))
        f = numpy.where(resting, n * normal * 0.5 * (plus + minus), n * unit)
    else:
        kept = numpy.asarray(rest, dtype=float)
        if kept.shape != grid.shape or not numpy.isfinite(kept).all():
            check.reject(owner, "rest", rest, f"must be None or a finite array of the grid's "
                         f"shape {grid.shape}")
        remaining = rho - h * float(kept[resting].sum())
        if not remaining > 0.0:
            check.reject(owner, "rest (grid mass at the nodes v_1 = 0)", rho - remaining,
                         f"must be below density = {rho:.6g}; the moving nodes would need "
                         "a negative mass")
        n = remaining / (h * float(unit.sum()))
        f = numpy.where(resting, kept, n * unit)
    return n, f


# -- Free transport ------------------------------------------------------------------------


def free_transport_sine(edges, t: float, c, amplitude: float, wavenumber: int, length: float,
                        phase: float = 0.0):
    r"""Exact cell averages of the periodic solution of d_t f + c d_x f = 0,
    f(x, 0) = 1 + a sin(2 pi k x / ell + phi).

    f(x, t) = 1 + a sin(2 pi k (x - c t)/ell + phi); over the cell [x_{i-1/2}, x_{i+1/2}]
    of width dx and centre x_i the average is, in the cancellation-free form,

        1 + a sin(2 pi k (x_i - c t)/ell + phi) sinc(k dx / ell),   sinc(z) = sin(pi z)/(pi z).

    Parameters
    ----------
    edges : array_like
        Cell edges (increasing).
    t : float
        Time >= 0.
    c : array_like
        Speeds, e.g. one per velocity node.
    amplitude : float
        a.
    wavenumber : int
        k, a nonzero integer (the data are ell-periodic).
    length : float
        ell > 0.
    phase : float
        phi (pi/2 gives a cosine).

    Returns
    -------
    numpy.ndarray
        Shape ``(len(edges) - 1,) + numpy.shape(c)``.
    """
    owner = "free_transport_sine"
    edges = check.cell_edges(owner, edges)
    t = check.time_point(owner, t)
    length = _positive(owner, "length", length)
    if not isinstance(wavenumber, numbers.Integral) or isinstance(wavenumber, bool) \
            or wavenumber == 0:
        check.reject(owner, "wavenumber", wavenumber, "must be a nonzero integer (the data "
                     "must be periodic on [0, length])")
    c = numpy.asarray(c, dtype=float)
    centre = (0.5 * (edges[:-1] + edges[1:])).reshape((-1,) + (1,) * c.ndim)
    width = numpy.diff(edges).reshape(centre.shape)
    k = float(wavenumber)
    return 1.0 + amplitude * numpy.sin(2.0 * math.pi * k * (centre - c * t) / length + phase) \
        * numpy.sinc(k * width / length)


def _images_arguments(owner, length, t, velocities, speeds):
    length = _positive(owner, "length", length)
    t = check.time_point(owner, t)
    v = numpy.asarray(velocities, dtype=float)
    if v.ndim != 1:
        check.reject(owner, "velocities", velocities, "must be a 1-D array of v_1 values")
    c = v if speeds is None else numpy.asarray(speeds, dtype=float)
    if c.shape != v.shape:
        check.reject(owner, "speeds", speeds, f"must be None or have the shape {v.shape} "
                     "of velocities")
    return length, t, v, c


def specular_images(initial, length: float, x, t: float, velocities, speeds=None):
    r"""Free transport between two specular walls at x = 0 and x = ell, by the method of images.

    The data g(x, v_1) on [0, ell] are extended to [-ell, ell] by G(-x, -v_1) = g(x, v_1)
    and 2 ell-periodically; the free solution G(x - c t, v_1) is then even under
    (x, v_1) -> (-x, -v_1) and (x, v_1) -> (2 ell - x, -v_1), so f(0, v_1) = f(0, -v_1) and
    f(ell, v_1) = f(ell, -v_1): specular reflection at both walls. Explicitly, with
    y = (x - c t) mod 2 ell,

        f(x, v_1, t) = g(y, v_1)                 y <= ell,
        f(x, v_1, t) = g(2 ell - y, -v_1)        y > ell.

    ``speeds`` c default to v_1; on a velocity grid pass the transport speeds, v_1 except
    0 at the node j = 0 (the grid's reflection fixes that node, and with c = 0 the fold
    never evaluates g at its mirror +L). A factor of the transverse velocities
    (a Maxwellian, for separable data) multiplies the result unchanged.

    Parameters
    ----------
    initial : callable
        g(x, v_1), vectorised: called with broadcastable arrays of positions in [0, ell]
        and of velocities.
    length : float
        ell > 0.
    x : array_like
        Positions, 1-D.
    t : float
        Time >= 0.
    velocities : array_like
        v_1 of the velocity nodes, 1-D.
    speeds : array_like or None
        c of each node.

    Returns
    -------
    numpy.ndarray
        f, shape ``(len(x), len(velocities))``.
    """
    length, t, v, c = _images_arguments("specular_images", length, t, velocities, speeds)
    x = numpy.asarray(x, dtype=float).reshape(-1, 1)
    y = numpy.mod(x - c[None, :] * t, 2.0 * length)
    mirrored = y > length
    folded = numpy.where(mirrored, 2.0 * length - y, y)
    return numpy.asarray(initial(folded, numpy.where(mirrored, -v[None, :], v[None, :])),
                         dtype=float) * numpy.ones(folded.shape)


def specular_images_cell_averages(initial, length: float, edges, t: float, velocities,
                                  speeds=None, points: int = 8):
    r"""Cell averages of :func:`specular_images` over the cells of ``edges`` in [0, ell].

    The image solution of node j is smooth in x except at the folds x = c_j t + m ell
    (integer m), where it has a kink (or a jump, where g(0, v_1) != g(0, -v_1)); every cell
    is split at the folds of all nodes and each piece gets the ``points``-point
    Gauss-Legendre rule, so the averages are as accurate as that rule on g, smooth on
    [0, ell] (exact for polynomials of degree 2 points - 1; a sine of 4 periods on
    [0, 1] and 50 cells: about 1e-15 with 8 points).

    Returns
    -------
    numpy.ndarray
        Shape ``(len(edges) - 1, len(velocities))``.
    """
    owner = "specular_images_cell_averages"
    edges = check.cell_edges(owner, edges)
    points = check.rule_points(owner, points)
    length, t, v, c = _images_arguments(owner, length, t, velocities, speeds)
    shifts = c * t
    lowest = math.floor((edges[0] - shifts.max()) / length)
    highest = math.ceil((edges[-1] - shifts.min()) / length)
    folds = shifts[:, None] + length * numpy.arange(lowest, highest + 1)[None, :]
    return gauss_cell_averages(
        edges, lambda x: specular_images(initial, length, x, t, v, c), folds, points)


# -- Mean free path and Knudsen number -------------------------------------------------------


def mean_speed(dimension: int, temperature: float) -> float:
    """Mean speed of a Maxwellian at rest, vbar = sqrt(2T) Gamma((d+1)/2) / Gamma(d/2):
    sqrt(pi T / 2) in 2D, sqrt(8 T / pi) in 3D."""
    return math.sqrt(2.0 * temperature) * math.exp(
        math.lgamma((dimension + 1) / 2) - math.lgamma(dimension / 2))


def mean_free_path(kernel, dimension: int, density: float, temperature: float,
                   knudsen: float = 1.0) -> float:
    r"""Mean free path lambda = vbar / nu of the Maxwellian (rho, u = 0, T) (docs/space.md).

    vbar is :func:`mean_speed` and nu = collision_frequency(kernel, d, rho, T, E) / eps the
    mean loss frequency of Q/eps (:func:`granframe.equations.homogeneous.collision_frequency`,
    E = d rho T / 2). For B = C |g|^lambda b with the default C (C |S^{d-1}| = 1) and b = 1,

        lambda = eps vbar / (rho <|g|^lambda>),   <|g|^lambda> = (4T)^{lambda/2}
                 Gamma((d+lambda)/2) / Gamma(d/2),

    eps sqrt(pi T/2) / rho (2D) and eps sqrt(8T/pi) / rho (3D) for Maxwell molecules, and
    eps / (sqrt 2 rho) for hard spheres in 2D and 3D: the classical
    1/(sqrt 2 n pi sigma^2) with pi sigma^2 = 1/eps in 3D.
    """
    from granframe.equations.homogeneous import collision_frequency

    owner = "mean_free_path"
    _check_dimension(owner, dimension)
    density = _positive(owner, "density", density)
    temperature = _positive(owner, "temperature", temperature)
    knudsen = _positive(owner, "knudsen", knudsen)
    nu = collision_frequency(kernel, dimension, density, temperature,
                             0.5 * dimension * density * temperature) / knudsen
    return mean_speed(dimension, temperature) / nu


def knudsen_number(kernel, dimension: int, density: float, temperature: float,
                   knudsen: float, length: float) -> float:
    """Knudsen number Kn = lambda / ell of :func:`mean_free_path` on an interval of
    length ell."""
    return mean_free_path(kernel, dimension, density, temperature, knudsen) / _positive(
        "knudsen_number", "length", length)


# -- Vibrating walls --------------------------------------------------------------------------

#: the mean of (S(theta) - cos theta)^2 over the phase, S the layer's escape slope
#: (:func:`granframe.space.vibration.escape_slope`): 1/2 (to 1e-15 on 4096 phases)
CATCH_MOMENT = 0.5


def vibrating_wall_heating_series(speed: float, wall_temperature: float,
                                  gas_temperature: float, reflection: str) -> float:
    r"""The energy a vibrating wall (:class:`granframe.space.boundaries.Vibrating`) adds,
    per arriving particle of a gas at rest at temperature T, to what the wall at rest
    sends back: the leading term of its expansion in V / sqrt(T) (docs/space.md,
    "Vibrating walls"),

    .. math:: \Delta e_{diffuse} = V^2 \Bigl(\frac{\pi}{4}\sqrt{\frac{T_w}{T}}
              + \frac14 + \frac12\langle (S - \cos\theta)^2\rangle\Bigr)
              = V^2 \Bigl(\frac{\pi}{4}\sqrt{\frac{T_w}{T}} + \frac12\Bigr),
              \qquad \Delta e_{specular} = 2 V^2,

    the first from the first hits' correlation with the wall's speed (the hit rate
    (a + U)/a times the work U w_1 + U^2/2 on an emission of mean normal speed
    sqrt(pi T_w / 2)), the last from the wall catching what it sent back too slowly
    (each catch renews a normal energy of about T_w, with probability
    V^2 (S - cos theta)^2 / (2 T_w)); the specular value holds exactly for every arriving
    speed a >= 3V. The remainder is O(V^3 / sqrt(T)).
    """
    owner = "vibrating_wall_heating_series"
    V = _positive(owner, "speed", speed)
    Tw = _positive(owner, "wall_temperature", wall_temperature)
    T = _positive(owner, "gas_temperature", gas_temperature)
    if reflection == "specular":
        return 2.0 * V * V
    if reflection != "diffuse":
        check.reject(owner, "reflection", reflection, "must be 'diffuse' or 'specular'")
    return V * V * (0.25 * math.pi * math.sqrt(Tw / T) + 0.25 + 0.5 * CATCH_MOMENT)


def vibrating_wall_heating(speed: float, wall_temperature: float, gas_temperature: float,
                           reflection: str, speeds: int = 3000) -> float:
    r"""The same energy from the layer's kernel without expansion
    (:class:`granframe.space.vibration.Layer`): the arriving normal speeds of the
    flux-weighted half-range Maxwellian at T, (a / T) exp(-a^2 / (2T)), on ``speeds``
    midpoints of [0, 12 sqrt(T)]; the leaving speeds of the diffuse wall on as many
    midpoints of [0, 12 sqrt(T_w) + V], each arriving speed's escape density normalised
    to one particle. Returns sum_a (e_out(a) - e_rest) F(a) da / sum_a F(a) da, with
    e_out(a) the mean normal energy b^2/2 that leaves for arrival speed a, e_rest = T_w
    (diffuse; the tangential energy is T_w/2 per component either way) or a^2/2
    (specular). Converges as speeds^-2 (the midpoint rule on smooth integrands).
    """
    from granframe.space.vibration import Layer

    owner = "vibrating_wall_heating"
    V = _positive(owner, "speed", speed)
    Tw = _positive(owner, "wall_temperature", wall_temperature)
    T = _positive(owner, "gas_temperature", gas_temperature)
    if reflection not in ("diffuse", "specular"):
        check.reject(owner, "reflection", reflection, "must be 'diffuse' or 'specular'")
    if not check.is_integer(speeds) or speeds < 100:
        check.reject(owner, "speeds", speeds, "must be an integer >= 100")
    top = 12.0 * math.sqrt(T)
    a = (numpy.arange(speeds) + 0.5) * (top / speeds)
    arriving = a / T * numpy.exp(-a * a / (2.0 * T))
    layer = Layer(V, Tw)
    if reflection == "diffuse":
        edge = 12.0 * math.sqrt(Tw) + V
        b = (numpy.arange(speeds) + 0.5) * (edge / speeds)
        g = layer.diffuse_escape(b, a)
        gained = (0.5 * b * b) @ g / g.sum(axis=0) - Tw
    else:
        b, weight = layer.specular_escape(a)
        gained = (0.5 * b * b * weight).sum(axis=0) / weight.sum(axis=0) - 0.5 * a * a
    return float((gained * arriving).sum() / arriving.sum())
