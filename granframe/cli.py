"""Command-line interface: ``granframe <command>``.

Commands
--------
plugins [--json]
    List every registered implementation per family with its source and a
    one-line description. The JSON form is documented in docs/plugins.md.
"""

from __future__ import annotations

import argparse
import json
import sys

from granframe._version import __version__
from granframe.registry import FAMILIES, default_registries


def _plugins(args) -> int:
    registries = default_registries()
    if args.json:
        json.dump(registries.to_json(), sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0
    for family in FAMILIES:
        entries = registries.entries(family)
        print(f"{family} ({len(entries)})")
        if not entries:
            print("    (none registered)")
        width = max((len(e.name) for e in entries), default=0)
        for e in entries:
            print(f"    {e.name:<{width}}  {e.description}  [{e.source}]")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="granframe",
        description="Fourier spectral solvers for the inelastic Boltzmann equation.")
    parser.add_argument("--version", action="version", version=f"granframe {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    plugins = commands.add_parser("plugins", help="list registered implementations per family")
    plugins.add_argument("--json", action="store_true", help="machine-readable output")
    plugins.set_defaults(handler=_plugins)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.handler(args)
    except (ValueError, TypeError) as exc:
        print(f"granframe: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into e.g. `head`, which stopped reading
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())
