"""The examples under docs/examples run as shipped (their quick variants), and the worked 3D
example with walls (docs/space.md) parses, builds and is within its step limits."""

import os
import pathlib
import re
import subprocess
import sys

import pytest

from granframe.tools.cli import main

EXAMPLES = sorted((pathlib.Path(__file__).parent.parent / "docs" / "examples").glob("*.py"))
WALLS_3D = pathlib.Path(__file__).parent.parent / "docs" / "examples" / "walls_3d.toml"


@pytest.mark.slow
@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.name)
def test_example_runs(example, tmp_path):
    env = {**os.environ, "GRANFRAME_QUICK": "1", "GRANFRAME_EXAMPLE_OUT": str(tmp_path),
           "MPLBACKEND": "Agg"}
    done = subprocess.run([sys.executable, str(example)], env=env, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "max |T/T_exact - 1|" in done.stdout
    errors = [float(e) for e in re.findall(r"^ *\d+ \| ([0-9.e+-]+)$", done.stdout, re.M)]
    assert len(errors) == 3 and errors == sorted(errors, reverse=True), done.stdout
    assert (tmp_path / "first_hour.png").stat().st_size > 10_000


def test_the_examples_are_found():
    assert [p.name for p in EXAMPLES] == ["first_hour.py"]


def test_the_3d_walls_example_builds_within_its_limits(capsys):
    """``granframe limits docs/examples/walls_3d.toml``, as docs/space.md shows it: within
    both limits, and its operator built and one step timed (not the run)."""
    assert main(["limits", str(WALLS_3D)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == ("transport ('muscl', SSP RK3 half steps): dt <= 0.01573; time_step "
                        "= 0.0125 is within it (0.795 of it)")
    assert lines[1].startswith("'ssp_rk2': dt <= 0.025, set by the collision term Q/eps")
    assert lines[2] == "  time_step = 0.0125: within it (0.5 of the limit)"
    assert re.fullmatch(r"estimated cost: 80 steps x .* per step \(one step timed on \d+ "
                        r"CPUs\) = .*", lines[3]), lines


LID_BOX = pathlib.Path(__file__).parent.parent / "docs" / "examples" / "lid_box.toml"


def test_the_lid_box_example_builds_within_its_limits(capsys):
    """``granframe limits docs/examples/lid_box.toml`` (the README's example on a rectangle):
    within the transport's limit on both axes and the collisions' limit."""
    assert main(["limits", str(LID_BOX), "--no-cost"]) == 0
    text = capsys.readouterr().out
    assert "both axes at once" in text and "ABOVE" not in text
