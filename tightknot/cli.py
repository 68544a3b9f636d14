"""Command-line interface (placeholder until subcommands land)."""

import sys


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``tightknot`` console script."""
    print("tightknot: no subcommands yet", file=sys.stderr)
    return 2
