"""Reproduce paper 003's experiments (thin wrapper over `evoik reproduce 003`).

Usage: python scripts/reproduce_003.py [--quick] [--seed S] [--out DIR] [--no-progress] [--html PATH] [--view]
Writes DIR/003/report.md, results.json, one CSV per table and the figures (PNG); see docs/REPRODUCTION.md.
"""

import sys

from evoik_pin.cli import main

if __name__ == "__main__":
    sys.exit(main(["reproduce", "003", *sys.argv[1:]]))
