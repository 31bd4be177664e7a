"""Granular phenomena in space against theory (studies/granular_*.py, docs/granular.md):
the studies' measurements and quick variants of their runs, such as the shear mode of the
homogeneous cooling state in the rescaled formulation. The theory itself (the first-Sonine
coefficients, the modes, the heated walls, Rankine-Hugoniot) is tested in
tests/test_theory.py."""

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
from granframe.theory.cooling import maxwellian_cooling_rate
from granframe.theory.euler import granular_euler_piston, piston_speed, rankine_hugoniot
from granframe.theory.modes import (heat_critical_wavenumber, heat_mode, longitudinal_matrix,
                                    shear_mode)
from granframe.theory.sonine import reference_frequency
from granframe.tools.analysis import cluster_monitors, heat_and_sound, heat_mode_rates
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
    k = 0.5 * shear_mode(e, 1.0, 1.0, 1.0, 1.0)["k_c"]
    length = 2 * math.pi / k
    store = tmp_path / "shear.zarr"
    Simulation(HCS.description(e, length, 8, 16, 3.5, 3.0)).run(store, progress=False)
    ds = granframe.open_run(store, time_axis="steps")
    measured = HCS.measured_rate(ds, length, 1.0)["rate"]
    eta = shear_mode(e, 1.0, 1.0, float(ds.temperature.values[-1].mean()), k)["eta"]
    predicted = HCS.cooling_rate(ds, 1.0) - eta * k * k
    assert predicted > 0.05 and measured == pytest.approx(predicted, rel=0.03)
    _assert_drawn(HCS, [store], tmp_path / "modes.png")


WALLS = _study("granular_walls")


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
            "--start", "maxwellian", "--snapshot-every", "3", "--resume", "--no-progress"]
    rows = []
    for _ in range(2):
        WALLS.main(argv)
        out = capsys.readouterr().out
        assert "estimated cost: 13 steps" in out and "verdict: " in out
        assert "figure: " in out and (tmp_path / "walls.png").exists()
        rows.append(json.loads((tmp_path / "walls_e0.9_kn0.2_c6_n16.json").read_text()))
    first, again = rows
    assert first == again and first["steps"] == 13 and first["warnings"]
    assert abs(first["residual"]) < 0.05 and first["heat"] > 0 > first["dissipation"]
    assert 0 < first["jump"] < 0.2 and first["rho_max/rho_b"] > 1 > first["T_min/T_b"]
    # every cell's fields error; the run's report names the largest
    errors = first["fields error by cell"]
    reported = next(re.search(r"changes the fields by ([0-9.e-]+) ", w)
                    for w in first["warnings"] if w.startswith("velocity resolution"))
    assert len(errors) == 6 and max(errors) == pytest.approx(float(reported.group(1)),
                                                             rel=2e-3)
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


def test_a_heated_gas_started_on_navier_stokes_with_the_jump_is_compared_with_it(tmp_path):
    """From the local Maxwellian of Navier-Stokes with Sone's jump (Kn = 0.5, 6 cells,
    N = 20, one step): the middle and the wall cells are the theory's (the start) to the
    step's change, the comparison names the theory's values, and at Kn = 0.5 no
    cell is 2 mean free paths from both walls (no bulk)."""
    from granframe.theory.walls import heated_walls_jump

    d = WALLS.description(0.9, 0.5, 6, 20, 3.5, 0.01, 0.01, start="navier-stokes")
    store = tmp_path / "ns.zarr"
    Simulation(d).run(store, progress=False)
    row = WALLS.against_jump(granframe.open_run(store, time_axis="steps"), 0.9, 0.5)
    theory = heated_walls_jump(0.9, 0.5)
    assert row["NS T(1/2)"] == theory["temperature"][0]
    assert row["NS T_b"] == theory["T_b"] and row["lambda_b"] == 0.5 / theory["rho_b"]
    for key in ("T(1/2)", "rho(1/2)", "T wall cell", "rho wall cell"):
        assert row[key] == pytest.approx(row[f"NS {key}"], rel=0.02), key
    assert row["bulk cells"] == 0 and math.isnan(row["bulk T"])


