"""The heated steady state against e, for Maxwell molecules and hard spheres (2D): a Dask sweep.

    python studies/heated_state_sweep.py --out docs/figures/sweep   # ~4 min on 2 cores

A sweep (granframe.run.sweep) over e in {0.2, 0.4, 0.6, 0.8, 0.9, 0.95} (product) and the two
kernels (product), with the heat bath tau = (1 - e^2)/8 zipped to e. That tau makes the
exact steady temperature of Maxwell molecules 8 tau / (1 - e^2) = 1 for every e. f0 is
the Maxwellian T0 = 1, with N = 48, S = 4.5, N_rho = 24, M = 24, RK4, dt = 0.05, to t = 20.
Reported: the steady temperature and kurtosis (the last record of each run) against e.
Maxwell molecules check the sweep against the exact law (T = 1). The sweep is run twice
into fresh stores, on a LocalCluster of 1 and of 2 worker processes, for the wall-time
scaling (docs/scaling.md); each run uses one thread. The sweep's TOML is written next to
the figures, for ``granframe sweep``.
"""

from __future__ import annotations

import pathlib
import shutil

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402
import tomli_w  # noqa: E402

from granframe.tools.studykit import command, finish, save_figure, write_csv, write_summary  # noqa: E402
from granframe.run.sweep import Sweep, read_table, run_sweep  # noqa: E402

RESTITUTIONS = (0.2, 0.4, 0.6, 0.8, 0.9, 0.95)


def sweep(quick: bool = False) -> Sweep:
    restitutions = RESTITUTIONS[::3] if quick else RESTITUTIONS
    base = {
        "title": "heated steady state", "final_time": 2.0 if quick else 20.0,
        "time_step": 0.05, "grid": {"dimension": 2, "n_modes": 40 if quick else 48,
                                    "support_radius": 4.5},
        "kernel": "maxwell", "restitution": {"name": "constant", "value": 0.5},
        "initial": {"name": "maxwellian", "temperature": 1.0},
        "operator": {"name": "fast_spectral", "radial_points": 24,
                     "sphere": {"name": "circle_trapezoid", "n_points": 24}},
        "output": {"snapshot_interval": 1.0 if quick else 5.0},
        # one thread per run: the workers are the parallelism (two 2-thread runs on 2 cores
        # ran 1.5x slower each, and the sweep gained only 1.29x from the second worker)
        "backend": {"name": "auto", "threads": 1},
    }
    return Sweep(base, product={"kernel": ["maxwell", "hard_spheres"]},
                 zip={"restitution.value": list(restitutions),
                      "heat_bath": [(1 - e * e) / 8 for e in restitutions]})


def run(out: pathlib.Path, quick: bool = False) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    study = sweep(quick)
    (out / "sweep.toml").write_text(tomli_w.dumps(study.to_dict()))
    timings = {}
    for workers in (1, 2):
        store = out / f"sweep_{workers}_workers.zarr"
        if store.exists():
            shutil.rmtree(store)
        result = run_sweep(study, store, workers=workers, progress=False)
        timings[workers] = result.wall_seconds
    table = read_table(out / "sweep_2_workers.zarr")
    rows = [{key: (value.item() if hasattr(value, "item") else value)
             for key, value in zip(table, values)} for values in zip(*table.values())]
    rows = [{k: (str(v) if isinstance(v, numpy.str_) else v) for k, v in r.items()}
            for r in rows]
    write_csv(out / "heated_state.csv", rows)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), constrained_layout=True)
    names = {"maxwell": "Maxwell molecules (λ = 0)", "hard_spheres": "hard spheres (λ = 1)"}
    for kernel, marker in (("maxwell", "o-"), ("hard_spheres", "s-")):
        chosen = sorted((r for r in rows if r["kernel"] == kernel),
                        key=lambda r: r["restitution.value"])
        e = [r["restitution.value"] for r in chosen]
        label = f"{names[kernel]}, one run per e"
        axes[0].plot(e, [r["temperature"] for r in chosen], marker, label=label)
        axes[1].plot(e, [r["kurtosis"] for r in chosen], marker, label=label)
    axes[0].axhline(1.0, color="k", ls=":", lw=1,
                    label="exact steady state of Maxwell molecules, T = 1")
    axes[1].axhline(2.0, color="k", ls=":", lw=1, label="Maxwellian (2D), 2")
    final = study.base["final_time"]
    axes[0].set(xlabel="restitution coefficient e (dimensionless)",
                ylabel=f"temperature T at t = {final:g} (dimensionless)",
                title=r"heated state, heat bath $\tau = (1 - e^2)/8$")
    axes[1].set(xlabel="restitution coefficient e (dimensionless)",
                ylabel=rf"kurtosis $\kappa$ at t = {final:g} (dimensionless)",
                title="heated state: overpopulated tails")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend()
    grid, operator = study.base["grid"], study.base["operator"]
    fig.suptitle(f"a sweep over e and the kernel: 2D, N = {grid['n_modes']}, S = "
                 f"{grid['support_radius']:g}, fast_spectral, N_ρ = {operator['radial_points']}, "
                 f"circle M = {operator['sphere']['n_points']};\nRK4, Δt = "
                 f"{study.base['time_step']:g}, to t = {final:g}; constant e, Maxwellian "
                 "T0 = 1; all quantities dimensionless", fontsize=10)
    save_figure(fig, out / "heated_state.png")
    maxwell = [r for r in rows if r["kernel"] == "maxwell"]
    summary = {"runs": len(rows), "finished": sum(r["status"] == "finished" for r in rows),
               "wall_seconds": {str(k): v for k, v in timings.items()},
               "speed_up_2_workers": timings[1] / timings[2],
               "maxwell_max_T_error": max(abs(r["temperature"] - 1.0) for r in maxwell),
               "rows": rows}
    write_summary(out, summary)
    for workers in (1, 2):       # the figures and table are kept; the stores are large
        shutil.rmtree(out / f"sweep_{workers}_workers.zarr")
    return summary


def _show(summary):
    print(f"{summary['finished']} of {summary['runs']} runs finished; wall time "
          f"{summary['wall_seconds']} s, speed-up with 2 workers "
          f"{summary['speed_up_2_workers']:.2f}; Maxwell max |T - 1| "
          f"{summary['maxwell_max_T_error']:.2e}")
    for r in summary["rows"]:
        print(f"  {r['kernel']:<12} e = {r['restitution.value']:<5g} T = {r['temperature']:.6f} "
              f"kurtosis = {r['kurtosis']:.5f} wall {r['wall_seconds']:.1f} s")


main = command(run, __doc__, "2 restitutions, N = 40, to t = 2 (smoke test)", show=_show)


if __name__ == "__main__":
    raise SystemExit(finish(main))
