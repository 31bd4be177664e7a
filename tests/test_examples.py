"""The examples under docs/examples run as shipped (their quick variants)."""

import os
import pathlib
import subprocess
import sys

import pytest

EXAMPLES = sorted((pathlib.Path(__file__).parent.parent / "docs" / "examples").glob("*.py"))


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.name)
def test_example_runs(example, tmp_path):
    env = {**os.environ, "GRANFRAME_QUICK": "1", "GRANFRAME_EXAMPLE_OUT": str(tmp_path),
           "MPLBACKEND": "Agg"}
    done = subprocess.run([sys.executable, str(example)], env=env, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "max |T/T_exact - 1|" in done.stdout
    assert (tmp_path / "first_hour.png").stat().st_size > 10_000


def test_the_examples_are_found():
    assert [p.name for p in EXAMPLES] == ["first_hour.py"]
