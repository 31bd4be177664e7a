"""Quantities the studies extract from runs: relative entropy, decay rates, tail exponents,
the energy budget of a space run with walls, the rates of the modes of the cooling state."""

from __future__ import annotations

import math

import numpy


def relative_entropy(f, g, cell_volume):
    """H(f|g) = int f ln(f/g) dv over the points where both are positive (rectangle rule)."""
    mask = (f > 0) & (g > 0)
    return float(numpy.sum(f[mask] * numpy.log(f[mask] / g[mask]))) * cell_volume


def fit_line(x, y):
    """Least-squares y = a + b x; returns (b, a, standard error of b)."""
    x, y = numpy.asarray(x, float), numpy.asarray(y, float)
    if len(x) < 3:
        raise ValueError(f"fit: needs at least 3 points, got {len(x)}")
    design = numpy.stack([numpy.ones_like(x), x], axis=1)
    (a, b), residual, _, _ = numpy.linalg.lstsq(design, y, rcond=None)
    dof = len(x) - 2
    sigma2 = float(residual[0]) / dof if dof > 0 and len(residual) else 0.0
    stderr = (sigma2 / float(((x - x.mean()) ** 2).sum())) ** 0.5
    return float(b), float(a), stderr


def exponential_rate(times, values, window):
    """Fit values ~ C exp(-lambda t) over ``window`` = (t_min, t_max); returns (lambda, stderr)."""
    times, values = numpy.asarray(times), numpy.asarray(values)
    use = (times >= window[0]) & (times <= window[1]) & (values > 0)
    slope, _, stderr = fit_line(times[use], numpy.log(values[use]))
    return -slope, stderr


def tail_exponent(speed, f, window):
    r"""Fit f ~ C exp(-c |v|^alpha) over ``window`` = (v_min, v_max) of |v|.

    ln(-ln(f / C)) is linear in ln|v| with slope alpha, but C is unknown; so the fit
    is made on d ln f / d|v| = -c alpha |v|^{alpha-1}: ln(-d ln f/d|v|) against ln|v|
    has slope alpha - 1. Returns (alpha, stderr).
    """
    speed, f = numpy.asarray(speed, float), numpy.asarray(f, float)
    keep = f > 0
    # points at the same |v| (both sides of a slice, equal up to round-off) are merged:
    # their mean ln f
    speed, inverse = numpy.unique(numpy.round(speed[keep], 9), return_inverse=True)
    log_f = numpy.bincount(inverse, numpy.log(f[keep])) / numpy.bincount(inverse)
    middle = 0.5 * (speed[1:] + speed[:-1])
    slope = numpy.diff(log_f) / numpy.diff(speed)
    use = (middle >= window[0]) & (middle <= window[1]) & (slope < 0)
    b, _, stderr = fit_line(numpy.log(middle[use]), numpy.log(-slope[use]))
    return b + 1.0, stderr


def energy_balance(ds, operator, knudsen: float, window: float = 0.2,
                   length: float = 1.0) -> dict:
    r"""The energy budget of a space run with walls at its last step.

    ``ds``: the run's dataset with the steps as its time axis (``f``, ``dt``,
    ``wall_energy``, ``kinetic_energy``); ``operator``: the run's collision operator
    (``operator.grid`` its velocity grid); ``length``: the interval's.

    ``heat``: what both walls put in per unit time, sum_walls wall_energy / dt (the last
    step; ``heat_window``: averaged over the last ``window`` of the steps);
    ``dissipation``: sum_cells dx h^d sum_j Q_j |v_j|^2 / 2 / eps of the final snapshot,
    Q the run's operator; ``dEdt``: the change of the total energy over the last step / dt.
    Every step E^{n+1} - E^n = (wall energy) + (collision step's energy change), so
    ``mismatch`` = (heat + dissipation)/heat equals dEdt/heat (``unsteadiness``) plus
    ``residual`` = (heat + dissipation - dEdt)/heat, the collision step's energy change
    against its rate at the end of the step (splitting and time error, O(dt)).
    """
    f = ds.f.values[-1]
    grid = operator.grid
    dx = length / ds.sizes["x"]
    q = numpy.asarray(operator(f))
    dissipation = float(numpy.sum(q * grid.speed_squared()) * grid.cell_volume
                        * 0.5 * dx / knudsen)
    dt = ds.dt.values[1:]
    heat_rate = ds.wall_energy.values[1:].sum(axis=1) / dt
    count = max(1, int(window * len(heat_rate)))
    energy = ds.kinetic_energy.values
    heat = float(heat_rate[-1])
    dEdt = float((energy[-1] - energy[-2]) / dt[-1])
    return {"heat": heat, "heat_window": float(heat_rate[-count:].mean()),
            "dissipation": dissipation, "dEdt": dEdt,
            "mismatch": (heat + dissipation) / heat, "unsteadiness": dEdt / heat,
            "residual": (heat + dissipation - dEdt) / heat}