def test_the_walls_study_gives_error_bars_and_refuses_a_bad_refinement(capsys):
    """Rows that follow a + b h^2 get order 2, the limit a and the GCI of the finest, with
    the Navier-Stokes value beside them; --refine needs three increasing members."""
    spacings = [1 / 24, 1 / 28, 1 / 32]
    rows = [{**{key: 1.0 + k + 3.0 * h * h for k, key in enumerate(WALLS.REFINED)},
             **{f"NS {key}": 0.5 for key in WALLS.REFINED}} for h in spacings]
    bars = WALLS.error_bars(rows, spacings)
    for k, key in enumerate(WALLS.REFINED):
        assert bars[key]["order"] == pytest.approx(2.0, abs=1e-9)
        assert bars[key]["extrapolated"] == pytest.approx(1.0 + k, abs=1e-12)
        assert bars[key]["navier-stokes"] == 0.5
    for bad in ("n-modes=24,28", "cells=12,10,8", "modes=1,2,3", "cells=a,b,c"):
        with pytest.raises(SystemExit):
            WALLS.main(["--out", "unused", "--refine", bad])
        assert f"argument --refine: '{bad}' is not allowed" in capsys.readouterr().err


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
    ("vibrated", ["--restitutions", "0.9,-1"], "argument --restitutions: '-1' is not "
                                               "allowed: must be a number in (0, inf]"),
    ("vibrated", ["--restitutions", "0.9,1"], "argument --restitutions: 1 is not allowed: "
                                              "each e must be below 1"),
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


def test_the_heat_rate_is_read_past_the_sound_it_excites():
    """A(s) = a e^(lambda s) + e^(sigma s)(b cos omega s + c sin omega s): heat_and_sound
    returns lambda and |b + ic|/a exactly, where the slope of ln A over the window is off by
    the sound pair's few per cent."""
    s = numpy.arange(0.0, 4.0001, 0.05)
    sound, rate = complex(-0.085, 0.41), 0.0148
    amplitude = 0.02 * numpy.exp(rate * s) + numpy.exp(sound.real * s) * (
        -3.6e-4 * numpy.cos(sound.imag * s) + 3e-5 * numpy.sin(sound.imag * s))
    fit = heat_and_sound(s, amplitude, sound, 1.0)
    assert fit["rate"] == pytest.approx(rate, abs=1e-9) and fit["rms"] < 1e-12
    assert fit["sound/heat"] == pytest.approx(math.hypot(3.6e-4, 3e-5) / 0.02, rel=1e-6)
    keep = s >= 1.0
    assert abs(numpy.polyfit(s[keep], numpy.log(amplitude[keep]), 1)[0] - rate) > 1e-3


def test_the_heat_rates_compare_with_navier_stokes_at_the_runs_own_scales():
    """heat_mode_rates on an amplitude made of a heat rate and the Navier-Stokes sound pair
    of the run's (k*, zeta*), k* = k sqrt(T_g)/nu_0(T_g), zeta* = zeta_g / nu_0(T_g): the
    measured rate is the heat rate, and its Navier-Stokes rates are heat_mode's at those
    scales times nu_0(T_g), with the run's zeta* and with the first Sonine one."""
    e, k, temperature, half_zeta = 0.9, 0.18, 0.7, 0.02
    nu0 = reference_frequency(1.0, 1.0, temperature)
    k_star, zeta = k * math.sqrt(temperature) / nu0, 2 * half_zeta / nu0
    values = numpy.linalg.eigvals(longitudinal_matrix(e, k_star, zeta)) * nu0
    sound = complex(values[numpy.argmax(values.imag)])
    s = numpy.arange(0.0, 4.0001, 0.05)
    amplitude = 0.02 * numpy.exp(0.0151 * s) + 4e-4 * numpy.exp(sound.real * s) * numpy.cos(
        sound.imag * s)
    rates, scales = heat_mode_rates(s, amplitude, e, k, temperature, half_zeta, 1.0)
    assert scales == pytest.approx({"nu0": nu0, "k*": k_star, "zeta*": zeta}, rel=1e-14)
    assert rates["measured rate"] == pytest.approx(0.0151, abs=1e-9)
    assert rates["sound/heat"] == pytest.approx(0.02, rel=1e-6)
    assert rates["Navier-Stokes rate with zeta_g"] == pytest.approx(
        heat_mode(e, k_star, zeta)[0] * nu0, rel=1e-14)
    assert rates["Navier-Stokes rate (Sonine zeta)"] == pytest.approx(
        heat_mode(e, k_star)[0] * nu0, rel=1e-14)
    late = s >= 3.25
    assert rates["measured late"] == pytest.approx(
        numpy.polyfit(s[late], numpy.log(amplitude[late]), 1)[0], rel=1e-12)


