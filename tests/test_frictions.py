"""Small frictions of the runner: a final time off the step grid, runs held in memory, the
step limit before building, and the direct method's precomputation."""

import json
import math
import time

import numpy
import pytest
import scipy.special
import xarray.testing

import granframe as gf
from granframe.run.description import fixed_steps
from granframe.run.runner import HealthError, Simulation, Stepper
from granframe.stepping.stability import step_limit
from granframe.tools.cli import main
from granframe_spectral.direct import DirectSpectral, angular_coefficients
from test_runner import heated


# -- a final time that is not a multiple of dt ----------------------------------------------
def short_last_step(**changes):
    """Heated Maxwell molecules (2D N = 32) to t = 1.03 with dt = 0.1: 10 steps, then 0.03."""
    return heated(**{"time_step": 0.1, "final_time": 1.03, "integrator": "if_rk4",
                     "output": {"snapshot_interval": 0.5}, **changes})


def test_fixed_steps_shorten_only_a_last_step_off_the_grid():
    assert fixed_steps(1.0, 0.1) == (10, 0.0)            # 1.0 / 0.1 is 10 to round-off
    assert fixed_steps(0.3, 0.1) == (3, 0.0)             # 0.3 / 0.1 = 2.9999999999999996
    full, last = fixed_steps(1.03, 0.1)
    assert full == 10 and last == pytest.approx(0.03, rel=1e-12)
    assert fixed_steps(0.05, 0.1) == (0, 0.05)           # a run shorter than one step


def test_a_snapshot_interval_off_the_step_grid_is_refused_with_a_multiple_suggested():
    with pytest.raises(ValueError, match=r"'snapshot_interval' = 0.25 is invalid; must be a "
                                         r"whole multiple \(>= 1\) of time_step = 0.1 .* "
                                         r"never changes the steps; e.g. 0.2"):
        heated(time_step=0.1, final_time=1.03, output={"snapshot_interval": 0.25})


@pytest.mark.parametrize("integrator", ["if_rk4", "penalised_ars222"])
def test_the_last_step_is_shortened_to_land_on_final_time(tmp_path, integrator):
    """With the schemes whose step depends on dt beyond the stages: exp(dt tau Delta) of the
    integrating factor (cached per dt) and the Strang-split heat bath and implicit
    relaxation of the penalised scheme."""
    simulation = Simulation(short_last_step(integrator=integrator))
    assert simulation.output_points() == [5, 10, 11]
    result = simulation.run(tmp_path / "run.zarr", progress=False)
    assert result.steps == 11 and result.time == 1.03
    store = gf.open_run(tmp_path / "run.zarr")
    assert list(store.time.values) == [0.0, 0.5, 1.0, 1.03]
    dt = store.dt.values
    assert numpy.all(dt[1:11] == 0.1) and dt[11] == pytest.approx(0.03, rel=1e-12)
    assert store.step_time.values[10] == 10 * 0.1 and store.step_time.values[-1] == 1.03
    # the same steps by hand: ten of dt = 0.1 at t = n dt, then one of 0.03 from t = 1
    f = simulation.backend.asarray(simulation.f0)
    for n in range(10):
        f = simulation.integrator.step(simulation.equation, n * 0.1, f, 0.1)
    f = simulation.integrator.step(simulation.equation, 1.0, f, 1.03 - 10 * 0.1)
    assert numpy.array_equal(store.f.isel(time=-1).values, f)


def test_a_run_resumed_before_the_short_step_equals_the_uninterrupted_one(tmp_path,
                                                                         monkeypatch):
    description = short_last_step(output={"snapshot_interval": 0.2})
    Simulation(description).run(tmp_path / "whole.zarr", progress=False)
    advance = Stepper._advance

    def interrupted(self, state, target):
        if state.step == 10:          # Ctrl-C just before the short step
            raise KeyboardInterrupt
        advance(self, state, target)

    monkeypatch.setattr(Stepper, "_advance", interrupted)
    with pytest.raises(KeyboardInterrupt):
        Simulation(description).run(tmp_path / "cut.zarr", progress=False)
    monkeypatch.setattr(Stepper, "_advance", advance)
    assert gf.open_run(tmp_path / "cut.zarr").attrs["progress_status"] == "interrupted"
    result = Simulation(description).run(tmp_path / "cut.zarr", resume=True, progress=False)
    assert result.steps == 11 and result.time == 1.03
    whole, cut = gf.open_run(tmp_path / "whole.zarr"), gf.open_run(tmp_path / "cut.zarr")
    assert numpy.array_equal(whole.f.values, cut.f.values)
    for name in ("step_time", "dt", "temperature", "mass"):
        assert numpy.array_equal(whole[name].values, cut[name].values), name


