"""Newton-iteration cost of the DER core for 1e2..1e5 vertices (see tightknot.benchmarks.der).

Usage: python bench/der_scaling.py [--json FILE] (same as ``tightknot bench der``).
"""

import sys

from tightknot.app.cli import main

if __name__ == "__main__":
    sys.exit(main(["bench", "der", *sys.argv[1:]]))