def test_the_heat_projection_removes_the_sound_pair():
    """Fields made of the three Navier-Stokes modes of e = 0.8 at k* = 0.15 (the sound pair
    with 20 % of the heat mode's amplitude, on top of cooling-state fields rho = 2,
    T = 3): heat_projection's amplitude is the heat mode's alone, c_h(s) = c_h(0)
    e^(lambda_h s) to 1e-12, while the density amplitude's slope is off by the sound."""
    import xarray

    e, k_star, length = 0.8, 0.15, 20.0
    matrix = longitudinal_matrix(e, k_star)
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
    nu0 = reference_frequency(1.0, 1.0, temperature)
    k_h = heat_critical_wavenumber(e) * nu0

    def rows(conduction):
        return [{"k": k, "T_g": temperature, "zeta_g/2": half_zeta,
                 "measured rate": heat_mode(e, k / nu0, 2 * half_zeta / nu0,
                                            conduction)[0] * nu0}
                for k in (1.2 * k_h, 0.8 * k_h)]

    exact = scipy.optimize.brentq(
        lambda k: heat_mode(e, k / nu0, 2 * half_zeta / nu0)[0], 0.8 * k_h, 1.2 * k_h,
        xtol=1e-14)
    assert HCS.heat_critical_between(e, rows(1.0)) == pytest.approx(exact, rel=1e-10)
    shifted = scipy.optimize.brentq(
        lambda k: heat_mode(e, k / nu0, 2 * half_zeta / nu0, 1.1)[0], 0.8 * k_h,
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
    nu0 = reference_frequency(1.0, 1.0, 1.0)
    k = 0.5 * heat_critical_wavenumber(e) * nu0
    length = 2 * math.pi / k
    description = HCS.description(e, length, 8, 16, 3.5, 0.2, field="heat")
    rate, (r, w, theta) = heat_mode(e, k / nu0)
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


def test_the_granular_euler_reference_keeps_rankine_hugoniot_and_cools_at_the_exact_rate():
    """e = 1: the plateau and the shock position of the finite-volume reference within
    1e-3 of the exact solution (1000 cells). Uniform gas at rest with e < 1: T(t) =
    exp(-c rho t) to round-off (the exact cooling substep)."""
    speed = piston_speed(1.5, SHOCK.GAMMA)
    exact = rankine_hugoniot(speed, SHOCK.GAMMA)
    ref = granular_euler_piston(speed, 1.0, 1e-3, 1.0, [0.15], cells=1000)
    x, rho, temperature = ref["x"], ref["density"][-1], ref["temperature"][-1]
    position = SHOCK.shock_position(x, rho)
    assert position == pytest.approx(exact["shock_speed"] * 0.15, abs=1e-3)
    assert SHOCK.plateau(x, rho, position) == pytest.approx(exact["rho_2"], rel=1e-3)
    assert SHOCK.plateau(x, temperature, position) == pytest.approx(exact["T_2"], rel=1e-3)
    rest = granular_euler_piston(0.0, 0.9, 0.5, 1.0, [0.3], cells=50)
    assert rest["temperature"][-1] == pytest.approx(
        math.exp(-(maxwellian_cooling_rate(0.9) / 0.5) * 0.3), rel=1e-13)


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
    assert temperature == pytest.approx(math.exp(-(maxwellian_cooling_rate(0.9) / 0.5) * 0.2),
                                        rel=1e-4)


def test_a_quick_elastic_shock_moves_at_the_rankine_hugoniot_speed(tmp_path):
    """40 cells, eps = 1e-3, Mach 1.5, to t = 0.15: the kinetic shock speed within 5 % and
    the plateau within 2 % of Rankine-Hugoniot, the mass to round-off."""
    speed = piston_speed(1.5, SHOCK.GAMMA)
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


def test_the_wall_speed_of_the_uniform_balance_puts_in_what_the_gas_dissipates():
    """x = V / sqrt(T) of the uniform gas: sqrt(T / 2 pi) Delta e(V, T) = (d/2) zeta_1
    T^(3/2) / eps at T = 1 and (by the scaling of the specular layer) at T = 2, and x^2 is
    the leading order's within its V^4 correction (e = 0.8, the largest V of the study)."""
    from granframe.space import exact

    for e in (0.8,):
        x = VIBRATED.wall_speed_ratio(e, 0.5)
        zeta = VIBRATED.cooling_coefficient(e)
        assert VIBRATED.uniform_temperature(e, 0.5, x) == pytest.approx(1.0, rel=1e-12)
        for t in (1.0, 2.0):
            speed = x * math.sqrt(t)
            put_in = math.sqrt(t / (2 * math.pi)) * exact.vibrating_wall_heating(
                speed, 1.0, t, "specular", speeds=1000)
            assert put_in == pytest.approx(zeta * t ** 1.5 / 0.5, rel=1e-8)
        lead = math.sqrt(2 * math.pi) * zeta / 0.5 / 2
        assert x * x == pytest.approx(lead, rel=0.2 * x * x)


def test_a_quick_vibrated_gas_balances_its_power(tmp_path):
    """8 cells, N = 24, e = 0.9, to t = 1 from the uniform gas: the mass to round-off; the
    power the wall puts in plus the dissipation is the energy's rate of change to 2 % of
    the power; the gas stays within 10 % of the uniform balance's temperature."""
    x = VIBRATED.wall_speed_ratio(0.9, 0.5)
    dt = 1.0 / 64
    d = VIBRATED.description(0.9, 0.5, x, 8, 24, 3.5, 1.0, dt)
    store = tmp_path / "v.zarr"
    run = Simulation(d)
    run.run(store, progress=False)
    ds = granframe.open_run(store, time_axis="steps")
    assert abs(ds.mass.values[-1] / ds.mass.values[0] - 1) < 1e-13
    end = VIBRATED.balance(ds, run.problem.operator, 0.5)
    assert end["power in"] > 0 and end["dissipation"] < 0
    assert abs(end["residual"]) < 0.02, end
    mean = float((end["temperature"] * end["density"]).mean())
    assert mean == pytest.approx(1.0, rel=0.1)
    _assert_drawn(VIBRATED, [store], tmp_path / "vib.png")


CLUSTERS = _study("granular_clusters")


def test_a_quick_cluster_run_reports_its_monitors(tmp_path):
    """16 cells, N = 24, to s = 1: the mass to round-off, the shear mode starts to pile up
    density (contrast above 1), and the monitors' keys are there."""
    d = CLUSTERS.description(0.8, 40.0, 16, 24, 4.0, 1.0, 0.3)
    store = tmp_path / "clusters.zarr"
    Simulation(d).run(store, progress=False)
    row = cluster_monitors(granframe.open_run(store, time_axis="steps"))
    assert row["mass drift"] < 1e-13
    assert row["rho max/min"] > 1.0 + 1e-6
    assert row["status"] == "finished"
    assert row["negative mass share"] < 1e-3
    _assert_drawn(CLUSTERS, [store], tmp_path / "clusters.png")


def test_the_heat_mode_is_below_the_shear_mode_only_for_moderate_inelasticity():
    """First-Sonine theory: k_h < k_c for e above 0.3747 only (docs/granular.md), and
    kappa* - mu* changes sign at e = 0.1878, below which k_h does not exist."""
    from scipy.optimize import brentq

    from granframe.theory.modes import heat_critical_wavenumber, shear_mode
    from granframe.theory.sonine import reference_frequency, transport_coefficients

    def ratio(e):
        return (heat_critical_wavenumber(e) * reference_frequency(1.0, 1.0, 1.0)
                / shear_mode(e, 1.0, 1.0, 1.0, 1.0)["k_c"])

    assert brentq(lambda e: ratio(e) - 1.0, 0.2, 0.7) == pytest.approx(0.3747, abs=1e-4)
    assert ratio(0.4) < 1.0 < ratio(0.35)
    conduction = [transport_coefficients(e)["kappa*"] - transport_coefficients(e)["mu*"]
                  for e in (0.15, 0.2)]
    assert conduction[0] < 0 < conduction[1]
    with pytest.raises(ValueError, match=r"^heat_critical_wavenumber: parameter 'restitution' "
                                         r"= 0\.15 is invalid; must be above 0\.1878"):
        heat_critical_wavenumber(0.15)


def test_the_vibrated_study_gives_its_numbers_error_bars_from_a_refinement():
    """Rows at three resolutions whose numbers follow a + b h^2: each gets its order 2, its
    limit a and the grid convergence index of the finest (error bar 1.25 |e_21| / 3)."""
    spacings = [1 / 8, 1 / 16, 1 / 32]
    members = [[{"e": 0.9, **{key: 1.0 + k + 3.0 * h * h for k, key in
                              enumerate(VIBRATED.REFINED)}}] for h in spacings]
    (entry,) = VIBRATED.error_bars(members, spacings)
    for k, key in enumerate(VIBRATED.REFINED):
        bar = entry[key]
        assert bar["order"] == pytest.approx(2.0, abs=1e-9)
        assert bar["extrapolated"] == pytest.approx(1.0 + k, abs=1e-12)
        assert bar["error_bar"] == pytest.approx(1.25 * 3.0 * (1 / 16 ** 2 - 1 / 32 ** 2) / 3,
                                                 rel=1e-9)