# -- runs held in memory --------------------------------------------------------------------
#: what differs between two runs of one description: when each was made, how long it took
_CLOCK_ATTRIBUTES = ("history", "progress_wall_seconds")


def without_clock(dataset):
    dataset = dataset.copy()
    dataset.attrs = {k: v for k, v in dataset.attrs.items() if k not in _CLOCK_ATTRIBUTES}
    return dataset


def test_a_run_in_memory_equals_the_same_run_on_disk_and_writes_nothing(tmp_path,
                                                                       monkeypatch):
    description = short_last_step()
    on_disk = tmp_path / "disk"
    on_disk.mkdir()
    Simulation(description).run(on_disk / "run.zarr", progress=False)
    expected = gf.open_run(on_disk / "run.zarr")
    here = tmp_path / "cwd"
    here.mkdir()
    monkeypatch.chdir(here)
    in_memory = gf.run_in_memory(description, progress=False)
    assert list(here.iterdir()) == [] and list(on_disk.iterdir()) == [on_disk / "run.zarr"]
    # bitwise: the same steps on the same machine; only the clock attributes differ
    xarray.testing.assert_identical(without_clock(in_memory), without_clock(expected))
    assert set(in_memory.attrs) == set(expected.attrs)
    assert in_memory.attrs["progress_status"] == "finished"
    result = Simulation(description).run(None, progress=False)
    assert result.store == "memory" and result.steps == 11 and result.time == 1.03
    xarray.testing.assert_identical(without_clock(result.dataset), without_clock(expected))


