"""Granular phenomena in space against theory (studies/granular_hcs.py, docs/granular.md):
the first-Sonine coefficients of 3D inelastic hard spheres, and a quick variant of the
shear mode of the homogeneous cooling state in the rescaled formulation."""

import importlib.util
import json
import math
import pathlib
import re
import subprocess
import sys

import numpy
import pytest
import scipy.integrate
import scipy.optimize

import granframe
from granframe.run.runner import HealthError, Simulation
from granframe.tools.studykit import finish, json_text

STUDIES = pathlib.Path(__file__).parent.parent / "studies"


def _study(name):
    path = STUDIES / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"{name}_study", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


HCS = _study("granular_hcs")


def _assert_drawn(study, stores, path):
    """The study's figure of ``stores`` is written: a PNG with something drawn in it."""
    study.figure(stores, path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 20_000


def test_sonine_coefficients_reduce_to_the_elastic_gas_and_match_the_table():
    elastic = HCS.sonine(1.0)
    assert elastic == {"a2": 0.0, "zeta*": 0.0, "eta*": 1.0, "kappa*": 1.0, "mu*": 0.0}
    # the table of docs/granular.md (the dilute limit of MFIX's GD99 model agrees to 2e-16)
    for e, kappa, mu in ((0.9, 1.068491, 0.115695), (0.7, 1.357967, 0.483735),
                         (0.5, 1.911421, 1.174914)):
        assert HCS.sonine(e)["kappa*"] == pytest.approx(kappa, abs=1e-6)
        assert HCS.sonine(e)["mu*"] == pytest.approx(mu, abs=1e-6)
    # van Noije & Ernst: a_2 changes sign at e = 1/sqrt(2)
    assert HCS.sonine(2 ** -0.5)["a2"] == pytest.approx(0.0, abs=1e-15)
    assert HCS.sonine(0.9)["a2"] == pytest.approx(-0.01456, abs=1e-5)
    assert HCS.sonine(0.5)["zeta*"] == pytest.approx(0.3156, abs=1e-4)
    # eta_0 = (5/16) eps sqrt(pi T): the elastic Chapman-Enskog viscosity of docs/space.md
    assert HCS.theory(1.0, 0.3, 1.0, 2.0, 0.0)["eta"] == pytest.approx(
        5 / 16 * 0.3 * math.sqrt(2 * math.pi), rel=1e-14)


def test_the_measured_rate_is_that_of_the_hydrodynamic_regime_past_the_relaxation():
    """A mode whose local rate relaxes geometrically to Gamma, ln A = c + Gamma s +
    b exp(-mu s), u_2/sqrt(T) = A sin(k x) on 8 cells: ``measured_rate`` gives Gamma and mu,
    where a straight line over the same window is off by the relaxation."""
    import xarray

    length, cells, gamma, mu = 20.0, 8, 0.0531, 1.7
    s = numpy.arange(0.0, 4.0001, 0.05)
    amplitude = 0.02 * numpy.exp(gamma * s + 0.01 * numpy.exp(-mu * s))
    x = (numpy.arange(cells) + 0.5) * length / cells
    temperature = numpy.full((s.size, cells), 1.3)
    velocity = numpy.zeros((s.size, cells, 3))
    velocity[:, :, 1] = (amplitude[:, None] * numpy.sin(2 * math.pi * x / length)
                         * numpy.sqrt(temperature))
    ds = xarray.Dataset({"velocity": (("time", "x", "axis"), velocity),
                         "temperature": (("time", "x"), temperature)},
                        coords={"time": s, "x": x})
    result = HCS.measured_rate(ds, length, 1.0)
    assert result["rate"] == pytest.approx(gamma, abs=1e-9)
    assert result["relaxation"] == pytest.approx(mu, rel=1e-5)
    keep = s >= 1.0
    straight = numpy.polyfit(s[keep], numpy.log(amplitude[keep]), 1)[0]
    assert abs(straight - gamma) > 1e-4 and abs(result["late"] - gamma) > 1e-6


def test_the_cooling_rate_of_g_is_read_from_the_drift_of_its_temperature():
    """T_g(s) = exp((2 a_0 - zeta_g) s) in every cell, any density profile: cooling_rate
    gives zeta_g / 2, not the rescaling rate a_0."""
    import xarray

    a_0, zeta = 0.2820, 0.5664
    s = numpy.arange(0.0, 4.0001, 0.05)
    density = numpy.tile(1.0 + 0.1 * numpy.sin(numpy.arange(8)), (s.size, 1))
    temperature = numpy.exp((2 * a_0 - zeta) * s)[:, None] * numpy.ones(8)
    ds = xarray.Dataset({"density": (("time", "x"), density),
                         "temperature": (("time", "x"), temperature)},
                        coords={"time": s}, attrs={"rescaling_rate": a_0})
    assert HCS.cooling_rate(ds, 1.0) == pytest.approx(zeta / 2, rel=1e-12)


def test_a_long_shear_mode_of_the_cooling_state_grows_at_the_navier_stokes_rate(tmp_path):
    """e = 0.8, k = k_c/2, 8 cells, N = 16, to s = 3: the mode grows, at the rate
    zeta_g/2 - eta k^2 / rho with the run's own cooling rate zeta_g (its T_g drift) within
    3 % (measured: 1.3 % below, the damping of 8 cells per wavelength, about 1 %, and
    N = 16; the study's converged runs: docs/granular.md)."""
    e = 0.8
    k = 0.5 * HCS.theory(e, 1.0, 1.0, 1.0, 1.0)["k_c"]
    length = 2 * math.pi / k
    store = tmp_path / "shear.zarr"
    Simulation(HCS.description(e, length, 8, 16, 3.5, 3.0)).run(store, progress=False)
    ds = granframe.open_run(store, time_axis="steps")
    measured = HCS.measured_rate(ds, length, 1.0)["rate"]
    eta = HCS.theory(e, 1.0, 1.0, float(ds.temperature.values[-1].mean()), k)["eta"]
    predicted = HCS.cooling_rate(ds, 1.0) - eta * k * k
    assert predicted > 0.05 and measured == pytest.approx(predicted, rel=0.03)
    _assert_drawn(HCS, [store], tmp_path / "modes.png")


WALLS = _study("granular_walls")


def test_the_navier_stokes_profile_between_heated_walls_solves_its_problem():
    """W = (T/T_b)^(3/2) solves W'' = Lambda W^(-1/3) with W = 1 at the walls, the mass
    is 1, Lambda = C rho_b^2, and for small Lambda T_min/T_b = 1 - Lambda/12 + O(Lambda^2);
    an elastic gas is uniform."""
    result = WALLS.navier_stokes(0.9, 0.1)
    y, t = result["distance"], result["T/T_b"]
    w = t ** 1.5
    h = y[1] - y[0]
    second = (w[2:] - 2 * w[1:-1] + w[:-2]) / h ** 2
    assert numpy.allclose(second, result["Lambda"] * w[1:-1] ** (-1 / 3), rtol=2e-3)
    assert t[-1] == pytest.approx(1.0, abs=1e-12) and t[0] == result["T_min/T_b"] < 0.6
    mass = 2 * result["rho_b"] * scipy.integrate.simpson(1 / t, x=y)
    assert mass == pytest.approx(1.0, abs=1e-9)
    coefficients = HCS.sonine(0.9)
    c = 6.144 * coefficients["zeta*"] / (math.pi * 0.02 * (coefficients["kappa*"]
                                                         - coefficients["mu*"]))
    assert result["Lambda"] == pytest.approx(c * result["rho_b"] ** 2, rel=1e-9)
    dilute = WALLS.navier_stokes(0.9, 2.0)
    assert dilute["T_min/T_b"] == pytest.approx(1 - dilute["Lambda"] / 12,
                                                abs=dilute["Lambda"] ** 2)
    assert WALLS.navier_stokes(1.0, 0.1)["T_min/T_b"] == 1.0


@pytest.mark.parametrize("e, knudsen", [(0.9, 0.2), (0.7, 0.5)])
def test_the_reduced_wall_problem_is_the_granular_energy_balance(e, knudsen):
    """The energy balance before its reduction to W'' = Lambda W^(-1/3): d/dx(kappa_0
    (kappa* - mu*) dT/dx) = (3/2) nu_0 zeta* rho T with rho = p/T, kappa_0 = (75/64) eps
    sqrt(pi T), nu_0 = 16 rho sqrt(T)/(5 eps sqrt(pi)), T = 1 at both walls and unit mass,
    solved as a boundary-value problem for T, the flux and the mass with p unknown, gives
    navier_stokes's rho_b = p and T_min/T_b (the constant 6.144 and the mu term checked)."""
    c = HCS.sonine(e)
    eps = math.sqrt(2.0) * knudsen

    def balance(x, y, p):
        temperature, flux, _ = y
        rho = p[0] / temperature
        kappa = 75 / 64 * eps * numpy.sqrt(math.pi * temperature) * (c["kappa*"] - c["mu*"])
        nu0 = 16 * rho * numpy.sqrt(temperature) / (5 * eps * math.sqrt(math.pi))
        return numpy.vstack([flux / kappa, 1.5 * nu0 * c["zeta*"] * rho * temperature, rho])

    def ends(left, right, p):
        return numpy.array([left[0] - 1.0, right[0] - 1.0, left[2], right[2] - 1.0])

    x = numpy.linspace(0.0, 1.0, 201)
    guess = numpy.vstack([numpy.ones_like(x), numpy.zeros_like(x), x])
    solution = scipy.integrate.solve_bvp(balance, ends, x, guess, p=[0.9], tol=1e-10)
    assert solution.status == 0
    expected = WALLS.navier_stokes(e, knudsen)
    assert solution.p[0] == pytest.approx(expected["rho_b"], rel=1e-8)
    minimum = solution.sol(numpy.linspace(0.0, 1.0, 2001))[0].min()
    assert minimum == pytest.approx(expected["T_min/T_b"], rel=1e-8)


def test_the_steady_estimate_extrapolates_a_relaxing_ratio_and_refuses_a_drift():
    """a + b exp(-k t) sampled as a run's steps (t in [0, 3]) gives a back to 1e-9 with no
    spread between the two windows; a ratio still falling linearly (no levelling off in
    the run) and a sampled oscillation give NaN, not a number."""
    times = numpy.linspace(0.0, 3.0, 262)
    relaxing = 0.5266 + 0.21 * numpy.exp(-1.05 * times)
    estimate = WALLS.steady_estimate(times, relaxing)
    assert estimate["steady"] == pytest.approx(0.5266, abs=1e-9)
    assert estimate["spread"] < 1e-9
    for history in (0.9 - 0.02 * times, 1.03 + 0.01 * numpy.sin(4.0 * times)):
        assert math.isnan(WALLS.steady_estimate(times, history)["steady"])


def test_a_quick_heated_gas_balances_its_energy_and_resumes_to_the_same_row(tmp_path, capsys):
    """6 cells, N = 16, to t = 0.3 (13 steps, f stored every 3): the mass to round-off,
    wall heat + dissipation = the energy's change to 5 % of the heat in the transient
    (the budget's time error), the gas next to the walls colder than them and denser in
    the middle; a second call with --resume finds the run finished and gives the same
    row, its warnings read back from the store."""
    argv = ["--out", str(tmp_path), "--n-modes", "16", "--cells", "6", "--final", "0.3",
            "--snapshot-every", "3", "--resume"]
    rows = []
    for _ in range(2):
        WALLS.main(argv)
        rows.append(json.loads(capsys.readouterr().out.strip().splitlines()[-1]))
    first, again = rows
    assert first == again and first["steps"] == 13 and first["warnings"]
    assert abs(first["residual"]) < 0.05 and first["heat"] > 0 > first["dissipation"]
    assert 0 < first["jump"] < 0.2 and first["rho_max/rho_b"] > 1 > first["T_min/T_b"]
    # every cell's tail error; the run's report names the largest
    tails = first["tail error by cell"]
    reported = next(re.search(r"estimated error ([0-9.e-]+) ", w) for w in first["warnings"]
                    if w.startswith("velocity resolution"))
    assert len(tails) == 6 and max(tails) == pytest.approx(float(reported.group(1)), rel=2e-3)
    assert json.loads((tmp_path / "walls_e0.9_kn0.2_c6_n16.json").read_text(),
                      parse_constant=_refuse_constant) == first
    ds = granframe.open_run(tmp_path / "walls_e0.9_kn0.2_c6_n16.zarr", time_axis="steps")
    assert ds.sizes["snapshot_time"] == 6
    assert abs(ds.mass.values[-1] / ds.mass.values[0] - 1) < 1e-13
    _assert_drawn(WALLS, [tmp_path / "walls_e0.9_kn0.2_c6_n16.zarr"], tmp_path / "walls.png")
    with pytest.raises(SystemExit):
        WALLS.main(argv[:-1] + ["--snapshot-every", "0"])
    assert ("argument --snapshot-every: '0' is not allowed: must be an integer in [1, inf]"
            in capsys.readouterr().err)


def _refuse_constant(name):
    """A strict JSON reader's answer to NaN or Infinity."""
    raise ValueError(f"not JSON: {name}")


def test_study_rows_are_strict_json_with_null_for_what_a_run_could_not_measure():
    """A heat-mode row's conduction factor is NaN where the rate cannot be inverted:
    the rows are written with null there (and for infinities, nested or in numpy
    floats), which a strict reader accepts; Python's json.dumps would write NaN."""
    row = {"e": 0.8, "conduction": math.nan, "rates": [0.02, math.inf, -math.inf],
           "fit": {"window": (numpy.float64("nan"), 2)}, "warnings": []}
    with pytest.raises(ValueError, match="NaN"):
        json.loads(json.dumps(row), parse_constant=_refuse_constant)
    assert json.loads(json_text(row, indent=1), parse_constant=_refuse_constant) == {
        "e": 0.8, "conduction": None, "rates": [0.02, None, None],
        "fit": {"window": [None, 2]}, "warnings": []}


@pytest.mark.parametrize("study, argv, message", [
    ("walls", ["--knudsen", "-1"], "argument --knudsen: '-1' is not allowed: must be a number "
                                   "in (0, inf]"),
    ("walls", ["--restitution", "1.5"], "argument --restitution: '1.5' is not allowed"),
    ("hcs", ["--k-over-kc", "0.5,x"], "argument --k-over-kc: 'x' is not allowed"),
    ("vibrated", ["--speeds", "0,-1"], "argument --speeds: '-1' is not allowed: must be a "
                                       "number in [0, inf]"),
    ("shock", ["--mach", "1"], "argument --mach: '1' is not allowed: must be a number in "
                               "(1, inf]"),
])
def test_the_granular_studies_refuse_bad_options_by_name(tmp_path, capsys, study, argv,
                                                         message):
    """argparse refuses, with the option, the value and the range, before anything runs."""
    module = {"walls": WALLS, "hcs": HCS, "vibrated": VIBRATED, "shock": SHOCK}[study]
    with pytest.raises(SystemExit) as stop:
        module.main(["--out", str(tmp_path)] + argv)
    assert stop.value.code == 2 and message in capsys.readouterr().err


def test_a_study_command_prints_what_granframe_refuses_without_a_traceback(tmp_path):
    """An option that argparse lets through but the core refuses (N odd) ends the command
    with status 2 and granframe's message naming the parameter; a health stop with 3."""
    command = [sys.executable, str(STUDIES / "granular_walls.py"), "--out", str(tmp_path),
               "--n-modes", "7", "--cells", "4"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.startswith("granular_walls.py: error: VelocityGrid: parameter "
                                  "'n_modes' = 7 is invalid; must be an even integer")

    def stopped(argv):
        raise HealthError("health check failed at step 3: loss of positivity")

    assert finish(stopped, []) == 3


def test_longitudinal_modes_of_the_cooling_state_at_long_wavelengths():
    """At k* = 0 the eigenvalues are 0 and +-zeta*/2 (Brey et al. 1998); the heat mode's
    real positive eigenvalue survives at small k* (clustering) and is gone by k* = 0.2 at
    e = 0.9; the density response starts at 1."""
    zeta = HCS.sonine(0.9)["zeta*"]
    values = numpy.sort(numpy.linalg.eigvals(HCS.longitudinal(0.9, 0.0)).real)
    assert numpy.allclose(values, [-zeta / 2, 0.0, zeta / 2], atol=1e-15)
    small = numpy.linalg.eigvals(HCS.longitudinal(0.9, 0.05))
    assert any(v.real > 0 and abs(v.imag) < 1e-12 for v in small)
    assert all(v.real < 0 for v in numpy.linalg.eigvals(HCS.longitudinal(0.9, 0.2)))
    response = HCS.density_response(0.9, 1.0, 1.0, 0.2, [0.0, 1.0])
    assert response[0] == pytest.approx(1.0, abs=1e-12)


def test_longitudinal_modes_of_an_elastic_gas_are_sound_and_heat_diffusion():
    """e = 1 (eta* = kappa* = 1): at small k* the complex pair is sound of speed
    sqrt(gamma) = sqrt(5/3), attenuated at (k^2/2n)((4/3) eta + kappa (1/c_v - 1/c_p)) =
    (k*^2/2)((4/3) eta* + kappa*) (c_v = 3/2, c_p = 5/2, kappa/(n nu_0) = (15/4) kappa*
    in these units; Landau & Lifshitz, Fluid Mechanics, section 79), and the real one is
    heat diffusion, -kappa k^2/(n c_p) = -(3/2) kappa* k*^2."""
    k = 1e-3
    values = numpy.linalg.eigvals(HCS.longitudinal(1.0, k))
    sound = values[numpy.argmax(values.imag)]
    assert sound.imag == pytest.approx(math.sqrt(5 / 3) * k, rel=1e-6)
    assert sound.real == pytest.approx(-k * k / 2 * (4 / 3 + 1), rel=1e-3)
    heat = values[numpy.argmin(numpy.abs(values.imag))]
    assert heat.real == pytest.approx(-1.5 * k * k, rel=1e-3)


def test_the_heat_mode_stops_growing_where_the_longitudinal_determinant_vanishes():
    """k*_h = sqrt(zeta*/(5 (kappa* - mu*))): det M(k*_h) = 0, one real eigenvalue > 0 just
    below it and none just above; below the shear mode's k*_c = sqrt(zeta*/(2 eta*))."""
    for e in (0.9, 0.8, 0.5):
        k_h = HCS.heat_critical(e)
        assert numpy.linalg.det(HCS.longitudinal(e, k_h)) == pytest.approx(0.0, abs=1e-15)
        below = numpy.linalg.eigvals(HCS.longitudinal(e, 0.99 * k_h))
        above = numpy.linalg.eigvals(HCS.longitudinal(e, 1.01 * k_h))
        assert sum(v.real > 0 for v in below) == 1
        assert all(v.real < 0 for v in above)
        c = HCS.sonine(e)
        assert k_h < math.sqrt(c["zeta*"] / (2 * c["eta*"]))
    assert HCS.heat_critical(0.9) * HCS.collision_scale(1.0, 1.0, 1.0) == pytest.approx(
        0.23242, abs=1e-5)


def test_the_heat_mode_is_an_eigenvector_that_stops_growing_at_k_h():
    """heat_mode: M v = lambda v with rho' = 1; at k*_h lambda = 0 and v = (1, 0, -1) (an
    isobaric mode: rho' + theta = 0, no flow), growing below k*_h and decaying above."""
    for e in (0.9, 0.5):
        k_h = HCS.heat_critical(e)
        for ratio in (0.5, 1.2):
            rate, vector = HCS.heat_mode(e, ratio * k_h)
            assert numpy.allclose(HCS.longitudinal(e, ratio * k_h) @ vector, rate * vector,
                                  atol=1e-14)
            assert vector[0] == 1.0 and (rate > 0) == (ratio < 1)
        rate, vector = HCS.heat_mode(e, k_h)
        assert rate == pytest.approx(0.0, abs=1e-14)
        assert numpy.allclose(vector, [1.0, 0.0, -1.0], atol=1e-12)


def test_the_heat_rate_is_read_past_the_sound_it_excites():
    """A(s) = a e^(lambda s) + e^(sigma s)(b cos omega s + c sin omega s): heat_and_sound
    returns lambda and |b + ic|/a exactly, where the slope of ln A over the window is off by
    the sound pair's few per cent."""
    s = numpy.arange(0.0, 4.0001, 0.05)
    sound, rate = complex(-0.085, 0.41), 0.0148
    amplitude = 0.02 * numpy.exp(rate * s) + numpy.exp(sound.real * s) * (
        -3.6e-4 * numpy.cos(sound.imag * s) + 3e-5 * numpy.sin(sound.imag * s))
    fit = HCS.heat_and_sound(s, amplitude, sound, 1.0)
    assert fit["rate"] == pytest.approx(rate, abs=1e-9) and fit["rms"] < 1e-12
    assert fit["sound/heat"] == pytest.approx(math.hypot(3.6e-4, 3e-5) / 0.02, rel=1e-6)
    keep = s >= 1.0
    assert abs(numpy.polyfit(s[keep], numpy.log(amplitude[keep]), 1)[0] - rate) > 1e-3


def test_the_heat_projection_removes_the_sound_pair():
    """Fields made of the three Navier-Stokes modes of e = 0.8 at k* = 0.15 (the sound pair
    with 20 % of the heat mode's amplitude, on top of cooling-state fields rho = 2,
    T = 3): heat_projection's amplitude is the heat mode's alone, c_h(s) = c_h(0)
    e^(lambda_h s) to 1e-12, while the density amplitude's slope is off by the sound."""
    import xarray

    e, k_star, length = 0.8, 0.15, 20.0
    matrix = HCS.longitudinal(e, k_star)
    values, vectors = numpy.linalg.eig(matrix)
    heat = int(numpy.argmax(numpy.where(numpy.abs(values.imag) < 1e-12, values.real, -1.0)))
    weights = numpy.full(3, 0.2 + 0.1j)
    weights[heat] = 1.0
    s = numpy.linspace(0.0, 4.0, 41)
    modes = (vectors[None] * (weights * numpy.exp(values * s[:, None]))[:, None, :]).sum(-1)
    r, w, theta = (0.01 * modes.real).T
    x = (numpy.arange(16) + 0.5) * length / 16
    sine, cosine = numpy.sin(2 * math.pi * x / length), numpy.cos(2 * math.pi * x / length)
    density = 2.0 * (1.0 + r[:, None] * sine)
    temperature = 3.0 * (1.0 + theta[:, None] * sine)
    velocity = numpy.zeros((s.size, x.size, 3))
    velocity[:, :, 0] = math.sqrt(3.0) * w[:, None] * cosine
    ds = xarray.Dataset({"density": (("time", "x"), density),
                         "temperature": (("time", "x"), temperature),
                         "velocity": (("time", "x", "v"), velocity)},
                        coords={"time": s, "x": x})
    projected = HCS.heat_projection(ds, e, length, k_star, None)
    rate = values[heat].real
    assert numpy.allclose(projected, projected[0] * numpy.exp(rate * s), rtol=1e-12,
                          atol=1e-15)
    slope = numpy.polyfit(s, numpy.log(numpy.abs(r)), 1)[0]
    assert abs(slope - rate) > 1e-2 * abs(rate)


def test_the_kinetic_heat_critical_wavenumber_between_two_runs():
    """Rates that are Navier-Stokes' give its k_h exactly; rates of Navier-Stokes with the
    heat-flux coefficient 1.1 times larger give k_h/sqrt(1.1) to 1e-3 (the difference is
    interpolated linearly in k^2 between 0.8 and 1.2 k_h); rates of one sign are refused."""
    e, temperature, half_zeta = 0.8, 1.0, 0.1351
    nu0 = HCS.collision_scale(1.0, 1.0, temperature)
    k_h = HCS.heat_critical(e) * nu0

    def rows(conduction):
        return [{"k": k, "T_g": temperature, "zeta_g/2": half_zeta,
                 "measured rate": HCS.heat_mode(e, k / nu0, 2 * half_zeta / nu0,
                                                conduction)[0] * nu0}
                for k in (1.2 * k_h, 0.8 * k_h)]

    exact = scipy.optimize.brentq(
        lambda k: HCS.heat_mode(e, k / nu0, 2 * half_zeta / nu0)[0], 0.8 * k_h, 1.2 * k_h,
        xtol=1e-14)
    assert HCS.heat_critical_between(e, rows(1.0)) == pytest.approx(exact, rel=1e-10)
    shifted = scipy.optimize.brentq(
        lambda k: HCS.heat_mode(e, k / nu0, 2 * half_zeta / nu0, 1.1)[0], 0.8 * k_h,
        1.2 * k_h, xtol=1e-14)
    assert HCS.heat_critical_between(e, rows(1.1)) == pytest.approx(shifted, rel=1e-3)
    assert abs(shifted / exact - 1 / math.sqrt(1.1)) < 2e-3
    same_sign = rows(1.0)
    same_sign[0]["measured rate"] = abs(same_sign[0]["measured rate"])
    same_sign[1]["measured rate"] = abs(same_sign[1]["measured rate"])
    with pytest.raises(ValueError, match="do not change sign"):
        HCS.heat_critical_between(e, same_sign)


def test_a_heat_mode_run_starts_on_its_navier_stokes_eigenvector(tmp_path):
    """e = 0.9, k = k_h/2, 8 cells, N = 16, to s = 0.2: the initial fields are the heat
    mode's eigenvector (rho' sin, u_1 cos, theta sin with the eigenvector's ratios; theta
    to 2.5 %, the second-order temperature of a cell's mixture), and the density's first
    growth is its rate lambda_h nu_0 within 3 % (continuity with the eigenvector's u_1: a
    wrong sign or phase of the flow fails)."""
    e = 0.9
    nu0 = HCS.collision_scale(1.0, 1.0, 1.0)
    k = 0.5 * HCS.heat_critical(e) * nu0
    length = 2 * math.pi / k
    description = HCS.description(e, length, 8, 16, 3.5, 0.2, field="heat")
    rate, (r, w, theta) = HCS.heat_mode(e, k / nu0)
    store = tmp_path / "heat.zarr"
    Simulation(description).run(store, progress=False)
    ds = granframe.open_run(store, time_axis="steps")
    x = ds.x.values
    average = math.sin(k * length / 16) / (k * length / 16)   # a sine's cell average
    sine, cosine = numpy.sin(k * x) * 2 / 8, numpy.cos(k * x) * 2 / 8
    density = ds.density.values[0] - 1.0
    assert (density @ sine) / average == pytest.approx(0.02 * r, rel=1e-5)
    assert (ds.velocity.values[0, :, 0] @ cosine) / average == pytest.approx(0.02 * w,
                                                                            rel=1e-4)
    # T of a cell's mixture of Maxwellians: + its spread of u_1 and rho-T covariance, O(A^2)
    assert (ds.temperature.values[0] - 1.0) @ sine / average == pytest.approx(0.02 * theta,
                                                                             rel=3e-2)
    s, amplitude = HCS.amplitude_history(ds, length, "heat")
    first = numpy.log(amplitude[2] / amplitude[0]) / s[2]
    assert first == pytest.approx(rate * nu0, rel=0.03)


SHOCK = _study("granular_shock")


def test_rankine_hugoniot_of_the_piston_problem_against_the_closed_form():
    """rho_2/rho_1 = (gamma+1) M^2/((gamma-1) M^2 + 2), p_2/p_1 = 1 + 2 gamma/(gamma+1)
    (M^2 - 1) (Landau & Lifshitz section 89), with U from M by the piston relation."""
    gamma = SHOCK.GAMMA
    for mach in (1.2, 1.5, 2.0, 3.0):
        state = SHOCK.rankine_hugoniot(SHOCK.piston_speed(mach))
        assert state["mach"] == pytest.approx(mach, rel=1e-12)
        ratio = (gamma + 1) * mach ** 2 / ((gamma - 1) * mach ** 2 + 2)
        assert state["rho_2"] == pytest.approx(ratio, rel=1e-12)
        assert state["p_2"] == pytest.approx(1 + 2 * gamma / (gamma + 1) * (mach ** 2 - 1),
                                             rel=1e-12)


def test_the_granular_euler_reference_keeps_rankine_hugoniot_and_cools_at_the_exact_rate():
    """e = 1: the plateau and the shock position of the finite-volume reference within
    1e-3 of the exact solution (1000 cells). Uniform gas at rest with e < 1: T(t) =
    exp(-c rho t) to round-off (the exact cooling substep)."""
    speed = SHOCK.piston_speed(1.5)
    exact = SHOCK.rankine_hugoniot(speed)
    ref = SHOCK.granular_euler(speed, 1.0, 1e-3, 1.0, [0.15], cells=1000)
    x, rho, temperature = ref["x"], ref["density"][-1], ref["temperature"][-1]
    position = SHOCK.shock_position(x, rho)
    assert position == pytest.approx(exact["shock_speed"] * 0.15, abs=1e-3)
    assert SHOCK.plateau(x, rho, position) == pytest.approx(exact["rho_2"], rel=1e-3)
    assert SHOCK.plateau(x, temperature, position) == pytest.approx(exact["T_2"], rel=1e-3)
    rest = SHOCK.granular_euler(0.0, 0.9, 0.5, 1.0, [0.3], cells=50)
    assert rest["temperature"][-1] == pytest.approx(
        math.exp(-SHOCK.cooling_rate(0.9, 0.5) * 0.3), rel=1e-13)


def test_the_maxwell_kernel_cools_any_gas_at_the_rate_the_shock_reference_uses(tmp_path):
    """The homogeneous 2D Maxwell gas (B = 1/(2 pi)): T(t) = exp(-(1 - e^2) rho t/(4 eps))."""
    from granframe.run.description import RunDescription

    d = RunDescription(
        title="Maxwell cooling", grid={"dimension": 2, "n_modes": 32, "support_radius": 5.0},
        kernel="maxwell", restitution={"name": "constant", "value": 0.9},
        initial={"name": "maxwellian"}, operator={"name": "fast_spectral"},
        integrator="rk4", knudsen=0.5, time_step=0.01, final_time=0.2,
        output={"snapshot_interval": 0.2})
    Simulation(d).run(tmp_path / "cool.zarr", progress=False)
    temperature = float(granframe.open_run(tmp_path / "cool.zarr").temperature.values[-1])
    assert temperature == pytest.approx(math.exp(-SHOCK.cooling_rate(0.9, 0.5) * 0.2),
                                        rel=1e-4)


def test_a_quick_elastic_shock_moves_at_the_rankine_hugoniot_speed(tmp_path):
    """40 cells, eps = 1e-3, Mach 1.5, to t = 0.15: the kinetic shock speed within 5 % and
    the plateau within 2 % of Rankine-Hugoniot, the mass to round-off."""
    speed = SHOCK.piston_speed(1.5)
    d = SHOCK.description(speed, 1.0, 1e-3, 40, 1.0, 0.15, 32, 4.5, 0.15 / 60)
    store = tmp_path / "shock.zarr"
    Simulation(d).run(store, progress=False)
    row = SHOCK.compare(store, speed, 1.0, 1e-3, 1.0)
    assert row["shock speed"] == pytest.approx(row["RH shock speed"], rel=0.05)
    assert row["rho_2"] == pytest.approx(row["RH rho_2"], rel=0.02)
    assert row["T_2"] == pytest.approx(row["RH T_2"], rel=0.02)
    assert row["mass drift"] < 1e-13
    _assert_drawn(SHOCK, [store], tmp_path / "shock.png")


VIBRATED = _study("granular_vibrated")


def test_the_effective_wall_temperature_is_the_period_mean_energy_of_the_vibrating_wall():
    """(d+1) T_eff / 2 = <J2/J0> of the vibrating wall (granframe.space.exact) to its
    fourth-order term c_4 eps^4 T_w, and T_eff = T_w at rest."""
    from granframe.space import exact

    assert VIBRATED.effective_temperature(0.0, 1.3) == 1.3
    for speed, wall in ((0.1, 1.0), (0.2, 0.5), (0.5, 2.0)):
        omega = 20.0
        mean = exact.vibrating_wall_energy_per_period(
            2, wall, speed / omega, omega, 1.0, 1.0)["mean_energy"]
        eps2 = speed * speed / wall
        fourth = wall * exact.VIBRATING_WALL_COEFFICIENTS[1] * eps2 * eps2
        assert 1.5 * VIBRATED.effective_temperature(speed, wall) == pytest.approx(
            mean - fourth, rel=1e-6)


def test_a_quick_vibrated_gas_balances_its_energy_over_a_period(tmp_path):
    """8 cells, N = 24, eps = 0.5, two periods: the mass to round-off; over the last period
    the wall's energy plus the dissipation (eight snapshots) is the energy's change to 2 %
    of what came in, and the vibrating wall puts in more than the resting one."""
    rows = {}
    for speed in (0.0, 1.0):
        d = VIBRATED.description(0.9, 0.5, speed, 0.25, 8, 24, 4.0, 2, 24)
        store = tmp_path / f"v{speed:g}.zarr"
        run = Simulation(d)
        run.run(store, progress=False)
        ds = granframe.open_run(store, time_axis="steps")
        assert abs(ds.mass.values[-1] / ds.mass.values[0] - 1) < 1e-13
        rows[speed] = VIBRATED.period_balance(ds, run.problem.operator, 0.5, 0.25)
        assert abs(rows[speed]["residual"]) < 0.02
    assert rows[1.0]["injected"] > rows[0.0]["injected"]
    _assert_drawn(VIBRATED, [tmp_path / "v0.zarr", tmp_path / "v1.zarr"], tmp_path / "vib.png")


CLUSTERS = _study("granular_clusters")


def test_a_quick_cluster_run_reports_its_monitors(tmp_path):
    """16 cells, N = 24, to s = 1: the mass to round-off, the shear mode starts to pile up
    density (contrast above 1), and the monitors' keys are there."""
    d = CLUSTERS.description(0.8, 40.0, 16, 24, 4.0, 1.0, 0.3)
    store = tmp_path / "clusters.zarr"
    Simulation(d).run(store, progress=False)
    row = CLUSTERS.monitors(granframe.open_run(store, time_axis="steps"))
    assert row["mass drift"] < 1e-13
    assert row["rho max/min"] > 1.0 + 1e-6
    assert row["status"] == "finished"
    assert row["negative mass share"] < 1e-3
    _assert_drawn(CLUSTERS, [store], tmp_path / "clusters.png")
