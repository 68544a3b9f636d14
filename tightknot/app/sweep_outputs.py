"""``tightknot table`` and ``tightknot plot``: a sweep store's flat table and its figures.

The table is :func:`tightknot.sweep.table.write_table`'s (csv, or parquet with the tables
extra), the figures :func:`tightknot.viz.sweep_figures.plot_tightness_sweep`'s. Exit
codes: 0 written, 2 bad input (no such store, an output that exists without --overwrite,
a store with no open-knot levels to plot).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

EXIT_OK = 0


def register(subparsers: Any) -> None:
    """Add ``tightknot table`` and ``tightknot plot`` to an argparse ``subparsers``."""
    _register_table(subparsers)
    _register_plot(subparsers)


_TABLE_EXAMPLES = """examples:
  tightknot table runs/sweep185 --out sweep185.csv
  tightknot table runs/f --out f.parquet          # needs pip install "tightknot[tables]"

one row per case and level: case_id, status, knot, level_kind, level_index, level_target,
reached, level_failure, every parameter of the case (defaults included), then the
measurements (pull_force_N, lambda_oc, end_to_end_m [m], stretch, L_over_D, min_gap_over_D0,
min_area_ratio, ...). In Python: tightknot.sweep.to_dataframe("runs/f").
"""

_PLOT_EXAMPLES = """examples:
  tightknot plot runs/f                        # writes runs/f/figures/
  tightknot plot runs/f --out figs/

figures: force_lambda_oc.png (pulling force against Lambda_OC), force_extension.png (force
against end-to-end distance), stretch_area_vs_force.png (stretch and min A/A0 against
force); a missed level is a cross at its last good state.
"""


def _register_table(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "table", help="a sweep store as one flat table (csv or parquet)",
        description="Write a sweep store as one table: a row per case and tightness level, "
        "every case parameter a column (defaults included), then the level's measurements.",
        epilog=_TABLE_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("store", metavar="STORE", help="the sweep's --out folder")
    p.add_argument("--out", required=True, metavar="FILE",
                   help="the table: FILE.csv, or FILE.parquet (the tables extra)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing FILE")
    p.add_argument("--quiet", action="store_true", help="print nothing but errors")
    p.set_defaults(handler=run_table)


def _register_plot(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "plot", help="the plots of a tightness sweep (force, Lambda_OC, extension, A/A0)",
        description="Draw a tightness sweep's store: pulling force against Lambda_OC and "
        "against end-to-end distance, stretch and min A/A0 against force (one line per case).",
        epilog=_PLOT_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("store", metavar="STORE", help="the sweep's --out folder")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="figures folder (default STORE/figures; its parent must exist)")
    p.add_argument("--overwrite", action="store_true", help="replace existing figures")
    p.add_argument("--quiet", action="store_true", help="print nothing but errors")
    p.set_defaults(handler=run_plot)


def _open_store(folder: str):  # noqa: ANN202 (Store)
    from tightknot.sweep.store import Store

    if not Path(folder).is_dir():
        raise ValueError(f"STORE {folder}: no such folder (a sweep's --out)")
    return Store.open(folder, create=False)


def run_table(args: argparse.Namespace) -> int:
    """Handler of ``tightknot table``: 0 written, 2 bad input."""
    from tightknot.app.run_folder import check_output_file, refuse_existing
    from tightknot.sweep.table import FORMATS, write_table

    out = Path(args.out)
    if out.suffix not in FORMATS:
        raise ValueError(f"--out {out}: the file name must end in {' or '.join(FORMATS)}")
    check_output_file(out, "--out")
    if not args.overwrite:
        refuse_existing([out], "--overwrite")
    n = write_table(_open_store(args.store), out)
    if not args.quiet:
        print(f"wrote {out} ({n} rows)")
    return EXIT_OK


def run_plot(args: argparse.Namespace) -> int:
    """Handler of ``tightknot plot``: 0 written, 2 bad input (no open-knot levels)."""
    from tightknot.app.run_folder import check_output_dir, refuse_existing
    from tightknot.sweep.table import param_columns, table_rows
    from tightknot.viz.sweep_figures import FIGURES, plot_tightness_sweep

    store = _open_store(args.store)
    folder = Path(args.out) if args.out is not None else store.folder / "figures"
    check_output_dir(folder, "--out")
    if not args.overwrite:
        refuse_existing([folder / name for name in FIGURES], "--overwrite")
    rows = table_rows(store)
    paths = plot_tightness_sweep(rows, param_columns(rows), folder)
    if not args.quiet:
        print(f"wrote {folder}/ ({', '.join(p.name for p in paths)})")
    return EXIT_OK
