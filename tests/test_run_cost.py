"""What a run will cost and what it should be, said before it starts: the cost estimate of
``granframe run`` and ``granframe limits``, the limits table of a step above a limit, and
the hint that points a free-cooling run to ``rescaled = true``."""

import json
import re

import pytest

from granframe.run.monitors import cooling_hint
from granframe.run.problems import RunCost, make_problem, run_cost
from granframe.tools.cli import main
from test_runner import heated
from test_space_store import TOML as SPACE_TOML

COST = re.compile(r"estimated cost: (\d+) steps x ([0-9.e+-]+) (s|min|h) per step \(one step "
                  r"timed on \d+ CPUs\) = ([0-9.e+-]+) (s|min|h)")


def test_run_cost_times_a_step_and_counts_the_steps():
    problem = make_problem(heated())
    f0 = problem.f0.copy()
    cost = run_cost(problem, repeats=2)
    assert cost.steps == 20 and 0.0 < cost.step_seconds < 60.0 and cost.cpus >= 1
    assert cost.total_seconds == pytest.approx(20 * cost.step_seconds)
    assert COST.fullmatch(cost.text()), cost.text()
    assert (problem.f0 == f0).all()     # the run's f0 is not touched
    assert cost.to_dict()["total_seconds"] == cost.total_seconds
    adaptive = RunCost(0.5, None, 2)
    assert adaptive.total_seconds is None and "adaptive error control" in adaptive.text()
    with pytest.raises(ValueError, match="'repeats' = 0 is invalid"):
        run_cost(problem, repeats=0)


def test_a_space_runs_cost_leaves_its_first_wall_record_alone():
    """The timed steps' wall totals are taken by their own records: the run's first record
    after the estimate starts from zero, as without it."""
    from granframe.run.description import RunDescription

    problem = make_problem(RunDescription.from_toml(SPACE_TOML))
    run_cost(problem)
    record = problem.record(problem.state(problem.f0))
    assert (record["wall_mass"] == 0.0).all() and (record["wall_energy"] == 0.0).all()


def test_granframe_run_prints_the_estimated_cost_before_stepping(tmp_path, capsys):
    path = tmp_path / "heated.toml"
    path.write_text(heated().to_toml())
    assert main(["run", str(path), "--out", str(tmp_path / "h.zarr")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert COST.fullmatch(out[0].removeprefix("granframe: ")), out
    assert int(COST.fullmatch(out[0].removeprefix("granframe: ")).group(1)) == 20
    assert "finished, 20 steps" in out[1]


def test_granframe_limits_prints_the_cost_and_json_holds_it(tmp_path, capsys):
    path = tmp_path / "heated.toml"
    path.write_text(heated().to_toml())
    assert main(["limits", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("'rk4': dt <= ") and COST.fullmatch(lines[-1]), lines
    assert main(["limits", str(path), "--json"]) == 0
    cost = json.loads(capsys.readouterr().out)["runs"][""]["cost"]
    assert cost["steps"] == 20 and cost["total_seconds"] == pytest.approx(
        20 * cost["step_seconds"])
    assert main(["limits", str(path), "--no-cost"]) == 0
    assert "estimated cost" not in capsys.readouterr().out


def test_granframe_limits_prints_its_table_when_the_step_is_above_the_transport_limit(
        tmp_path, capsys):
    """A space run whose step is above the transport's CFL limit: the description alone is
    refused by granframe run; limits prints every limit, names the one violated, estimates
    the cost all the same and exits with status 3."""
    path = tmp_path / "sod.toml"
    path.write_text(SPACE_TOML.replace("time_step = 0.003", "time_step = 0.012")
                    .replace("snapshot_interval = 0.006", "snapshot_interval = 0.012"))
    assert main(["run", str(path), "--out", str(tmp_path / "s.zarr")]) == 2
    assert "the transport's CFL limit" in capsys.readouterr().err
    assert main(["limits", str(path)]) == 3
    lines = capsys.readouterr().out.splitlines()
    assert re.fullmatch(r"transport \('muscl', SSP RK3 half steps\): dt <= [0-9.]+; "
                        r"time_step = 0.012 is ABOVE it \(granframe run refuses it\)",
                        lines[0]), lines
    assert lines[1].startswith("'rk4': dt <= ") and COST.fullmatch(lines[-1]), lines
    assert main(["limits", str(path), "--set", "time_step=0.024", "--set",
                 "output.snapshot_interval=0.024", "--set", "health.step_limit=false",
                 "--no-cost"]) == 3
    assert ("time_step = 0.024 is ABOVE it (health.step_limit = false: granframe run does "
            "not check it)") in capsys.readouterr().out
    assert main(["limits", str(path), "--set", "time_step=0.003", "--no-cost"]) == 0


def free_cooling(**changes):
    """Heated Maxwell molecules without their heat bath: a free-cooling run."""
    return heated(**{"heat_bath": 0.0, **changes})


def test_a_free_cooling_run_is_pointed_to_the_rescaled_formulation(tmp_path, capsys):
    hint = cooling_hint(free_cooling())
    assert "rescaled = true" in hint and "free cooling" in hint
    assert cooling_hint(free_cooling(rescaled=True, integrator="rk4")) is None
    assert cooling_hint(heated()) is None                                 # heated
    assert cooling_hint(free_cooling(restitution={"name": "constant", "value": 1.0})) is None
    assert cooling_hint(free_cooling(restitution={"name": "viscoelastic",
                                                  "strength": 0.2})) is None   # e(|g|)
    path = tmp_path / "cooling.toml"
    path.write_text(free_cooling().to_toml())
    assert main(["run", str(path), "--out", str(tmp_path / "c.zarr")]) == 0
    assert f"granframe: hint: {hint}" in capsys.readouterr().err.splitlines()
