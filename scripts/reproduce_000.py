"""Reproduce paper 000's experiments (thin wrapper over `evoik reproduce 000`).

Usage: python scripts/reproduce_000.py [--quick] [--seed S] [--out DIR] [--no-progress]
Writes DIR/000/report.md, results.json, one CSV per table and the figures (PNG); see docs/REPRODUCTION.md.
"""

import sys

from evoik_pin.cli import main

if __name__ == "__main__":
    sys.exit(main(["reproduce", "000", *sys.argv[1:]]))
