"""Command-line interface: ``granframe <command>``.

This module parses the command line (:func:`build_parser`) and runs the command
(:func:`main`, :func:`entry`). The commands are implemented by concern in
:mod:`granframe.tools.cli_run` (run, sweep), :mod:`granframe.tools.cli_inspect`
(plugins, info, check, plot) and :mod:`granframe.tools.cli_plan` (limits, advise,
bench), over :mod:`granframe.tools.cli_inputs` (what they read).

Commands
--------
plugins [--json] [[FAMILY] NAME]
    List every registered implementation per family with its source and a
    one-line description; with NAME, show one implementation (its family, description,
    parameters with their types and defaults, docstring summary). The JSON forms are
    documented in docs/plugins.md.
bench [--json] [--backend NAME] [--threads T] [--repeats R] [--precision P]
      [--config D:N[:N_RHO:M] ...] [--batch B ...]
    Time the fast operator against the FFT floor (docs/benchmarks.md); with --batch, on
    stacks of B distributions, per distribution.
run SOURCE --out STORE [--resume [--rollback]] [--overwrite] [--quick] [--only NAMES]
    [--progress] [--set KEY=VALUE ...]
    Run a description (a TOML file or a study module under studies/) into a zarr store;
    a study with several runs writes STORE/<name>.zarr each, then its report (from the
    runs that have ended, so also after --only). --set overrides a key of the description.
    Exit status 3 when a health check stopped the run, 130 when interrupted.
plot STORE --out DIR [--format png|pdf|svg] [--dpi DPI]
    Draw the figures of a run (PNG unless --format says otherwise).
info STORE [--json]
    Say what is in a store (--json: a run store's content as a JSON document).
check STORE
    Read every committed chunk of a run (or sweep) store and list the missing or damaged
    ones; exit status 3 when there is any.
sweep SWEEP.toml --out STORE [--scheduler ADDRESS] [--workers N] [--overwrite]
      [--retry-failed] [--progress] [--processes P]
    Run every point of a parameter sweep on Dask into one zarr store (docs/scaling.md);
    running it again skips ended runs and resumes cut ones. Exit status 3 when a run failed.
refine DESCRIPTION.toml --vary KEY=V1,V2,... [--vary ...] --quantity SPEC [...] --out DIR
       [--workers N] [--formal-order P] [--overwrite] [--progress]
    Run a description refined together along its velocity grid, cells or time step (one
    store each, on Dask) and report each quantity's observed order, Richardson estimate
    and grid convergence index with a figure (docs/runner.md, "Error bars from
    refinement"). Exit status 3 when a member did not finish.
advise SCENE.toml [--out DESCRIPTION.toml] [--json]
    Propose the cheapest configuration predicted to meet the scene's tolerance
    (docs/advise.md); --out writes it as a run description for ``granframe run``. A scene
    with a [space] table, or a space run description, also gets the price of a hierarchy
    of collision models against the all-kinetic run.
limits SOURCE [--quick] [--set KEY=VALUE ...] [--json] [--no-cost]
    The explicit time-step limit of each run of a description, and the rates behind it,
    without building the operator; then the run's estimated cost (its operator built and
    one step timed; --no-cost leaves it out). Exit status 3 when a fixed time step is above
    a limit (the table is printed all the same).
"""

from __future__ import annotations

import argparse
import re
import sys

from granframe._version import __version__
from granframe.tools.cli_inspect import check_command, info_command, plot_command, plugins_command
from granframe.tools.cli_plan import advise_command, bench_command, limits_command
from granframe.tools.cli_run import processes, refine_command, run_command, sweep_command


def _dpi(text: str) -> float:
    """``--dpi``: a finite number within the plotting module's DPI_RANGE."""
    from granframe.tools.plotting import DPI_RANGE

    low, high = DPI_RANGE
    try:
        value = float(text)
    except ValueError:
        value = None
    if value is None or not low <= value <= high:
        raise argparse.ArgumentTypeError(f"must be a number from {low} to {high}, got {text!r}")
    return value


