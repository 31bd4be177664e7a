"""Small pieces shared by the studies (``studies/*.py``): their command line and how it
ends, their output folder, CSV tables, figures and ``summary.json``, and a time step at the
transport's CFL limit. A study imports granframe and this module, never another study."""

from __future__ import annotations

import argparse
import csv
import json
import math
import pathlib
import sys
from typing import Callable

import matplotlib
import numpy

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from granframe.space.transport import step_limit  # noqa: E402
from granframe.velocity.grid import VelocityGrid  # noqa: E402


def number(low: float, high: float = math.inf, low_open: bool = True, kind=float):
    """An argparse type: a finite number of ``kind`` in (low, high] (``low_open``) or
    [low, high]; anything else is refused with the value and the range allowed."""
    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and (value > low if low_open else value >= low)
                and value <= high):
            shown = f"({low:g}, " if low_open else f"[{low:g}, "
            raise argparse.ArgumentTypeError(
                f"{text!r} is not allowed: must be {'an integer' if kind is int else 'a number'}"
                f" in {shown}{high:g}]")
        return value
    return parse


def numbers(low: float, low_open: bool = True, kind=float):
    """An argparse type: comma-separated numbers, each as :func:`number` allows."""
    one = number(low, low_open=low_open, kind=kind)

    def parse(text: str) -> list:
        return [one(part) for part in text.split(",")]
    return parse


def name_list(allowed):
    """An argparse type: comma-separated names, each one of ``allowed``."""
    def parse(text: str) -> list[str]:
        chosen = [part for part in text.split(",") if part]
        unknown = [part for part in chosen if part not in allowed]
        if unknown:
            raise argparse.ArgumentTypeError(
                f"{', '.join(map(repr, unknown))} not allowed: choose from {', '.join(allowed)}")
        return chosen
    return parse


def study_arguments(doc: str, n_modes: int, cells: int, final: float | None,
                    quick: dict | None = None):
    """The options the granular studies share (``--final`` only where ``final`` is not
    None), each with its default in ``--help``; a value outside what the study can run is
    refused by argparse, by name. ``quick``: option -> value of the study's ``--quick``
    run (a small version to try it; an option given explicitly still wins, see
    :func:`parse_study`). ``--progress`` shows a progress bar (default: on a terminal)."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0].replace("\n", " "),
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--out", required=True, help="folder for the stores, tables, figure")
    parser.add_argument("--restitution", type=number(0.0, 1.0), default=0.9,
                        help="the restitution coefficient e")
    parser.add_argument("--n-modes", type=number(4, kind=int, low_open=False),
                        default=n_modes, help="velocity grid modes N per axis")
    parser.add_argument("--support", type=number(0.0), default=3.5,
                        help="velocity grid support radius S")
    parser.add_argument("--cells", type=number(1, kind=int, low_open=False), default=cells,
                        help="space cells")
    if final is not None:
        parser.add_argument("--final", type=number(0.0), default=final, help="final time")
    parser.add_argument("--quadrature", choices=("auto", "review"), default="auto",
                        help="the fast operator's rules (review: a quarter of the cost at "
                             "N = 24 in 3D, but Q differs from the default rules' by 3.7 %% "
                             "of max |Q| there)")
    parser.add_argument("--figure", nargs="+", metavar="STORE",
                        help="draw these runs into a figure in OUT and stop")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="a progress bar per run (default: on a terminal only)")
    return quick_option(parser, quick)


def quick_option(parser, quick: dict | None):
    """Add ``--quick`` to ``parser``: option -> value of the study's small version, shown in
    its help and applied by :func:`parse_study` where the option is not given explicitly."""
    quick = dict(quick or {})
    shown = ", ".join(f"--{key.replace('_', '-')} "
                      f"{format(value, 'g') if isinstance(value, float) else value}"
                      for key, value in quick.items())
    parser.add_argument("--quick", action="store_true",
                        help=f"a small version to try the study ({shown or 'as given'}); "
                             "options given explicitly still win")
    parser.set_defaults(quick_settings=quick)
    return parser


def parse_study(parser, argv=None):
    """Parse a study's command line; with ``--quick`` the quick settings replace the
    defaults (not the options given explicitly)."""
    args = parser.parse_args(argv)
    if args.quick and args.quick_settings:
        parser.set_defaults(**args.quick_settings)
        args = parser.parse_args(argv)
    return args


def run_study(simulation, store, args, **mode):
    """Run one of a study's runs as ``granframe run`` does: its title and estimated cost
    first, a progress bar (``args.progress``), then the line saying where it finished,
    its warnings and its one-line verdict. Returns the :class:`RunResult`; a run stopped by
    a health check raises :class:`~granframe.run.runner.HealthError` as ``run`` does."""
    from granframe.run.problems import run_cost
    from granframe.tools.cli_run import verdict

    print(f"[{pathlib.Path(store).name}] {simulation.description.title}", flush=True)
    print(run_cost(simulation.problem).text(), flush=True)
    result = simulation.run(store, progress=args.progress, **mode)
    print(f"{store}: finished, {result.steps} steps to t = {result.time:g} in "
          f"{result.wall_seconds:.1f} s")
    for warning in (*result.warnings, *result.accuracy_warnings):
        print(f"warning: {warning}", file=sys.stderr)
    print(verdict(result), flush=True)
    return result


def run_to_stop(simulation, store, args) -> list[str]:
    """:func:`run_study` of a run that may stop itself on a health check (overwriting
    ``store``): the warnings of its result, or the stop as one warning (the store keeps
    every step up to it)."""
    from granframe.run.runner import HealthError

    try:
        result = run_study(simulation, store, args, overwrite=True)
    except HealthError as stop:
        return [f"stopped: {stop}"]
    return [str(w) for w in result.warnings + result.accuracy_warnings]


def print_table(rows: list[dict], columns: dict) -> None:
    """The rows as an aligned text table of ``columns`` (key -> format spec, e.g. ".4g");
    the full rows go to the study's JSON file."""
    head = list(columns)
    cells = [[format(row.get(key, float("nan")), spec) if isinstance(row.get(key), (int, float))
              else str(row.get(key, "")) for key, spec in columns.items()] for row in rows]
    widths = [max([len(h)] + [len(c[k]) for c in cells]) for k, h in enumerate(head)]
    print("  ".join(h.rjust(w) for h, w in zip(head, widths)))
    for c in cells:
        print("  ".join(v.rjust(w) for v, w in zip(c, widths)))


