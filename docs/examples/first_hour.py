# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#   kernelspec:
#     display_name: Python 3
#     name: python3
# ---

# %% [markdown]
# # A first hour with granframe: compose, run, open, plot, compare
#
# The review's heated Maxwell molecules in 2D (Carrillo, Hu, Ma, Rey, section 3, Test 1(b)):
# d_t f = Q(f, f) + τ Δ_v f with B = 1/(2π), e = 0.5, τ = 0.1, from the Maxwellian with
# T0 = 8. Its temperature is known exactly,
# T(t) = (T0 − 8τ/(1−e²)) exp(−(1−e²) t/4) + 8τ/(1−e²),
# so the error of a run can be measured, and shown to converge as the grid is refined.
#
# Open it in Jupyter with `jupytext --to notebook docs/examples/first_hour.py`, or run it as
# a script: `python docs/examples/first_hour.py` (about a minute; `GRANFRAME_QUICK=1` for a
# few seconds). It writes its stores and figure under `runs/first_hour/`
# (`GRANFRAME_EXAMPLE_OUT` to change that).

# %%
import os
import pathlib

import matplotlib.pyplot as plt
import numpy

import granframe as gf
from granframe.model.exact import heated_maxwell_temperature
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.tools import plotting

QUICK = os.environ.get("GRANFRAME_QUICK") == "1"
OUT = pathlib.Path(os.environ.get("GRANFRAME_EXAMPLE_OUT", "runs/first_hour"))
OUT.mkdir(parents=True, exist_ok=True)

# %% [markdown]
# ## Compose the study in Python
# A description is an attrs value: a base, and the variants made from it with
# `attrs.evolve`-style changes. Here the grid is refined, N = 24, 32, 40 (quick) or
# 32, 48, 64, with the review's support S = 10 (R = 20, L = 5(3 + √2)) and RK4.

# %%
E, TAU, T0 = 0.5, 0.1, 8.0
FINAL = 0.4 if QUICK else 4.0
MODES = (24, 32, 40) if QUICK else (32, 48, 64)


def description(n_modes: int) -> RunDescription:
    return RunDescription(
        title=f"heated Maxwell molecules, N = {n_modes}",
        grid={"dimension": 2, "n_modes": n_modes, "support_radius": 10.0},
        kernel="maxwell", restitution={"name": "constant", "value": E},
        initial={"name": "maxwellian", "temperature": T0},
        operator={"name": "fast_spectral", "radial_points": 32,
                  "sphere": {"name": "circle_trapezoid", "n_points": 16}},
        integrator="rk4", heat_bath=TAU, time_step=0.01, final_time=FINAL,
        output={"snapshot_interval": FINAL / 4})


# %% [markdown]
# ## Run each variant into its own store
# A store is safe to interrupt: `Simulation(d).run(path, resume=True)` continues it.

# %%
stores = {}
for n in MODES:
    stores[n] = OUT / f"heated_N{n}.zarr"
    result = Simulation(description(n)).run(stores[n], overwrite=True, progress=False)
    print(f"N = {n}: {result.status}, {result.steps} steps in {result.wall_seconds:.1f} s"
          + "".join(f"\n  warning: {w}" for w in result.warnings))

# %% [markdown]
# ## Open a run as an xarray Dataset
# Coordinates `time` (snapshots of f), `step_time` (moments, every step), `v1`, `v2`; every
# variable carries `units` and `long_name`, and the description is in the attributes.

# %%
ds = gf.open_run(stores[MODES[-1]])
print(ds)
print(ds.temperature.attrs)

# %% [markdown]
# ## Compare with the exact law, grid by grid
# The largest relative error of T over the run, for each N: it must fall as N grows
# (the refinement column), down to what the time step and the truncation R = 20 leave.

# %%
print(f"{'N':>4} | max |T/T_exact - 1|")
errors = {}
for n in MODES:
    run = gf.open_run(stores[n])
    exact = heated_maxwell_temperature(run.step_time.values, T0, E, TAU)
    errors[n] = float(numpy.max(numpy.abs(run.temperature.values / exact - 1)))
    print(f"{n:>4} | {errors[n]:.2e}")
assert errors[MODES[-1]] < errors[MODES[0]], "the error must fall as N is refined"

# %% [markdown]
# ## Plot with granframe's functions, into a figure of one's own

# %%
fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
plotting.temperature(ds, ax=left)
for n in MODES:
    run = gf.open_run(stores[n])
    exact = heated_maxwell_temperature(run.step_time.values, T0, E, TAU)
    right.semilogy(run.step_time, numpy.abs(run.temperature / exact - 1) + 1e-300,
                   label=f"N = {n}")
right.set(xlabel="time t (dimensionless)", ylabel="|T/T_exact − 1| (dimensionless)",
          title="error against the exact law, by N", ylim=(1e-12, None))
right.legend()
fig.suptitle(plotting.caption(ds), fontsize=8)
fig.savefig(OUT / "first_hour.png", dpi=110)
print("figure:", OUT / "first_hour.png")
