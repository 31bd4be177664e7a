r"""The cooling rate of a granular gas: zeta in dT/dt = -zeta T / eps for a Maxwellian.

From the weak form in the sigma-representation, one collision of relative velocity
g = v - v_* changes the energy by |v'|^2 + |v'_*|^2 - |v|^2 - |v_*|^2
= -(1 - e(|g|)^2)/4 |g|^2 (1 - g.sigma/|g|), so that for B = C |g|^lambda b(g.sigma/|g|)

.. math:: \int Q(f,f)|v|^2 dv = -\frac{C\beta}{8}\iint f f_*
          |g|^{\lambda+2}\bigl(1 - e(|g|)^2\bigr)\,dv\,dv_*,\qquad
          \beta = \int_{S^{d-1}} b(\hat g\cdot\sigma)(1 - \hat g\cdot\sigma)\,d\sigma

(Brilliantov & Poeschel, Kinetic Theory of Granular Gases, Oxford 2004, ch. 6; Villani,
J. Stat. Phys. 124 (2006) 781, for the sigma-representation). For a Maxwellian of density
rho and temperature T the double integral is rho^2 times the average over its relative
speeds, and with d/dt int |v|^2 f = rho d dT/dt this is the rate of
:func:`maxwellian_cooling_rate`. For Maxwell molecules (lambda = 0) and a constant e the
double integral is 2 rho (d rho T) for any f at rest, so the rate is exact for any f.
"""

from __future__ import annotations

import math

import numpy
import scipy.special

#: Gauss-Laguerre nodes of the averages over the relative speeds of a Maxwellian
LAGUERRE_NODES = 96


def relative_speed_average(function, dimension: int, temperature,
                           nodes: int = LAGUERRE_NODES):
    r"""<F(s)> over the relative speeds s = |v - v_*| of two particles of a Maxwellian at
    temperature T (s is the speed of a d-dimensional Maxwellian at 2T):

    .. math:: \langle F\rangle = \frac{\int_0^\infty F(s)\, s^{d-1} e^{-s^2/4T}\,ds}
                                      {\int_0^\infty s^{d-1} e^{-s^2/4T}\,ds}
              = \frac{1}{\Gamma(d/2)}\sum_i w_i F\bigl(2\sqrt{T y_i}\bigr),

    with (y_i, w_i) the ``nodes``-point generalised Gauss-Laguerre rule of weight
    y^{d/2-1} e^{-y} (Abramowitz & Stegun 25.4.45; substitute y = s^2/4T). It is exact for
    F a polynomial in s^2 of degree < ``nodes``; odd powers of s are not polynomials in y,
    and with 96 nodes <s> is off by 1.2e-4 in 2D (1.1e-5 in 3D), <s^3> (the cooling rate of
    hard disks and spheres) by 7e-7 (7e-8).

    Parameters
    ----------
    function : callable
        F, vectorised over an array of speeds.
    dimension : int
        d.
    temperature : float or array_like
        T > 0; an array gives the average at each of its temperatures.

    Returns
    -------
    float or numpy.ndarray
        <F>, of the shape of ``temperature``.
    """
    y, w = scipy.special.roots_genlaguerre(nodes, dimension / 2 - 1)
    temperature = numpy.asarray(temperature, dtype=float)
    speeds = 2.0 * numpy.sqrt(temperature[..., None] * y)
    average = numpy.asarray(function(speeds), dtype=float) @ w / math.gamma(dimension / 2)
    return float(average) if average.ndim == 0 else average


def maxwellian_cooling_rate(restitution, density=1.0, temperature=1.0, *, dimension: int = 3,
                            speed_exponent: float = 0.0, scattering: float = 1.0):
    r"""zeta in dT/dt = -zeta T / eps of a Maxwellian (rho, T), for the kernel
    B = C |g|^lambda b and the restitution coefficient e (module notes):

    .. math:: \zeta = \frac{C\beta\,\rho}{8 d T}
              \bigl\langle s^{\lambda+2}(1 - e(s)^2)\bigr\rangle_{2T},

    which for a constant e is

    .. math:: \zeta = C\beta\,\rho\,(1 - e^2)\,(4T)^{\lambda/2}
              \frac{\Gamma((d + \lambda + 2)/2)}{2 d\,\Gamma(d/2)}

    (Brilliantov & Poeschel 2004, ch. 6, at first order in the Sonine expansion, a_2 = 0;
    :func:`granframe.theory.sonine.hard_sphere_cooling_rate` adds the a_2 correction):

    - Maxwell molecules (lambda = 0), any d: zeta = C beta rho (1 - e^2)/4, rho (1 - e^2)/4
      with the review's B = 1/|S^{d-1}| (C beta = 1), exact for any f at rest (the rate of
      Haff's exponential law and of :func:`granframe.model.exact.heated_maxwell_temperature`);
    - 3D hard spheres B = |g|/(4 pi) (lambda = 1, C beta = 1): zeta = 4 (1 - e^2) rho
      sqrt(T) / (3 sqrt(pi)), Haff's law (Haff, J. Fluid Mech. 134 (1983) 401).

    Parameters
    ----------
    restitution : float or callable
        A constant e in [0, 1], or e(s) of the relative speed (vectorised).
    density, temperature : float or array_like
        rho and T > 0 (arrays broadcast for a constant e; T a scalar for e(s)).
    dimension : int
        d (the rate of Maxwell molecules does not depend on it).
    speed_exponent : float
        lambda of |g|^lambda.
    scattering : float
        C beta, with beta = int_{S^{d-1}} b (1 - cos theta) dsigma (times E^gamma for a
        kernel with an energy factor): 1 for the review's kernels.

    Returns
    -------
    float or numpy.ndarray
        zeta.
    """
    d, lam = dimension, speed_exponent
    if callable(restitution):
        average = relative_speed_average(
            lambda s: s ** (lam + 2) * (1.0 - numpy.asarray(restitution(s)) ** 2), d,
            temperature)
        return scattering * density * average / (8.0 * d * temperature)
    ratio = (math.exp(math.lgamma((d + lam + 2) / 2) - math.lgamma(d / 2)) if lam
             else d / 2)                     # Gamma((d + lambda + 2)/2) / Gamma(d/2)
    e = restitution
    return (scattering * density * (1.0 - e * e) * (4.0 * temperature) ** (lam / 2)
            * (ratio / (2 * d)))
