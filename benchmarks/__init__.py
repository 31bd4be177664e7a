"""granframe's benchmark suite for asv (airspeed velocity), run from the repository root.

    asv run --python=same --quick          # the installed granframe, every benchmark once
    asv continuous --factor 1.05 A B       # two commits, each built in its own environment

See docs/benchmarks.md, "Tracking across commits". The modules:

- :mod:`benchmarks.bench_operator` -- one call of the fast collision operator;
- :mod:`benchmarks.bench_space` -- one step of a run in space (collisions and transport);
- :mod:`benchmarks.bench_store` -- one commit to a run store, in memory and on disk.

Everything a benchmark builds is built in ``setup`` and kept for the process (asv re-runs
``setup`` before every timed call), so that only the call itself is timed.
"""