class Parser(argparse.ArgumentParser):
    """An :class:`argparse.ArgumentParser` that names the closest choice or option when
    one is mistyped (Python 3.11's argparse has no ``suggest_on_error``).

    Subcommands get parsers of the same class (``add_subparsers`` makes them so). Each
    parser refuses the arguments it does not know itself, instead of returning them from
    :meth:`parse_known_args`, so that the message comes with the subcommand's usage and
    names the closest of its options; an unknown option is reported before a missing
    required argument.
    """

    def parse_known_args(self, args=None, namespace=None):
        self._arguments = list(sys.argv[1:] if args is None else args)
        namespace, extras = super().parse_known_args(args, namespace)
        if extras:
            self.error(self._unrecognized(extras))
        return namespace, extras

    def error(self, message):
        from granframe.registry import did_you_mean

        choice = re.fullmatch(r"argument .*?: invalid choice: '(.*?)' \(choose from (.*)\)",
                              message)
        if choice:
            choices = [c.strip().strip("'") for c in choice.group(2).split(",")]
            message += did_you_mean(choice.group(1), choices)
        elif message.startswith("the following arguments are required"):
            unknown = [token for token in getattr(self, "_arguments", ())
                       if self._is_unknown_option(token)]
            if unknown:
                message = self._unrecognized(unknown)
        super().error(message)

    def _is_unknown_option(self, token: str) -> bool:
        if not token.startswith("-") or token in ("-", "--") or re.fullmatch(
                r"-\d+$|-\d*\.\d+", token):
            return False
        option = token.split("=", 1)[0]
        known = self._option_string_actions
        return option not in known and not (option.startswith("--") and any(
            name.startswith(option) for name in known))

    def _unrecognized(self, tokens) -> str:
        """``unrecognized arguments: ...``, with the closest option to each unknown one."""
        from granframe.registry import closest

        options = [name for name in self._option_string_actions if name.startswith("--")]
        hints = []
        for token in tokens:
            match = closest(token.split("=", 1)[0], options) if token.startswith("-") else None
            if match is not None:
                hints.append(f"'{match}'" if len(tokens) == 1 else f"'{match}' for '{token}'")
        return f"unrecognized arguments: {' '.join(tokens)}" + (
            f"; did you mean {', '.join(hints)}?" if hints else "")