def draw(figure: Callable, stores, path) -> None:
    """Draw the study's figure of ``stores`` into ``path`` and say where, and in how long."""
    import time

    began = time.perf_counter()
    figure(stores, path)
    print(f"figure: {path} ({time.perf_counter() - began:.1f} s)")


def output_folder(args, draw, name: str):
    """OUT (``args.out``), created; with ``--figure`` the stores drawn by ``draw`` into
    OUT/``name`` instead, and None (nothing to run)."""
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.figure:
        draw(args.figure, out / name)
        return None
    return out


def cfl_time_step(cells: int, final: float, grid: dict, cfl: float = 0.5,
                  length: float = 1.0, fraction: float = 1.0) -> float:
    """The largest dt <= ``fraction`` x the transport's CFL limit
    (:func:`granframe.space.transport.step_limit`, 2 cfl dx / (L - h) with dx =
    length / cells) that divides ``final`` a whole number of times. ``grid``: the
    velocity grid's table (``n_modes``, ``support_radius``; L and h do not depend on its
    ``dimension``, 2 where it has none)."""
    velocity = VelocityGrid(**{"dimension": 2, **grid})
    limit = fraction * step_limit(velocity, length / cells, cfl)
    return final / math.ceil(final / limit * (1 - 1e-12))


def relaxation_fit(times, values, starts, rate_guess: float, bounds,
                   accepted=(0.0, math.inf)) -> dict | None:
    """The steady value of a quantity that still relaxes when a run ends: v(t) = a +
    b exp(-k (t - t_0)) fitted by least squares (scipy.optimize.curve_fit, started at
    (v_last, v_first - v_last, ``rate_guess``) within ``bounds`` on (a, b, k)) over the
    values at t >= each of ``starts`` (t_0 the first time kept). Returns ``steady`` = a of
    the first fit, ``spread`` = |a_1 - a_2| of the first two (the extrapolation's
    uncertainty) and ``rate`` = k of the first; None where a fit fails or a fitted rate
    lies outside ``accepted`` (no relaxation the run has followed)."""
    import numpy
    import scipy.optimize

    fits = []
    for start in starts:
        keep = times >= start
        t, v = times[keep], values[keep]
        try:
            (a, _, rate), _ = scipy.optimize.curve_fit(
                lambda s, a, b, k: a + b * numpy.exp(-k * (s - t[0])), t, v,
                p0=(v[-1], v[0] - v[-1], rate_guess), bounds=bounds)
        except (RuntimeError, ValueError):
            return None
        if not accepted[0] <= rate <= accepted[1]:
            return None
        fits.append((float(a), float(rate)))
    return {"steady": fits[0][0], "spread": abs(fits[0][0] - fits[1][0]), "rate": fits[0][1]}