def test_a_health_check_stops_a_run_in_memory_as_it_stops_one_on_disk(tmp_path, monkeypatch):
    """Forward Euler far beyond the heat bath's limit, the up-front check off (as in
    test_runner): the step-by-step health check raises HealthError with the same message."""
    d = heated(integrator="forward_euler", heat_bath=50.0, time_step=0.05, final_time=5.0,
               output={"snapshot_interval": 0.5}, health={"step_limit": False})
    with pytest.raises(HealthError) as on_disk:
        Simulation(d).run(tmp_path / "bad.zarr", progress=False)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(HealthError) as in_memory:
        Simulation(d).run_in_memory(progress=False)
    assert str(in_memory.value) == str(on_disk.value)
    assert "health check failed at step" in str(in_memory.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.zarr"]
    xarray.testing.assert_identical(without_clock(in_memory.value.dataset),
                                    without_clock(gf.open_run(tmp_path / "bad.zarr")))
    assert on_disk.value.dataset is None


def test_a_run_in_memory_cannot_be_resumed():
    with pytest.raises(ValueError, match="'resume' = True is invalid; needs a store on disk"):
        Simulation(heated()).run(None, resume=True, progress=False)


# -- the step limit before building ---------------------------------------------------------
def resolved(**changes):
    """A resolved 2D run (N = 48, S = 5, T0 = 1) with the direct method (exact angular
    integrals; the energy integral of its Q for Maxwell molecules is exact to 1e-7, that of
    fast_spectral with 48 x 32 points to 7e-6)."""
    return heated(**{"grid": {"dimension": 2, "n_modes": 48, "support_radius": 5.0},
                     "initial": {"name": "maxwellian", "temperature": 1.0}, "heat_bath": 0.0,
                     "operator": {"name": "direct_spectral"}, "final_time": 0.1,
                     "time_step": 0.01, "output": {}, **changes})


def runner_limit(description):
    simulation = Simulation(description)
    return step_limit(simulation.integrator, simulation.equation, simulation.f0)


@pytest.mark.parametrize("changes,dominant", [
    ({"heat_bath": 1.0}, "linear"),                                    # rk4
    ({"integrator": "if_rk4", "knudsen": 0.01, "time_step": 0.01}, "nonlinear"),
    ({"integrator": "penalised_ars222", "knudsen": 1e-3, "time_step": 0.01}, "dissipation"),
    ({"kernel": "hard_spheres", "restitution": {"name": "toscani", "strength": 1.0,
                                                "exponent": 0.5}}, "nonlinear"),
], ids=["heat-bath", "collisions", "dissipation", "hard-spheres-toscani"])
def test_the_step_limit_from_the_description_is_the_one_the_runner_checks(changes, dominant):
    cheap = gf.time_step_limit(heated(**changes))
    assert cheap == runner_limit(heated(**changes))       # the same radii, bitwise
    assert cheap.dominant == dominant
    too_large = heated(**{**changes, "time_step": 1.5 * cheap.limit, "output": {}})
    with pytest.raises(ValueError, match=f"'time_step' = .* is invalid; must be <= "
                                         f"{cheap.limit:.4g}, the explicit stability limit"):
        Simulation(too_large)


BIMODAL = {"name": "gaussian_mixture", "components": [
    {"density": 0.5, "temperature": 0.6, "velocity": [1.0, 0.0]},
    {"density": 0.5, "temperature": 0.6, "velocity": [-1.0, 0.0]}]}


@pytest.mark.parametrize("kernel,initial,conservative,tolerance", [
    ("maxwell", {"name": "maxwellian", "temperature": 1.0}, False, 1e-6),
    ("hard_spheres", BIMODAL, False, 2e-5),
    ("maxwell", {"name": "maxwellian", "temperature": 1.0}, True, 1e-12),
    ("hard_spheres", BIMODAL, True, 1e-12),
], ids=["maxwell", "hard-spheres-bimodal", "maxwell-conservative",
        "hard-spheres-bimodal-conservative"])
def test_a_rescaled_runs_drift_limit_before_building_agrees_with_the_runners(
        kernel, initial, conservative, tolerance):
    """The cooling rate a_0 behind the drift radius takes the energy dissipation D(f0) in
    closed form, the runner's from its operator. Both approximate the same integral: at
    N = 48 the operator's is off by 1e-7 (Maxwell) and 7e-6 (hard spheres). A conservative
    run's operator dissipates D(f) itself, so there the limits agree to round-off."""
    description = resolved(rescaled=True, kernel=kernel, initial=initial,
                           conservative=conservative)
    cheap, checked = gf.time_step_limit(description), runner_limit(description)
    assert cheap.dominant == checked.dominant == "drift"
    assert cheap.rates["nonlinear"] == checked.rates["nonlinear"]
    assert cheap.limit == pytest.approx(checked.limit, rel=tolerance)


def test_the_step_limit_of_a_3d_run_builds_no_operator_and_is_fast(monkeypatch):
    from granframe_spectral.fast import FastSpectral

    def refuse(*args, **kwargs):
        raise AssertionError("the operator was built")

    monkeypatch.setattr(FastSpectral, "__init__", refuse)
    for changes in ({"heat_bath": 0.5}, {"rescaled": True, "kernel": "hard_spheres"}):
        description = heated(**{"grid": {"dimension": 3, "n_modes": 32,
                                          "support_radius": 5.0},
                                "initial": {"name": "maxwellian", "temperature": 1.0},
                                "operator": {"name": "fast_spectral"}, "heat_bath": 0.0,
                                **changes})
        gf.time_step_limit(description)                     # imports, plans
        started = time.perf_counter()
        limit = gf.time_step_limit(description)
        assert time.perf_counter() - started < 1.0 and limit.limit > 0.0


def test_granframe_limits_reports_the_limit_and_fails_above_it(tmp_path, capsys):
    path = tmp_path / "heated.toml"
    path.write_text(heated().to_toml())
    limit = gf.time_step_limit(heated())
    assert main(["limits", str(path)]) == 0
    out = capsys.readouterr().out
    assert f"'rk4': dt <= {limit.limit:.4g}, set by the collision term Q/eps" in out
    assert "time_step = 0.05: within it" in out
    assert main(["limits", str(path), "--set", "heat_bath=10.0"]) == 3
    assert "time_step = 0.05: ABOVE the limit (granframe run refuses it)" in (
        capsys.readouterr().out)
    limit = gf.time_step_limit(heated(heat_bath=10.0))
    assert main(["limits", str(path), "--set", "heat_bath=10.0", "--json"]) == 3
    document = json.loads(capsys.readouterr().out)["runs"][""]
    assert document["limit"] == limit.limit and document["within"] is False
    assert document["rates"] == {str(k): v for k, v in limit.rates.items()}
    path.write_text(heated(rescaled=True, heat_bath=0.0, integrator="ssp_rk2").to_toml())
    assert main(["limits", str(path)]) == 3
    assert ("'ssp_rk2': unstable at any step: the drift of the rescaled formulation has an "
            "imaginary spectrum") in capsys.readouterr().out


# -- direct_spectral's precomputation -------------------------------------------------------
def direct_weights_by_pairs(operator):
    """The weights of :class:`DirectSpectral` pair by pair from the class notes' formula, with
    the vectors x = a k and y = a k - b m themselves (no keys, no symmetry), and the gather
    index of k - m: the obviously-correct reference of the vectorised precomputation."""
    grid, kernel = operator.grid, operator.kernel
    d, n, L = grid.dimension, grid.n_modes, grid.half_width
    one = numpy.arange(-(n // 2) + 1, n // 2)
    modes = numpy.stack(numpy.meshgrid(*([one] * d), indexing="ij"), axis=-1).reshape(-1, d)
    k, m = modes[:, None, :].astype(float), modes[None, :, :].astype(float)
    coeffs, degree = angular_coefficients(kernel, d, operator.angular_degree)
    rho, scale = operator._radial()
    gain = numpy.zeros(k.shape[:1] + m.shape[1:2])
    loss = numpy.zeros_like(gain)
    for r, s, e in zip(rho, scale, operator.restitution(rho)):
        a, b = math.pi * r * (1 + e) / (4 * L), math.pi * r / L
        x, y = a * k, a * k - b * m
        nx, ny = numpy.linalg.norm(x, axis=-1), numpy.linalg.norm(y, axis=-1)
        with numpy.errstate(invalid="ignore", divide="ignore"):
            cos = numpy.clip(numpy.where((nx > 0) & (ny > 0), numpy.sum(x * y, axis=-1)
                                         / (nx * ny), 1.0), -1.0, 1.0)
        for order in range(degree + 1):
            if d == 2:
                gain += s * 2 * math.pi * (1 if order == 0 else 2) * coeffs[order] * (
                    scipy.special.jv(order, nx) * scipy.special.jv(order, ny)
                    * scipy.special.eval_chebyt(order, cos))
            else:
                gain += s * 8 * math.pi ** 2 * (2 * order + 1) * coeffs[order] * (
                    scipy.special.spherical_jn(order, nx) * scipy.special.spherical_jn(order, ny)
                    * scipy.special.eval_legendre(order, cos))
        speed = b * numpy.linalg.norm(m, axis=-1)
        average = scipy.special.j0(speed) if d == 2 else numpy.sinc(speed / math.pi)
        loss = loss + s * average * (2 * math.pi * coeffs[0] if d == 3 else coeffs[0]) * (
            2 * math.pi if d == 2 else 4 * math.pi)
    difference = k - m
    valid = numpy.all(numpy.abs(difference) <= n // 2 - 1, axis=-1)
    index = numpy.ravel_multi_index(tuple(numpy.moveaxis(
        numpy.where(valid[..., None], difference, 0).astype(int) + n // 2 - 1, -1, 0)),
        (n - 1,) * d)
    return (gain - loss) * valid, numpy.where(valid, index, 0)


@pytest.mark.parametrize("dimension,n_modes,kernel,restitution", [
    (2, 10, "maxwell", {"value": 0.5}),
    (2, 8, "hard_spheres", {"value": 0.2}),
    (3, 6, "hard_spheres", {"value": 0.5}),
    (3, 8, "maxwell", {"value": 0.9}),
    (2, 8, "anisotropic", {"value": 0.5}),
    (3, 6, "anisotropic", {"value": 0.7}),
    (2, 8, "hard_spheres", {"name": "toscani", "strength": 0.5, "exponent": 0.5}),
], ids=["2d-maxwell", "2d-hs", "3d-hs", "3d-maxwell", "2d-anisotropic", "3d-anisotropic",
        "2d-toscani"])
def test_direct_weights_equal_the_formula_pair_by_pair(dimension, n_modes, kernel,
                                                       restitution):
    """To 1e-14 of the largest weight: the vectorised precomputation (keys of the fundamental
    rows, the isotropic constant-e weights as a matrix product over rho) and the pair-by-pair
    formula round differently, nothing else."""
    kernel = (gf.VariableHardSpheres(0.5, angular=lambda c: 1 + 0.4 * c)
              if kernel == "anisotropic" else gf.collision_kernel(kernel))
    law = gf.restitution_law(restitution.pop("name", "constant"), **restitution)
    operator = DirectSpectral(gf.VelocityGrid(dimension, n_modes, 4.0), kernel, law,
                              gf.array_backend("numpy", threads=1))
    weights, index = direct_weights_by_pairs(operator)
    assert numpy.array_equal(operator._l_index, index)
    assert numpy.max(numpy.abs(operator._weights - weights)) <= 1e-14 * numpy.max(
        numpy.abs(weights))
