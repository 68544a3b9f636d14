"""``tightknot bench NAME``: one sub-subcommand per benchmark module.

Each module ``tightknot.benchmarks.<name>`` listed in :data:`BENCHMARKS` defines
``register(subparsers)``, which adds its own parser (with ``--json FILE``) and sets
``handler``. Benchmarks print their numbers and write JSON; speed targets are checked
there, never in timed tests (ratios measured within one run, the machines are shared).
"""

from __future__ import annotations

import argparse
import importlib
from typing import Any

#: Benchmark modules, in the order ``tightknot bench --help`` lists them.
BENCHMARKS = ("der", "contact", "knots", "sweep", "batch", "tradeoff", "scaling", "peers",
              "force_range", "tangles")

_EXAMPLES = """examples:
  tightknot bench der --json der.json
  tightknot bench der --sizes 100 1000 --no-startup
  tightknot bench NAME --help
"""


def _available() -> list[Any]:
    """The benchmark modules present in this version (a module exists once it is written)."""
    mods = []
    for name in BENCHMARKS:
        try:
            mods.append(importlib.import_module(f"tightknot.benchmarks.{name}"))
        except ModuleNotFoundError as err:
            if err.name != f"tightknot.benchmarks.{name}":
                raise
    return [m for m in mods if hasattr(m, "register")]


def register(subparsers: Any) -> None:
    """Add ``bench`` and one parser per available benchmark."""
    p = subparsers.add_parser(
        "bench", help="benchmarks: print numbers and write --json FILE",
        description="Benchmarks. Each prints its measurements and writes them as JSON.",
        epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="which", metavar="NAME", parser_class=type(p))
    sub.required = True
    for mod in _available():
        mod.register(sub)
