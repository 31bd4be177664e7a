"""The space set-ups several studies share (studies/space.py, studies/euler_limit.py,
studies/hierarchy.py; docs/space.md): the elastic Sod tube of 2D Maxwell molecules between
specular walls with its L1 errors against the exact Euler solution, and Maxwell molecules
between two diffuse walls; dt at the transport's CFL limit."""

from __future__ import annotations

import numpy

from granframe.run.description import RunDescription
from granframe.theory.euler import euler_riemann_cell_averages
from granframe.tools.studykit import cfl_time_step

#: the velocity grid of the Sod tube: on N = 24 (h = 0.644, h/sqrt(T) = 0.88 in the
#: rarefaction's T = 0.53) the spectral Q of the grid Maxwellian is 5e-4 of its peak, and the
#: star states of the eps -> 0 limit come out about 1 % off (the refinement stalls near L1
#: rho = 1.2e-2 at 200 cells); on N = 32, 1.6e-5 and 0.2 %
SOD_GRID = {"dimension": 2, "n_modes": 32, "support_radius": 3.5}
# the edge monitors of the quick Sod tube (50 cells, N = 32, S = 3.5) warn: at t = 0.2 the
# share of the energy beyond the edge radius in the worst cell is 0.76 % (eps = 1e-2),
# 0.18 % (1e-3) and 0.19 % (1e-4), above the tolerance 0.1 %. It is the velocity grid's
# resolution, not the box: at eps = 1e-2 a wider support S = 4.5 at N = 32 (h = 0.621)
# raises it to 2.6 %, while N = 40 and 48 at S = 3.5 lower it to 0.24 % and 0.12 %; a
# quick variant that silences them would cost more than twice as much
#: the velocity grid of the wall runs (T from 0.8 to 1.2)
GRID = {"dimension": 2, "n_modes": 24, "support_radius": 3.5}
GAMMA = 2.0                       # (d + 2)/d with d = 2
SOD_LEFT = {"density": 1.0, "temperature": 1.0}
SOD_RIGHT = {"density": 0.125, "temperature": 0.8}
SOD_FINAL = 0.2


def euler_state(state) -> tuple:
    """(rho, u, p) of a {density, temperature} state at rest, p = rho T: the argument of
    :func:`granframe.theory.euler.euler_riemann`."""
    return (state["density"], 0.0, state["density"] * state["temperature"])


def sod_description(cells: int, knudsen: float, final: float = SOD_FINAL, grid=SOD_GRID,
                    integrator: str = "penalised_ars222", conservative=True) -> RunDescription:
    """The elastic Sod tube between specular walls at dt = the CFL limit."""
    return RunDescription(
        title=f"Sod tube, eps = {knudsen:g}, {cells} cells",
        grid=grid, kernel="maxwell", restitution={"name": "constant", "value": 1.0},
        initial={"name": "riemann", "left": SOD_LEFT, "right": SOD_RIGHT},
        operator={"name": "fast_spectral"}, integrator=integrator, knudsen=knudsen,
        conservative=conservative, time_step=cfl_time_step(cells, final, grid),
        final_time=final, output={"snapshot_interval": final},
        space={"cells": cells, "left": "specular", "right": "specular"})


def sod_errors(ds) -> dict:
    """L1 errors sum_i dx |w_i - w_exact,i| of rho, u_1, T at the last step of a Sod run
    against the cell averages of the exact Euler solution (gamma = 2) at that time."""
    cells = ds.sizes["x"]
    edges = numpy.linspace(0.0, 1.0, cells + 1)
    t = float(ds.step_time.values[-1])
    exact = euler_riemann_cell_averages(euler_state(SOD_LEFT), euler_state(SOD_RIGHT),
                                        GAMMA, edges, t)
    computed = {"rho": ds.density.values[-1], "u": ds.velocity.values[-1][:, 0],
                "T": ds.temperature.values[-1]}
    return {name: float(numpy.sum(numpy.abs(computed[name] - exact[name])) / cells)
            for name in computed}


def walls_description(cells: int, knudsen: float, restitution: float, T1: float, T2: float,
                      initial: float, final: float, fraction: float = 1.0,
                      title: str = "", conservative=False) -> RunDescription:
    """Maxwell molecules between diffuse walls at T1 (x = 0) and T2 (x = 1), from the
    Maxwellian of temperature ``initial``, explicit SSP RK2 collisions, on :data:`GRID`
    with dt at ``fraction`` of the CFL limit."""
    return RunDescription(
        title=title or f"diffuse walls T1 = {T1:g}, T2 = {T2:g}, e = {restitution:g}, "
                       f"eps = {knudsen:g}, {cells} cells",
        grid=GRID, kernel="maxwell", restitution={"name": "constant", "value": restitution},
        initial={"name": "maxwellian", "temperature": initial},
        operator={"name": "fast_spectral"}, integrator="ssp_rk2", knudsen=knudsen,
        conservative=conservative,
        time_step=cfl_time_step(cells, final, GRID, fraction=fraction), final_time=final,
        output={"snapshot_interval": final},
        space={"cells": cells, "left": {"name": "diffuse", "temperature": T1},
               "right": {"name": "diffuse", "temperature": T2}})
