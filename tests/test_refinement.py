"""Error bars from refinement (granframe.run.refinement, ``granframe refine``): the grid
convergence index against the worked example of Celik et al. (2008) and exact power laws,
a family of runs with a known order (first-order upwind transport in space, SSP RK3 in
time), the quantities read from the stores, the command line and its refusals."""


import math

import pytest

from granframe.run.refinement import Refinement, grid_convergence, parse, run_refinement

#: collisionless transport of a density wave on a periodic interval (2D N = 16)
BASE = {"final_time": 0.128, "time_step": 0.016, "kernel": "maxwell",
        "grid": {"dimension": 2, "n_modes": 16, "support_radius": 3.5},
        "restitution": {"name": "constant", "value": 1.0},
        "initial": {"name": "sinusoidal_mode", "field": "density", "amplitude": 0.2},
        "output": {"snapshot_interval": 0.128},
        "space": {"cells": 16, "reconstruction": "upwind", "collisions": False,
                  "left": "periodic", "right": "periodic"}}


def test_the_grid_convergence_index_of_the_worked_example():
    """Celik, Ghia, Roache, Freitas, Coleman & Raad, J. Fluids Eng. 130 (2008) 078001,
    table 1 (phi = 6.063, 5.972, 5.863 on grids of 18000, 8000, 4500 cells in 2D:
    r_21 = 1.5, r_32 = 1.333): p = 1.53, phi_ext = 6.1685, GCI_fine = 2.2 %."""
    result = grid_convergence([5.863, 5.972, 6.063], [1.5 * 1.333, 1.5, 1.0])
    assert result["convergence"] == "monotone" and result["observed"]
    assert result["order"] == pytest.approx(1.53, abs=0.01)
    assert result["extrapolated"] == pytest.approx(6.1685, abs=5e-4)
    assert result["gci"] == pytest.approx(0.022, abs=5e-4)


@pytest.mark.parametrize("order,spacings", [(2.0, [4.0, 2.0, 1.0]), (1.3, [3.0, 2.0, 1.0]),
                                            (3.0, [2.0, 1.5, 1.0, 0.5])])
def test_an_exact_power_law_gives_its_order_and_limit(order, spacings):
    """phi = 1.7 + 0.3 h^p, with constant and varying ratios: the order and the limit to
    1e-9; the index is 1.25 |e_21 / phi_1| / (r_21^p - 1)."""
    values = [1.7 + 0.3 * h ** order for h in spacings]
    result = grid_convergence(values, spacings)
    assert result["order"] == pytest.approx(order, abs=1e-9)
    assert result["extrapolated"] == pytest.approx(1.7, abs=1e-9)
    r21 = spacings[-2] / spacings[-1]
    e21 = abs(values[-2] - values[-1]) / values[-1]
    assert result["gci"] == pytest.approx(1.25 * e21 / (r21 ** order - 1), rel=1e-9)


def test_oscillatory_round_off_and_two_members_say_so():
    oscillating = grid_convergence([1.0, 1.1, 1.05], [4.0, 2.0, 1.0], formal_order=2.0)
    assert oscillating["convergence"] == "oscillatory" and not oscillating["observed"]
    assert oscillating["order"] == 2.0
    assert grid_convergence([1.0, 1.0, 1.0], [4.0, 2.0, 1.0])["convergence"] == "round-off"
    # the vibrated gas at N = 24, 32, 48: the last refinement moved it most
    divergent = grid_convergence([0.94737, 0.95109, 0.96427], [1 / 24, 1 / 32, 1 / 48])
    assert divergent["convergence"] == "divergent" and divergent["order"] is None
    assert math.isnan(divergent["error_bar"])
    two = grid_convergence([1.0, 1.03], [2.0, 1.0], formal_order=1.0)
    assert two["convergence"] == "two members" and two["gci"] == pytest.approx(3 * 0.03 / 1.03)
    with pytest.raises(ValueError, match=r"^grid_convergence: parameter 'formal_order' = None "
                                         r"is invalid; must be given with two members"):
        grid_convergence([1.0, 1.03], [2.0, 1.0])
    with pytest.raises(ValueError, match=r"parameter 'spacings' .* must decrease"):
        grid_convergence([1.0, 1.1, 1.2], [1.0, 2.0, 4.0])


