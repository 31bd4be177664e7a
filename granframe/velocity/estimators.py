r"""A-posteriori error indicators of a discrete f: what the grid fails to represent.

Two quantities bound the two truncations of the spectral methods (review, section 2):

- the **spectral tail**: the Fourier coefficients that the N modes per axis cut off are of
  the size of those on the outermost evolved shell, so their size relative to
  \hat f_0 estimates the resolution error in velocity (h too coarse for f);
- the **mass beyond a radius**: the share of f outside the ball B_S that the operators
  assume contains the support (relative velocities are cut at R = 2S), which estimates the
  truncation error of the collision integral (S too small for f).

Both are cheap (one FFT, one masked sum). They are indicators, not error bounds: the
accuracy-vs-cost study (docs/accuracy-vs-cost.md) relates them to measured errors.
"""

from __future__ import annotations

import numpy

from granframe import validators as check


def spectral_tail(grid, f, shell: int = 1, xp=numpy) -> float:
    r"""max |\hat f_k| / |\hat f_0| over the outermost ``shell`` evolved shells.

    The shells are the modes with N/2 - shell <= max_i |k_i| <= N/2 - 1 (the Nyquist modes
    |k_i| = N/2 are not evolved, :meth:`VelocityGrid.project`). The coefficients are
    \hat f_k = (-1)^{k_1 + ... + k_d} DFT(f)_k / N^d, so only moduli are needed. For a
    Maxwellian of temperature T, \hat f_k / \hat f_0 = exp(-T (\pi |k| / L)^2 / 2) and the
    result is exp(-T (\pi (N/2 - shell) / L)^2 / 2).

    Parameters
    ----------
    grid : VelocityGrid
    f : array of shape ``grid.shape`` (namespace ``xp``)
    shell : int
        Width of the outer band, 1 <= shell < N/2.
    """
    n = grid.n_modes
    if not check.is_integer(shell) or not 1 <= int(shell) < n // 2:
        check.reject("spectral_tail", "shell", shell, f"must be an integer in [1, {n // 2 - 1}]")
    grid.check_shape(f)
    spectrum = xp.abs(xp.fft.rfftn(f, axes=tuple(range(grid.dimension))))
    zero = float(spectrum[(0,) * grid.dimension])
    if not zero > 0.0:
        check.reject("spectral_tail", "f", "f", "must have a positive mass (hat f_0 > 0)")
    return float(xp.max(spectrum[xp.asarray(outer_band(grid, int(shell)))])) / zero


