"""Helpers shared by the benchmark modules (not benchmarks themselves)."""

from __future__ import annotations

#: Threads of the array backend in every benchmark: the setting of ``granframe bench``.
THREADS = 2

#: What a benchmark process has built, by key: asv calls ``setup`` before every timed call,
#: and an operator's precomputation (seconds at 3D N = 32) must not be repeated each time.
_BUILT: dict = {}


def cached(key, build):
    """``build()`` the first time ``key`` is asked for in this process, then the same object."""
    if key not in _BUILT:
        _BUILT[key] = build()
    return _BUILT[key]


def require(module: str, what: str):
    """Import ``module``; in a commit that does not have it yet, NotImplementedError (asv:
    skipped) naming ``what``, so that the suite also runs on older commits."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise NotImplementedError(f"{what} is not in this version of granframe "
                                  f"({exc})") from exc


def array_backend(name: str, threads: int = THREADS):
    """The array backend ``name`` with ``threads`` threads; a backend that cannot be built
    here (pyfftw or numba not installed) raises NotImplementedError, which asv reports as
    a skipped benchmark."""
    import granframe as gf

    try:
        return gf.array_backend(name, threads=threads)
    except (ImportError, LookupError, ValueError) as exc:
        raise NotImplementedError(f"array backend {name!r} is not available: {exc}") from exc


def parse_config(text: str) -> tuple:
    """'D:N:N_RHO:M' -> (d, N, N_rho, M), integers."""
    dimension, n_modes, radial, sphere = (int(p) for p in text.split(":"))
    return dimension, n_modes, radial, sphere


def sphere_rule(dimension: int, points: int):
    """M points on S^{d-1}: the circle's trapezoid rule in 2D, in 3D the Gauss product rule
    of M = 2 n^2 points (32 points: n = 4), as ``granframe bench`` takes them."""
    import granframe as gf

    if dimension == 2:
        return gf.CircleTrapezoid(points)
    n_polar = round((points / 2) ** 0.5)
    if 2 * n_polar ** 2 != points:
        raise ValueError(f"sphere points {points} in 3D must be 2 n^2, e.g. 32")
    return gf.SphereProduct(n_polar)


def release() -> None:
    """Close what this process has built (operators' worker threads, stores' locks and
    staging directories) and forget it; the next ``setup`` builds anew."""
    for built in _BUILT.values():
        for item in built if isinstance(built, tuple) else (built,):
            for name in ("discard", "close"):
                method = getattr(item, name, None)
                if callable(method):
                    method()
                    break
    _BUILT.clear()
