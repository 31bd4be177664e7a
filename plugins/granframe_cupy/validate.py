"""One command to validate the CuPy backend on a GPU machine and record its numbers.

    pip install -e ".[test,gpu]" && python -m granframe_cupy.validate --out gpu-validation

(where CuPy is already installed, e.g. a ``cupy-cuda12x`` or ``cupy-cuda13x`` wheel,
``pip install -e ".[test]"`` is enough).

1. The GPU tests (``pytest -m gpu`` over the backend-parametrised test files): on the GPU,
   with the fused kernels and with the generic steps, the element-wise steps equal einsum,
   the operators equal the NumPy backend to 1e-12 (2D and 3D, fast and direct), float32
   stays within its floor, mass is conserved and energy dissipated (hypothesis), a run on
   the GPU equals the CPU run, and the bench reports device memory.
2. ``granframe bench --backend cupy`` on the review's table (3D, N = 8, 16, 32, 64;
   N_rho = 30, M = 32) plus N = 128, in float64 and float32 with the fused kernels, and in
   float64 with the generic steps: time per evaluation by CUDA events (median after
   warm-up), the cuFFT floor (the operator's batched transforms) and time/floor, device
   memory.
3. The targets on an H100: 3D N = 64 in <= 15 ms per evaluation (float64), and
   3D N = 128 runs.

Writes ``OUT/gpu_tests.txt``, ``OUT/bench.json`` and ``OUT/bench.md`` (with the device
name), and exits with the tests' status.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import subprocess
import sys

from granframe.tools import bench
from granframe_cupy import gpu_available

CONFIGS = [(3, n, 30, 32) for n in (8, 16, 32, 64, 128)]
#: Test files with backend-parametrised (gpu-marked) cases.
TEST_FILES = ["tests/test_backend_kernels.py", "tests/test_cupy_backend.py",
              "tests/test_operators.py", "tests/test_operator_properties.py"]
#: Target seconds per evaluation of 3D N = 64 (N_rho = 30, M = 32) on an H100.
TARGET_N64_S = 15e-3
#: The variants timed: label, precision, backend options.
VARIANTS = [("fused kernels", "float64", {}), ("fused kernels", "float32", {}),
            ("generic steps", "float64", {"fused": False})]


def benchmark(out: pathlib.Path, device: str, repeats: int, configs=CONFIGS,
              options: dict | None = None) -> str:
    """Step 2 and 3: time the variants, write ``bench.json`` and ``bench.md`` into ``out``,
    return the report. ``options`` are added to every variant's backend options
    (``{"module": "numpy"}`` runs the same steps on the host)."""
    sections, records = [], []
    for label, precision, variant in VARIANTS:
        part = bench.run(configs, "cupy", 1, repeats, precision, {**variant, **(options or {})})
        records += part
        sections.append(f"### {precision}, {label}\n\n{bench.table(part)}\n")
    largest = max(r["n_modes"] for r in records)
    lines = [f"3D N = {largest} ran."]
    n64 = [r for r in records if r["n_modes"] == 64 and r["precision"] == "float64"
           and "fused" not in r["backend_options"]]
    if n64:
        seconds = n64[0]["evaluation_s"]
        lines.insert(0, f"3D N = 64, float64: {seconds * 1e3:.2f} ms per evaluation (target "
                        f"<= {TARGET_N64_S * 1e3:.0f} ms on an H100: "
                        f"{'met' if seconds <= TARGET_N64_S else 'NOT met'}).")
    (out / "bench.json").write_text(json.dumps({"device": device, "records": records},
                                               indent=2))
    text = (f"fast_spectral on {device} (cupy backend), CUDA events, median of {repeats} "
            f"after warm-up\n\n" + "\n".join(sections) + "\n" + "\n".join(lines) + "\n")
    (out / "bench.md").write_text(text)
    return text


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--repeats", type=int, default=20)
    args = parser.parse_args(argv)
    if not gpu_available():
        print("granframe_cupy.validate: no CuPy or no CUDA device here", file=sys.stderr)
        return 2
    missing = [name for name in TEST_FILES if not pathlib.Path(name).is_file()]
    if missing:
        print(f"granframe_cupy.validate: run it from the repository root ({missing[0]} "
              "not found here)", file=sys.stderr)
        return 2
    import cupy

    args.out.mkdir(parents=True, exist_ok=True)
    device = cupy.cuda.runtime.getDeviceProperties(0)["name"].decode()
    tests = subprocess.run([sys.executable, "-m", "pytest", "-m", "gpu", "-v", *TEST_FILES],
                           capture_output=True, text=True)
    (args.out / "gpu_tests.txt").write_text(tests.stdout + tests.stderr)
    print(tests.stdout.strip().splitlines()[-1] if tests.stdout.strip() else tests.stderr)
    print(benchmark(args.out, device, args.repeats))
    return tests.returncode


if __name__ == "__main__":
    raise SystemExit(main())