#: What each command's ``--help`` says above its options (argparse's description) and,
#: below them, its examples (the epilog).
COMMAND_HELP = {
    "plugins": ("""\
List the registered implementations of every family (collision kernels, restitution laws,
quadratures, collision operators, time integrators, initial conditions, array backends)
with their source. With NAME (FAMILY NAME when the name is registered in several families,
or FAMILY alone for one family's list), show one implementation: its family, description,
source, docstring summary and parameters with their types and defaults.""",
                """\
  granframe plugins
  granframe plugins toscani
  granframe plugins collision_operators fast_spectral --json"""),
    "bench": ("""\
Time the fast spectral operator against the FFT floor, the time of the transforms it cannot
avoid (docs/benchmarks.md). --batch evaluates stacks of B distributions at once and reports
time and floor per distribution.""",
              """\
  granframe bench --config 2:64 --config 3:32 --repeats 5
  granframe bench --config 3:32 --quadrature auto review
  granframe bench --json --backend numpy --batch 1 8 64
  granframe bench --space 3:32:64 2:64:256"""),
    "run": ("""\
Run a description (a .toml file, or a study module defining description(quick) or
runs(quick)) into a zarr store. A study with several runs writes STORE/<name>.zarr for each,
then its report to STORE/report from the runs that have ended (also after --only). --set
overrides a key of the description (repeatable; the value is read as TOML). Before the
first step it prints the run's estimated cost: one step timed on this machine, times the
number of steps. Exit status 3 when a health check stopped a run, 130 when interrupted.""",
            """\
  granframe run studies/heated_maxwell.py --out runs/h.zarr
  granframe run studies/heated_maxwell.py --out runs/h.zarr --resume
  granframe run desc.toml --out runs/d.zarr --set grid.n_modes=64 --set kernel.name=vhs
  granframe run studies/review_test1.py --out runs/test1 --only a,b"""),
    "plot": ("""\
Draw the figures of a run store (temperature, relative entropy, slices and contours of f,
moments) into a folder; of a space run, x-t maps and profiles of its fields; of a run on a
rectangle, maps of rho, T, the speed with streamlines and the vorticity at every snapshot,
and with --animate an x-y animation of one of them.""",
             """\
  granframe plot runs/h.zarr --out figures/h
  granframe plot runs/box.zarr --out figures/box --animate vorticity"""),
    "info": ("""\
Say what is in a store. A run store: status, snapshots, moments, the resolution of the last
commit and its warnings, the accuracy monitors (their values, largest values, first excess
and warnings), provenance and the description; with --json, its metadata and
progress as stored and the range of its snapshots and moments, as one JSON document. A
sweep store: its axes, how many points finished, failed or are pending, its failures, the
runs that end under-resolved, and its base description.""",
             """\
  granframe info runs/h.zarr
  granframe info runs/h.zarr --json
  granframe info runs/sweep.zarr"""),
    "check": ("""\
Read every committed chunk of a run (or sweep) store and verify its checksum; list the
missing or damaged ones (exit status 3 when there is any).""",
              """\
  granframe check runs/h.zarr"""),
    "sweep": ("""\
Run every point of a parameter sweep (a base description and its axes) on Dask into one
zarr store (docs/scaling.md). Running it again skips ended runs and resumes cut ones; a
sweep of the same base with more axis values extends the store and runs only the new
points. Points refused for their parameters are not run again unless --retry-failed;
--overwrite replaces a sweep (or run) store, never anything else. Exit status 3 when a run
failed.""",
              """\
  granframe sweep sweep.toml --out runs/sweep.zarr --workers 2
  granframe sweep sweep.toml --out runs/sweep.zarr --retry-failed
  granframe sweep sweep.toml --out runs/sweep.zarr --overwrite"""),
    "refine": ("""\
Run a description refined together along its velocity grid (grid.n_modes), its cells
(space.cells) or its time step, coarse to fine and by the same ratio at every level, one
store per member in a sweep store OUT/family.zarr (on Dask; running it again resumes it),
and report each quantity's values, observed order, Richardson estimate and grid
convergence index of the finest member (Roache 1994; Celik et al. 2008) in
OUT/refinement.md, .json and a figure OUT/refinement.png (docs/runner.md, "Error bars from
refinement"). Exit status 3 when a member did not finish.""",
               """\
  granframe refine sod.toml --vary grid.n_modes=24,32,48 --quantity temperature@t=0.2,x=0.5 --out ref
  granframe refine sod.toml --vary space.cells=50,100,200 --vary time_step=0.004,0.002,0.001 --quantity density@t=0.2,x=0.6 --out ref"""),
    "advise": ("""\
Propose the cheapest configuration (grid, quadratures, time step) predicted to meet a
scene's tolerance on its temperature or distribution (docs/advise.md). A scene with a
[space] table (cells, walls), or a space run description, also gets the price of a
hierarchy of collision models chosen cell by cell against the all-kinetic run.""",
               """\
  granframe advise scene.toml
  granframe advise scene.toml --out desc.toml && granframe run desc.toml --out runs/a.zarr
  granframe advise space-run.toml"""),
    "limits": ("""\
Report the explicit time-step limit of each run of a description (a .toml file or a study
module) and the spectral radii behind it (heat bath, collisions, energy dissipation, and the
drift of a rescaled run), from the description alone: the operator is not built, so it
takes a fraction of a second where building it takes seconds to minutes. It is the limit
granframe run checks before the first step (docs/runner.md, docs/stability.md). A space
run's transport (CFL) limit comes first. Then the run's cost on this machine: its operator
is built and one step timed, times the number of steps (--no-cost leaves it out, and the
command takes a fraction of a second). Exit status 3 when the description's fixed time step
is above a limit; the table is printed all the same.""",
               """\
  granframe limits studies/heated_maxwell.py
  granframe limits studies/space.py --quick --no-cost
  granframe limits desc.toml --set time_step=0.05 --set grid.n_modes=64
  granframe limits desc.toml --json"""),
}


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``granframe``: a subcommand per command with its ``handler``, and
    the description and examples of :data:`COMMAND_HELP`."""
    parser = Parser(
        prog="granframe", formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Fourier spectral solvers for the inelastic Boltzmann equation.",
        epilog="examples:\n  granframe plugins\n  granframe run studies/heated_maxwell.py "
               "--out runs/h.zarr\n  granframe COMMAND --help")
    parser.add_argument("--version", action="version", version=f"granframe {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    plugins = commands.add_parser("plugins", help="list registered implementations per family")
    plugins.add_argument("names", nargs="*", metavar="[FAMILY] NAME",
                         help="show this implementation (or this family)")
    plugins.add_argument("--json", action="store_true", help="machine-readable output")
    plugins.set_defaults(handler=plugins_command)
    bench = commands.add_parser("bench", help="time the fast operator against the FFT floor")
    bench.add_argument("--json", action="store_true", help="machine-readable output")
    bench.add_argument("--backend", default=None, help="array backend (default: pyfftw if "
                       "installed, else numpy)")
    bench.add_argument("--threads", type=int, default=2, help="threads (default 2)")
    bench.add_argument("--repeats", type=int, default=7, help="timed evaluations (default 7)")
    bench.add_argument("--precision", default="float64", choices=["float64", "float32"],
                       help="arithmetic of the operator and of the floor (default float64)")
    bench.add_argument("--config", action="extend", nargs="+", metavar="D:N[:N_RHO:M]",
                       help="configurations (one or more, repeatable); default: the review's "
                            "five")
    bench.add_argument("--batch", action="extend", nargs="+", type=int, metavar="B",
                       help="stack sizes: evaluate B distributions at once and report the "
                            "time and FFT floor per distribution (e.g. --batch 1 8 64); "
                            "default: one distribution")
    bench.add_argument("--quadrature", action="extend", nargs="+", metavar="PRESET",
                       choices=["auto", "review"],
                       help="time each configuration D:N with the rules of these presets of "
                            "fast_spectral's quadrature option (e.g. --quadrature auto "
                            "review) instead of its N_RHO and M")
    bench.add_argument("--space", nargs="*", metavar="D:N:CELLS[:N_RHO:M]", default=None,
                       help="time one step of a space run and its parts instead (default "
                            "configurations: 3:32:64 and 2:64:256, the review's rules)")
    bench.set_defaults(handler=bench_command)
    run = commands.add_parser("run", help="run a description (TOML or study module) into a store")
    run.add_argument("source", metavar="STUDY_OR_TOML",
                     help="a .toml run description or a .py study defining description(quick)")
    run.add_argument("--out", required=True, metavar="STORE",
                     help="zarr store to write (a folder of stores for a study with several "
                          "runs, plus report/)")
    run.add_argument("--only", metavar="NAMES", help="comma-separated runs of a study to run")
    run.add_argument("--resume", action="store_true",
                     help="continue the run in STORE from its last complete snapshot")
    run.add_argument("--overwrite", action="store_true",
                     help="replace an existing granframe store STORE (nothing else)")
    run.add_argument("--rollback", action="store_true",
                     help="with --resume: continue a damaged store from its last intact "
                          "commit")
    run.add_argument("--quick", action="store_true",
                     help="the study's reduced variant (smaller grid or time)")
    run.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                     help="progress bar (default: only on a terminal)")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a key of the description (repeatable), e.g. "
                          "grid.n_modes=64; VALUE is read as TOML")
    run.add_argument("--partition", type=_partition, default=None, metavar="C1,C2,...",
                     help="under mpiexec: the cells of each process, in rank order, whole "
                          "chunks of space.block_cells (default: as even as the chunks "
                          "allow)")
    run.set_defaults(handler=run_command)
    plot = commands.add_parser("plot", help="draw the figures of a run store (PNG, PDF or SVG)")
    plot.add_argument("store", metavar="STORE")
    plot.add_argument("--out", required=True, metavar="DIR", help="folder for the figures")
    plot.add_argument("--format", default="png", choices=["png", "pdf", "svg"],
                      help="file format of the figures (default png)")
    plot.add_argument("--dpi", type=_dpi, default=110,
                      help="resolution of the raster parts in dots per inch, 10 to 600 "
                           "(default 110)")
    plot.add_argument("--animate", default=None, metavar="FIELD",
                      help="a run on a rectangle: also an x-y animation of FIELD (density, "
                           "temperature, speed or vorticity) over the snapshots, FIELD.gif")
    plot.set_defaults(handler=plot_command)
    info = commands.add_parser("info", help="say what is in a run or sweep store")
    info.add_argument("store", metavar="STORE")
    info.add_argument("--json", action="store_true",
                      help="a run store's content as a JSON document")
    info.set_defaults(handler=info_command)
    check = commands.add_parser("check", help="read every committed chunk of a store and "
                                "report missing or damaged ones (exit 3 if any)")
    check.add_argument("store", metavar="STORE")
    check.set_defaults(handler=check_command)
    sweep = commands.add_parser("sweep", help="run a parameter sweep on Dask into one store")
    sweep.add_argument("sweep", metavar="SWEEP.toml",
                       help="a base description ([base]) and axes ([product], [zip])")
    sweep.add_argument("--out", required=True, metavar="STORE", help="the sweep's zarr store")
    sweep.add_argument("--scheduler", metavar="ADDRESS",
                       help="an existing Dask scheduler (default: a LocalCluster here)")
    sweep.add_argument("--workers", type=int, default=None,
                       help="worker processes of the LocalCluster (default: one per core)")
    sweep.add_argument("--overwrite", action="store_true",
                       help="replace an existing granframe store STORE (nothing else)")
    sweep.add_argument("--retry-failed", action="store_true",
                       help="run again the points refused for their parameters and the runs "
                            "stopped by a health check (default: keep them failed)")
    sweep.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                       help="progress bar (default: only on a terminal)")
    sweep.add_argument("--processes", type=int, default=1,
                       help="MPI processes per run: each runs as mpiexec -n P granframe run "
                            "(default 1: in its worker's process)")
    sweep.set_defaults(handler=sweep_command)
    refine = commands.add_parser("refine", help="error bars from refinement: observed order, "
                                 "Richardson estimate, grid convergence index")
    refine.add_argument("description", metavar="DESCRIPTION.toml", help="a run description")
    refine.add_argument("--vary", action="append", required=True, metavar="KEY=V1,V2,...",
                        help="a parameter refined from coarse to fine: grid.n_modes, "
                             "space.cells or time_step; several are refined together, by "
                             "the same ratio")
    refine.add_argument("--quantity", action="append", required=True, metavar="SPEC",
                        help="NAME[.v1[.v2]][@t=T][,x=X|x=mean][,wall=left|right], e.g. "
                             "temperature@t=1,x=0.5 or wall_energy@wall=left")
    refine.add_argument("--out", required=True, metavar="DIR",
                        help="folder for the family's store, the table and the figure")
    refine.add_argument("--workers", type=int, default=None,
                        help="Dask worker processes (default: one per core)")
    refine.add_argument("--formal-order", type=float, default=None,
                        help="the scheme's order, for two members or where no order can be "
                             "observed")
    refine.add_argument("--overwrite", action="store_true",
                        help="replace an existing family store (nothing else)")
    refine.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="progress bar (default: only on a terminal)")
    refine.set_defaults(handler=refine_command)
    advise = commands.add_parser("advise", help="the cheapest configuration for a scene and "
                                 "tolerance")
    advise.add_argument("scene", metavar="SCENE.toml",
                        help="physics, quantity (temperature or distribution) and tolerance, "
                             "with a [space] table for a space scene; or a space run "
                             "description, to price a hierarchy")
    advise.add_argument("--out", metavar="DESCRIPTION.toml",
                        help="write the proposed run description")
    advise.add_argument("--json", action="store_true", help="machine-readable output")
    advise.set_defaults(handler=advise_command)
    limits = commands.add_parser("limits", help="the explicit time-step limit of a run "
                                 "and its estimated cost")
    limits.add_argument("source", metavar="STUDY_OR_TOML",
                        help="a .toml description or a study module (.py)")
    limits.add_argument("--quick", action="store_true",
                        help="the study's quick runs (study modules only)")
    limits.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a key of the description, as for run (repeatable)")
    limits.add_argument("--json", action="store_true", help="machine-readable output")
    limits.add_argument("--no-cost", action="store_true",
                        help="leave out the cost estimate (which builds the operator and "
                             "times one step)")
    limits.set_defaults(handler=limits_command)
    for name, command in commands.choices.items():
        command.description, examples = COMMAND_HELP[name]
        command.epilog = f"examples:\n{examples}"
        command.formatter_class = argparse.RawDescriptionHelpFormatter
    return parser


def _partition(text: str) -> list[int]:
    """--partition: whole numbers separated by commas."""
    try:
        counts = [int(part) for part in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a list of cell counts such as "
                                         "24,40") from None
    return counts


def main(argv: list[str] | None = None) -> int:
    """Run the command ``argv`` (the process's arguments when None); the exit status, 2
    for a refusal and 130 when interrupted."""
    args = build_parser().parse_args(argv)
    try:      # the imports made here are inside the handling of a Ctrl-C too
        size, rank = processes()
        if size > 1 and args.command != "run":
            if rank == 0:
                print(f"granframe: error: granframe {args.command} runs in one process; "
                      f"under mpiexec ({size} processes) only granframe run is spread over "
                      "them", file=sys.stderr)
            return 2
        if size > 1 and rank != 0:      # one voice: process 0's; the others speak on errors
            import os

            sys.stdout = open(os.devnull, "w")
            sys.stderr = open(os.devnull, "w")
        return args.handler(args)
    except BrokenPipeError:  # output piped into e.g. `head`, which stopped reading
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:   # Ctrl-C outside a run (start-up, a report, a sweep)
        print("\ngranframe: interrupted", file=sys.stderr)
        return 130
    except (ValueError, TypeError, OSError) as exc:
        print(f"granframe: error: {exc}", file=sys.stderr)
        return 2


def _importing(frame) -> bool:
    """Whether ``frame`` runs inside an import begun since :func:`entry` (a frame of
    importlib's bootstrap between it and ``entry``'s own frame)."""
    while frame is not None and frame.f_code is not entry.__code__:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


def _interrupt(signum, frame):
    """Ctrl-C as KeyboardInterrupt, but never during an import: raised in one of importlib's
    lock callbacks it would be printed as "Exception ignored" and lost (the run would go
    on), and raised in a module that a compiled extension imports while it initialises
    (NumPy's import of ``datetime``) it becomes that extension's ImportError, printed with
    a traceback. So while any import is under way it is sent again 10 ms later, once the
    import has returned."""
    if _importing(frame):
        import os
        import threading

        threading.Timer(0.01, os.kill, (os.getpid(), signum)).start()
        return
    raise KeyboardInterrupt


def entry() -> None:
    """The ``granframe`` command: :func:`main`'s status as the process's exit status.

    Ctrl-C is delivered outside the import machinery (:func:`_interrupt`). After it the
    process leaves with status 130 through ``os._exit`` (stdout and stderr flushed first;
    the run has already marked and released its store): CPython would otherwise end it by
    SIGINT whenever the KeyboardInterrupt passed through code run by ``PyRun_*``, such as
    the initialisation of a compiled module being imported, even though :func:`main`
    handled it. A Ctrl-C while the process exits after the command (the libraries'
    ``atexit`` callbacks: Dask, thread pools) ends it at once with the command's status,
    instead of an "Exception ignored in atexit callback" traceback.
    """
    import os
    import signal

    interruptible = signal.getsignal(signal.SIGINT) is signal.default_int_handler
    if interruptible:   # not ignored
        signal.signal(signal.SIGINT, _interrupt)
    code = main()

    def leave(signum=None, frame=None):
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):   # a closed pipe or stream
                pass
        os._exit(code)

    if code == 130:
        leave()
    if interruptible:
        signal.signal(signal.SIGINT, leave)
    sys.exit(code)


if __name__ == "__main__":
    entry()
