"""Small pieces shared by measurement studies (``studies/*.py`` that sweep settings in one
process instead of writing run stores): their command line and their CSV tables."""

from __future__ import annotations

import argparse
import csv
import pathlib
from typing import Callable


def write_csv(path, rows: list[dict], fields=None) -> None:
    """Rows of dicts as a CSV table with a header (``fields``: the columns and their order)."""
    with open(path, "w", newline="") as stream:
        writer = csv.DictWriter(stream, list(fields or rows[0]))
        writer.writeheader()
        writer.writerows(rows)


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
