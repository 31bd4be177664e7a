r"""First-Sonine transport coefficients and cooling rate of 3D inelastic hard spheres.

In granframe's units (B = |g|/(4 pi), Q/eps: pi sigma^2 = 1/eps, unit mass) the first
Sonine approximation of the Chapman-Enskog solution about the homogeneous cooling state
(Brey, Dufty, Kim & Santos, Phys. Rev. E 58 (1998) 4638; Garzo & Dufty, Phys. Rev. E 59
(1999) 5895, in the dilute limit) gives, with eta_0 = (5/16) eps sqrt(pi T) the elastic
viscosity, kappa_0 = (75/64) eps sqrt(pi T) the elastic conductivity and
nu_0 = rho T / eta_0,

    zeta = nu_0 zeta*,   zeta* = (5/12)(1 - e^2)(1 + 3 a_2 / 16),
    eta  = eta_0 / (nu_eta* - zeta*/2),   nu_eta* = (3 - e)(1 + e)/4 (1 - a_2/32),
    a_2  = 16 (1 - e)(1 - 2 e^2) / (81 - 17 e + 30 e^2 (1 - e))   (van Noije & Ernst,
           Granular Matter 1 (1998) 57),

and for the heat flux q = -kappa grad T - mu grad n

    kappa* = kappa/kappa_0 = (2/3)(1 + 2 a_2) / (nu_kappa* - 2 zeta*),
    nu_kappa* = (1 + e)/3 (1 + 33 (1 - e)/16 + (19 - 3e) a_2 / 512),
    mu* = n mu / (T kappa_0) = 2 (zeta* kappa* + 2 a_2 / 3) / (2 nu_kappa* - 3 zeta*)

(the same expressions, with c* = 2 a_2, are the dilute limit of the GD99 model of the MFIX
code, model/calc_mu_s.f; docs/granular.md).
"""

from __future__ import annotations

import math


def transport_coefficients(restitution: float) -> dict:
    r"""The first-Sonine a_2, zeta*, eta* = eta/eta_0, kappa* = kappa/kappa_0 and
    mu* = n mu/(T kappa_0) of 3D inelastic hard spheres with a constant restitution
    coefficient e (module notes: Brey et al. 1998, Garzo & Dufty 1999, van Noije & Ernst
    1998). An elastic gas (e = 1) has a_2 = zeta* = mu* = 0, eta* = kappa* = 1.

    Returns
    -------
    dict
        ``a2``, ``zeta*``, ``eta*``, ``kappa*``, ``mu*``.
    """
    e = restitution
    a2 = 16 * (1 - e) * (1 - 2 * e * e) / (81 - 17 * e + 30 * e * e * (1 - e))
    zeta = 5 / 12 * (1 - e * e) * (1 + 3 * a2 / 16)
    nu_eta = (3 - e) * (1 + e) / 4 * (1 - a2 / 32)
    nu_kappa = (1 + e) / 3 * (1 + 33 * (1 - e) / 16 + (19 - 3 * e) * a2 / 512)
    kappa = 2 / 3 * (1 + 2 * a2) / (nu_kappa - 2 * zeta)
    mu = 2 * (zeta * kappa + 2 * a2 / 3) / (2 * nu_kappa - 3 * zeta)
    return {"a2": a2, "zeta*": zeta, "eta*": 1 / (nu_eta - zeta / 2), "kappa*": kappa,
            "mu*": mu}


def elastic_viscosity(knudsen: float, temperature: float) -> float:
    r"""eta_0 = (5/16) eps sqrt(pi T): the shear viscosity of elastic 3D hard spheres in
    granframe's units (pi sigma^2 = 1/eps, unit mass), the first Chapman-Enskog
    approximation eta_0 = (5/(16 sigma^2)) sqrt(m T / pi) (Chapman & Cowling, The
    Mathematical Theory of Non-uniform Gases, 3rd ed., 1970, section 10.21; docs/space.md)."""
    return 5 / 16 * knudsen * math.sqrt(math.pi * temperature)


def reference_frequency(knudsen: float, density: float, temperature: float) -> float:
    r"""nu_0 = rho T / eta_0 = 16 rho sqrt(T) / (5 eps sqrt(pi)), the collision frequency
    that makes the first-Sonine coefficients dimensionless (:func:`elastic_viscosity`;
    Brey et al. 1998)."""
    return 16 * density * math.sqrt(temperature) / (5 * knudsen * math.sqrt(math.pi))


def hard_sphere_cooling_rate(restitution: float, knudsen: float, density: float,
                             temperature: float) -> float:
    r"""zeta = nu_0 zeta* in dT/dt = -zeta T of 3D inelastic hard spheres in their homogeneous
    cooling state, first Sonine approximation (module notes):

        zeta = (rho T / eta_0) (5/12)(1 - e^2)(1 + 3 a_2/16)
             = 16 rho sqrt(T) / (5 eps sqrt(pi)) (5/12)(1 - e^2)(1 + 3 a_2/16)

    (van Noije & Ernst 1998; Brey et al. 1998; Brilliantov & Poeschel, Kinetic Theory of
    Granular Gases, 2004, ch. 6): the Maxwellian's rate
    :func:`~granframe.theory.cooling.maxwellian_cooling_rate` (with 1/eps) times
    1 + 3 a_2/16."""
    return (density * temperature / elastic_viscosity(knudsen, temperature)
            * transport_coefficients(restitution)["zeta*"])