def test_a_family_with_a_known_order(tmp_path):
    """First-order upwind transport: cells and time step refined together (16, 32, 64),
    the mean velocity at x = 1/2 (measured order 0.99, monotone); the time step alone on
    16 cells (SSP RK3): order 2.9 (measured 2.95 on the density of a cell centre). The
    stores are in OUT/family.zarr, the table, JSON and figure beside it."""
    cells = Refinement(BASE, {"space.cells": [16, 32, 64], "time_step": [0.016, 0.008, 0.004]},
                       ["velocity.v1@t=0.128,x=0.5"])
    result = run_refinement(cells, tmp_path / "cells", workers=1, progress=False)
    row = result.rows[0]
    assert row["convergence"] == "monotone" and row["order"] == pytest.approx(1.0, abs=0.1)
    assert abs(row["extrapolated"] - row["values"][-1]) < row["error_bar"]
    for name in ("refinement.md", "refinement.json", "refinement.png"):
        assert (tmp_path / "cells" / name).stat().st_size > 100
    steps = Refinement(BASE, {"time_step": [0.016, 0.008, 0.004, 0.002]},
                       ["density@t=0.128,x=0.28125"])
    row = run_refinement(steps, tmp_path / "steps", workers=1, progress=False).rows[0]
    assert row["order"] == pytest.approx(3.0, abs=0.15), row


@pytest.mark.parametrize("vary,what", [
    ({"restitution.value": [0.5, 0.6, 0.7]}, "must be one of grid.n_modes, space.cells, "
                                             "time_step"),
    ({"space.cells": [32, 16, 64]}, "must go from coarse to fine"),
    ({"space.cells": [16, 32], "time_step": [0.016, 0.004]}, "same ratio"),
    ({"space.cells": [16, 32], "time_step": [0.016, 0.008, 0.004]}, "same number of values"),
    ({"space.cells": [16]}, "at least two values"),
])
def test_bad_refinements_are_refused_by_name(vary, what):
    with pytest.raises((ValueError, TypeError),
                       match=rf"^Refinement: parameter 'vary' = .* is invalid; .*{what}"):
        Refinement(BASE, vary, ["density@t=0.128,x=0.5"])


@pytest.mark.parametrize("spec,what", [("temperature@t", "t=, x=, wall= at most once"),
                                       ("temperature@t=a", "a number"),
                                       ("temperature@wall=top", "wall=left or wall=right"),
                                       ("2temperature", "must read NAME")])
def test_bad_quantities_are_refused_by_name(spec, what):
    with pytest.raises(ValueError, match=rf"^quantity: parameter 'spec' = .* is invalid; .*{what}"):
        parse(spec)


def test_the_command_line(tmp_path, capsys):
    import tomli_w

    from granframe.tools.cli import main

    (tmp_path / "wave.toml").write_text(tomli_w.dumps(BASE))
    argv = ["refine", str(tmp_path / "wave.toml"), "--vary", "space.cells=16,32,64",
            "--vary", "time_step=0.016,0.008,0.004", "--quantity",
            "velocity.v1@t=0.128,x=0.5", "--out", str(tmp_path / "ref"), "--workers", "1"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "| velocity.v1@t=0.128,x=0.5 | 0.090021966, 0.10294885, 0.10946807 | 0.988 | " \
           "monotone |" in out
    assert main(argv[:3] + ["space.cells=16,x"] + argv[4:]) == 2
    assert "parameter '--vary' = 'space.cells=16,x' is invalid; its values must be numbers" \
        in capsys.readouterr().err
    assert main(argv[:-4] + ["--quantity", "nothing@t=0.128,x=0.5", "--out",
                             str(tmp_path / "ref2"), "--workers", "1"]) == 2
    err = capsys.readouterr().err
    assert "quantity: parameter 'spec' = 'nothing@t=0.128,x=0.5' is invalid; must name a " \
           "recorded variable" in err and "Traceback" not in err