def outer_band(grid, shell: int = 1) -> numpy.ndarray:
    """The rfft-layout mask (NumPy, ``grid.half_shape``) of the outermost ``shell`` evolved
    shells, N/2 - shell <= max_i |k_i| <= N/2 - 1 (:func:`spectral_tail`)."""
    n = grid.n_modes
    largest = numpy.zeros(grid.half_shape, dtype=int)
    for axis, k in enumerate(grid.half_wavenumbers()):
        shape = [-1 if j == axis else 1 for j in range(grid.dimension)]
        largest = numpy.maximum(largest, numpy.abs(k).astype(int).reshape(shape))
    return (largest >= n // 2 - shell) & (largest <= n // 2 - 1)


def mass_beyond(grid, f, radius: float, xp=numpy) -> float:
    r"""int_{|v - u| > radius} |f| dv / int |f| dv, with u the mean velocity of f.

    For a Maxwellian of temperature T this is Q(d/2, radius^2 / (2T)), the regularised upper
    incomplete gamma function (exp(-radius^2 / (2T)) in 2D).
    """
    if not check.is_real(radius) or not float(radius) > 0.0:
        check.reject("mass_beyond", "radius", radius, "must be a positive real number")
    grid.check_shape(f)
    u = grid.bulk_velocity(f, xp)
    distance = sum((c - float(ui)) ** 2 for c, ui in zip(grid.mesh(xp), u))
    absolute = xp.abs(f)
    return float(xp.sum(absolute * (distance > float(radius) ** 2))) / float(xp.sum(absolute))


def pair_share_beyond(grid, f, radius: float, power: float = 0.0, xp=numpy) -> float:
    r"""The share of pairs with |v - v_*| > ``radius``, weighted by |v - v_*|^p:

    .. math:: \frac{\iint_{|v - v_*| > R} |v - v_*|^p |f(v)| |f(v_*)|\, dv\, dv_*}
                   {\iint |v - v_*|^p |f(v)| |f(v_*)|\, dv\, dv_*}.

    With p = 0 this is what truncating relative velocities to the ball B_R (R = 2S by default)
    leaves out of the collision integral. With p = lambda it is the share of the loss
    frequency, and with p = lambda + 2 the share of the energy dissipation of a
    |g|^lambda kernel. The autocorrelation of |f| is computed by FFT on a grid padded to 2N
    per axis, so that no lag wraps around. For a Maxwellian of temperature T the relative
    velocity is Maxwellian at 2T, and the share is Q((d + p)/2, R^2 / (4T)).
    """
    if not check.is_real(radius) or not float(radius) > 0.0:
        check.reject("pair_share_beyond", "radius", radius, "must be a positive real number")
    grid.check_shape(f)
    d, n = grid.dimension, grid.n_modes
    axes = tuple(range(d))
    spectrum = xp.fft.rfftn(xp.abs(f), s=(2 * n,) * d, axes=axes)
    correlation = xp.fft.irfftn(spectrum * xp.conj(spectrum), s=(2 * n,) * d, axes=axes)
    distance = squared_lags(grid)
    weight = xp.asarray(distance ** (float(power) / 2))
    beyond = xp.asarray(distance > float(radius) ** 2)
    weighted = correlation * weight
    return float(xp.sum(weighted * beyond)) / float(xp.sum(weighted))


def squared_lags(grid) -> numpy.ndarray:
    """|v - v_*|^2 of the lags of the autocorrelation of f on the grid padded to 2N per
    axis (NumPy, (2N,) * d; :func:`pair_share_beyond`)."""
    d, n = grid.dimension, grid.n_modes
    lag = numpy.fft.fftfreq(2 * n, 1.0 / (2 * n)) * grid.spacing
    return sum(numpy.reshape(lag, [-1 if i == j else 1 for j in range(d)]) ** 2
               for i in range(d))


#: Estimated error per unit of spectral tail: in studies/free_cooling.py a temperature error
#: of 1e-3 came with a tail of 3.5e-4, so error ~ 3 x tail (the factor granframe advise uses).
TAIL_ERROR_FACTOR = 3.0


def resolution_report(grid, f, negative_share: float, tolerance: float, xp=numpy) -> dict:
    r"""The resolution indicators of f and what to raise when one exceeds ``tolerance``.

    Returns ``spectral_tail`` (:func:`spectral_tail`, outermost shell), ``tail_error``
    (``TAIL_ERROR_FACTOR`` times it: the error it predicts), ``pairs_beyond_support``
    (:func:`pair_share_beyond` at R = 2S, unweighted: the share of pairs whose relative
    speed the operators cut off), ``negative_mass_fraction`` (``negative_share``, from the
    moments) and ``warnings``: one sentence per indicator above ``tolerance``, naming the
    grid parameter to raise (``grid.n_modes`` for the tail and the negative share,
    ``grid.support_radius`` for the pairs beyond 2S). An f that N does not resolve spreads
    |f| over the whole box through its oscillations, so the pairs beyond 2S then also
    point at N first.
    """
    return resolution_entry(grid, spectral_tail(grid, f, xp=xp),
                            pair_share_beyond(grid, f, 2.0 * grid.support_radius, xp=xp),
                            negative_share, tolerance)


def resolution_entry(grid, tail: float, beyond: float, negative_share: float,
                     tolerance: float) -> dict:
    """The report of :func:`resolution_report` from its three measured indicators (the
    spectral tail, the share of pairs beyond 2S, the negative mass share): the tail error
    and the warnings added."""
    error = TAIL_ERROR_FACTOR * tail
    warnings = []
    if error > tolerance:
        shown, limit = check.distinct(error, tolerance)
        warnings.append(f"velocity resolution: spectral tail {tail:.3g}, estimated error "
                        f"{shown} > health.resolution_tolerance = {limit}; raise "
                        f"grid.n_modes (N = {grid.n_modes})")
    if negative_share > tolerance:
        shown, limit = check.distinct(negative_share, tolerance)
        warnings.append(f"positivity: negative mass share {shown} > "
                        f"health.resolution_tolerance = {limit}; f oscillates, raise "
                        f"grid.n_modes (N = {grid.n_modes})")
    if beyond > tolerance:
        shown, limit = check.distinct(beyond, tolerance)
        warnings.append(f"support: share {shown} of pairs with relative speed beyond "
                        f"R = 2S = {2.0 * grid.support_radius:g} > "
                        f"health.resolution_tolerance = {limit}; raise grid.support_radius"
                        + (" once N resolves f" if warnings else ""))
    return {"spectral_tail": tail, "tail_error": error, "pairs_beyond_support": beyond,
            "negative_mass_fraction": float(negative_share), "warnings": warnings}