def last_quarter(s, skip: float):
    """Where s lies in the last quarter of the window skip <= s <= s[-1]."""
    s = numpy.asarray(s)
    return s >= skip + 0.75 * (s[-1] - skip)


def relaxed_rate(s, amplitude, skip: float) -> dict:
    """The rate Gamma of a mode's amplitude A(s) > 0 in the hydrodynamic regime, after the
    kinetic relaxation of its initial data.

    Past the first collision times the local rate d ln A / ds approaches Gamma
    geometrically, so over s >= ``skip`` the least-squares fit is

        ln A(s) = c + Gamma s + b exp(-mu s),

    linear in (c, Gamma, b) for each mu, mu by a bounded scalar search in [0.05, 20] (the
    relaxation rate, of the order of the collision frequency). ``late`` is the straight-line
    slope over the last quarter of the window: it differs from Gamma by what is left of
    the relaxation there. A straight line over the whole window would carry the
    relaxation into the rate (+4.7e-4 at e = 0.9, +2.4e-3 at e = 0.5 over 1 <= s <= 4, for
    the shear mode of the cooling state, docs/granular.md).

    Returns
    -------
    dict
        ``rate`` (Gamma), ``late`` and ``relaxation`` (mu).
    """
    import scipy.optimize

    s, amplitude = numpy.asarray(s, float), numpy.asarray(amplitude, float)
    keep = s >= skip
    s, log_a = s[keep], numpy.log(amplitude[keep])

    def fit(mu):
        basis = numpy.stack([numpy.ones_like(s), s, numpy.exp(-mu * (s - s[0]))], axis=1)
        coefficients, *_ = numpy.linalg.lstsq(basis, log_a, rcond=None)
        return coefficients, float(numpy.sum((basis @ coefficients - log_a) ** 2))

    mu = scipy.optimize.minimize_scalar(lambda m: fit(m)[1], bounds=(0.05, 20.0),
                                        method="bounded",
                                        options={"xatol": 1e-8}).x
    late = last_quarter(s, skip)
    return {"rate": float(fit(mu)[0][1]),
            "late": float(numpy.polyfit(s[late], log_a[late], 1)[0]),
            "relaxation": float(mu)}


def cooling_state_rate(s, density, temperature, rescaling_rate: float, skip: float) -> float:
    """zeta_g / 2, half the collisional cooling rate of g in the cooling state a rescaled
    run reaches (not a_0, the rescaling rate, which is that of the Maxwellian f0): with
    T the mass-weighted mean temperature over the cells (``density`` and ``temperature``:
    records x cells of any shape), d ln T / ds = 2 a_0 - zeta_g, fitted by a straight line
    over the last quarter of s >= ``skip``."""
    s = numpy.asarray(s, float)
    density = numpy.asarray(density, float).reshape(len(s), -1)
    temperature = numpy.asarray(temperature, float).reshape(len(s), -1)
    mean = (density * temperature).sum(axis=1) / density.sum(axis=1)
    window = last_quarter(s, skip)
    slope = numpy.polyfit(s[window], numpy.log(mean[window]), 1)[0]
    return float(rescaling_rate - slope / 2)


def heat_and_sound(s, amplitude, sound: complex, skip: float) -> dict:
    r"""The heat mode's rate from a density amplitude that also carries the sound pair.

    A run started on the Navier-Stokes heat mode as a local Maxwellian has no heat flux at
    s = 0; while the flux builds up over the first collision times it excites the sound
    pair a little (a per cent of the amplitude), which is damped only over ~10 s, so the
    slope of ln A is the heat mode's only after several runs' lengths. Over s >= ``skip``
    the least-squares fit

        A(s) = a exp(lambda s) + exp(sigma s) (b cos(omega s) + c sin(omega s)),

    with sigma + i omega = ``sound`` (the Navier-Stokes sound pair, per unit s), is linear
    in (a, b, c) for each lambda, and lambda is found by a bounded scalar search. Returns
    ``rate`` (lambda), ``sound/heat`` (|b + i c|/a) and ``rms`` (the fit's residual over
    the mean amplitude)."""
    import scipy.optimize

    keep = numpy.asarray(s) >= skip
    s, amplitude = numpy.asarray(s)[keep], numpy.asarray(amplitude)[keep]
    damping = numpy.exp(sound.real * s)

    def fit(rate):
        basis = numpy.stack([numpy.exp(rate * s), damping * numpy.cos(sound.imag * s),
                             damping * numpy.sin(sound.imag * s)], axis=1)
        coefficients, *_ = numpy.linalg.lstsq(basis, amplitude, rcond=None)
        return coefficients, float(numpy.sum((basis @ coefficients - amplitude) ** 2))

    rate = scipy.optimize.minimize_scalar(lambda r: fit(r)[1], bounds=(-1.0, 1.0),
                                          method="bounded", options={"xatol": 1e-10}).x
    (a, b, c), residual = fit(rate)
    return {"rate": float(rate), "sound/heat": float(math.hypot(b, c) / abs(a)),
            "rms": math.sqrt(residual / s.size) / float(numpy.mean(numpy.abs(amplitude)))}


