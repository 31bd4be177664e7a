"""One command to validate the CuPy backend on a GPU machine and record its numbers.

    pip install -e ".[test,gpu]" && python -m granframe_cupy.validate --out gpu-validation

1. The GPU tests (``pytest -m gpu tests/test_cupy_backend.py``): the operators on the GPU
   equal the NumPy backend to 1e-12 (2D, 3D, fast and direct), float32 within its floor, a
   run on the GPU equals the CPU run, and the bench reports device memory.
2. ``granframe bench --backend cupy`` on the review's table (3D, N = 8, 16, 32, 64;
   N_rho = 30, M = 32) plus N = 128, in float64 and float32: time per evaluation by CUDA
   events (median after warm-up), the cuFFT floor and time/floor, device memory.

Writes ``OUT/gpu_tests.txt``, ``OUT/bench.json`` and ``OUT/bench.md`` (with the device name),
and exits with the tests' status.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import subprocess
import sys

from granframe import bench
from granframe_cupy import gpu_available

CONFIGS = [(3, n, 30, 32) for n in (8, 16, 32, 64, 128)]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--repeats", type=int, default=20)
    args = parser.parse_args(argv)
    if not gpu_available():
        print("granframe_cupy.validate: no CuPy or no CUDA device here", file=sys.stderr)
        return 2
    import cupy

    args.out.mkdir(parents=True, exist_ok=True)
    device = cupy.cuda.runtime.getDeviceProperties(0)["name"].decode()
    tests = subprocess.run([sys.executable, "-m", "pytest", "-m", "gpu", "-v",
                            "tests/test_cupy_backend.py"], capture_output=True, text=True)
    (args.out / "gpu_tests.txt").write_text(tests.stdout + tests.stderr)
    print(tests.stdout.strip().splitlines()[-1] if tests.stdout.strip() else tests.stderr)
    records = []
    for precision in ("float64", "float32"):
        records += bench.run(CONFIGS, "cupy", 1, args.repeats, precision)
    (args.out / "bench.json").write_text(json.dumps({"device": device, "records": records},
                                                    indent=2))
    text = (f"fast_spectral on {device} (cupy backend), CUDA events, median of "
            f"{args.repeats} after warm-up\n\n{bench.table(records)}\n")
    (args.out / "bench.md").write_text(text)
    print(text)
    return tests.returncode


if __name__ == "__main__":
    raise SystemExit(main())