def mean_distances(a: dict, b: dict) -> dict:
    """The mean over the cells of |a - b| for every field of ``a`` (on a uniform mesh of unit
    length, the L1 distance sum_i dx |a_i - b_i|)."""
    return {name: float(numpy.abs(numpy.asarray(a[name]) - b[name]).mean()) for name in a}


def refinement_row(runs: dict, cells: int, fine: dict, coarse: dict, average) -> dict:
    """The errors of the run on ``cells`` among ``runs`` (cells -> fields, the coarser runs
    in it already) against a reference on two meshes:

    - ``L1_<field>``: :func:`mean_distances` from ``fine`` averaged onto its cells;
    - ``reference_bar_<field>``: that of ``coarse`` from ``fine``, both averaged onto its
      cells (the reference's own error, the bar of the first);
    - ``change_<field>``: with a coarser run in ``runs``, the distance of the next coarser
      one from this run averaged onto its cells (the refinement's change).

    ``average(fields, cells)`` averages fields onto ``cells`` (a conservative block
    average)."""
    truth = average(fine, cells)
    row = {**{f"L1_{k}": v for k, v in mean_distances(runs[cells], truth).items()},
           **{f"reference_bar_{k}": v
              for k, v in mean_distances(average(coarse, cells), truth).items()}}
    coarser = [c for c in runs if c < cells]
    if coarser:
        previous = max(coarser)
        change = mean_distances(runs[previous], average(runs[cells], previous))
        row.update({f"change_{k}": v for k, v in change.items()})
    return row


def write_csv(path, rows: list[dict], fields=None) -> None:
    """Rows of dicts as a CSV table with a header (``fields``: the columns and their order)."""
    with open(path, "w", newline="") as stream:
        writer = csv.DictWriter(stream, list(fields or rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def json_text(data, indent=None) -> str:
    """``data`` as strict JSON (RFC 8259): a NaN or an infinity, a quantity a run could
    not measure, is written as ``null``. Python's own ``json`` writes ``NaN``, which
    strict readers (JavaScript, ``jq``, most other languages' parsers) refuse."""
    def finite(value):
        if isinstance(value, dict):
            return {key: finite(item) for key, item in value.items()}
        if isinstance(value, (list, tuple)):
            return [finite(item) for item in value]
        if isinstance(value, float) and not math.isfinite(value):
            return None
        return value
    return json.dumps(finite(data), indent=indent, allow_nan=False)


def save_figure(fig, path, dpi: int = 100) -> None:
    """Write ``fig`` as a PNG at ``dpi`` and release it."""
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def read_summary(out, only) -> dict:
    """The summary to update: the existing ``out/summary.json`` when only some parts are
    measured again (``only``), so that the others keep their entries; else empty."""
    path = pathlib.Path(out) / "summary.json"
    return json.loads(path.read_text()) if only and path.exists() else {}


def write_summary(out, summary: dict) -> None:
    """``out/summary.json``, indented."""
    (pathlib.Path(out) / "summary.json").write_text(json_text(summary, indent=1))


def command(run: Callable, doc: str, quick_help: str, parts: str | None = None,
            show: Callable | None = None) -> Callable:
    """The ``main(argv)`` of a study: ``--out DIR``, ``--quick`` and, when the study has
    named ``parts``, ``--only a,b``; it calls ``run(out, quick[, only])`` and, when given,
    ``show(summary)`` to print the numbers."""

    def main(argv=None) -> int:
        parser = argparse.ArgumentParser(description=doc.splitlines()[0])
        parser.add_argument("--out", type=pathlib.Path, required=True)
        parser.add_argument("--quick", action="store_true", help=quick_help)
        if parts:
            parser.add_argument("--only", default=None, help=f"comma-separated {parts} names")
        args = parser.parse_args(argv)
        if parts:
            summary = run(args.out, args.quick,
                          set(args.only.split(",")) if args.only else None)
        else:
            summary = run(args.out, args.quick)
        if show is not None:
            show(summary)
        return 0

    return main


def finish(main: Callable, argv=None) -> int:
    """Run a study's ``main(argv)`` as a command: what granframe refuses (a
    :class:`ValueError` or :class:`TypeError` naming the parameter, the value and what is
    allowed) is printed as ``PROG: error: MESSAGE`` with status 2, a run stopped by its
    health checks as ``PROG: run stopped: MESSAGE`` with status 3 (its store keeps every
    snapshot before the stop), neither with a traceback; ``main``'s own status otherwise."""
    from granframe.run.runner import HealthError

    prog = pathlib.Path(sys.argv[0]).name
    try:
        return main(argv) or 0
    except HealthError as stop:
        print(f"{prog}: run stopped: {stop}", file=sys.stderr)
        return 3
    except (ValueError, TypeError) as refused:
        print(f"{prog}: error: {refused}", file=sys.stderr)
        return 2