def heat_mode_rates(s, amplitude, restitution: float, wavenumber: float,
                    temperature: float, half_zeta: float, skip: float,
                    knudsen: float = 1.0) -> tuple[dict, dict]:
    r"""The heat mode's rate in s of a rescaled run of 3D hard spheres, measured from the
    density's amplitude A(s) of its wave, against Navier-Stokes.

    The Navier-Stokes rates are lambda_h(k*, zeta*) nu_0(T_g)
    (:func:`~granframe.theory.modes.heat_mode`) at k* = k sqrt(T_g) / nu_0(T_g), T_g the
    run's mean temperature at the end, with zeta* = 2 (zeta_g / 2) / nu_0(T_g) the run's own
    cooling rate (``half_zeta``, :func:`cooling_state_rate`) and with the first Sonine
    zeta*. The measured rate is :func:`heat_and_sound`'s, the sound pair taken from the
    eigenvalues of :func:`~granframe.theory.modes.longitudinal_matrix` (k*, zeta*) of the
    largest imaginary part; ``measured late`` the straight slope of ln A over the last
    quarter of s >= ``skip``.

    Returns
    -------
    rates : dict
        ``measured rate``, ``measured late``, ``sound/heat``, ``fit rms``,
        ``Navier-Stokes rate with zeta_g`` and ``Navier-Stokes rate (Sonine zeta)``.
    scales : dict
        ``nu0``, ``k*`` and ``zeta*`` (the run's) of the comparison.
    """
    from granframe.theory.modes import heat_mode, longitudinal_matrix
    from granframe.theory.sonine import reference_frequency

    nu0 = reference_frequency(knudsen, 1.0, temperature)
    k_star = wavenumber * math.sqrt(temperature) / nu0
    zeta = 2 * half_zeta / nu0
    values = numpy.linalg.eigvals(longitudinal_matrix(restitution, k_star, zeta)) * nu0
    fit = heat_and_sound(s, amplitude, complex(values[numpy.argmax(values.imag)]), skip)
    s, amplitude = numpy.asarray(s), numpy.asarray(amplitude)
    late = last_quarter(s, skip)
    rates = {"measured rate": fit["rate"],
             "measured late": float(numpy.polyfit(s[late], numpy.log(amplitude[late]),
                                                  1)[0]),
             "sound/heat": fit["sound/heat"], "fit rms": fit["rms"],
             "Navier-Stokes rate with zeta_g": heat_mode(restitution, k_star, zeta)[0] * nu0,
             "Navier-Stokes rate (Sonine zeta)": heat_mode(restitution, k_star)[0] * nu0}
    return rates, {"nu0": nu0, "k*": k_star, "zeta*": zeta}


def cluster_monitors(ds) -> dict:
    """What the run's monitors say: the largest mass drift, the smallest f, the largest
    negative mass share, the density contrast rho_max/rho_min and the coldest cell's
    T/<T> (over all cells, on a line or a rectangle) at the end, and the step at which the
    accuracy monitor first flagged (if it did), from the dataset ``ds`` of a run
    (:func:`granframe.open_run` with ``time_axis="steps"``)."""
    mass = ds.mass.values
    density = ds.density.values
    temperature = ds.temperature.values
    return {"s": float(ds.time.values[-1]), "steps": int(len(mass) - 1),
            "mass drift": float(numpy.abs(mass / mass[0] - 1.0).max()),
            "min f / max f0": float(ds.min_f.values.min()),
            "negative mass share": float(ds.negative_mass_fraction.values.max()),
            "rho max/min": float(density[-1].max() / density[-1].min()),
            "T min/mean": float(temperature[-1].min() / temperature[-1].mean()),
            "status": ds.attrs.get("progress_status"),
            "accuracy flagged at s": ds.attrs.get("progress_accuracy_flagged_time"),
            "accuracy flagged monitor": ds.attrs.get("progress_accuracy_flagged_monitor")}
