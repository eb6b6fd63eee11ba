"""Reproduce paper 002's experiments (thin wrapper over `evoik reproduce 002`).

Usage: python scripts/reproduce_002.py [--quick] [--seed S] [--out DIR] [--no-progress] [--html PATH] [--view]
Writes DIR/002/report.md, results.json, one CSV per table and the figures (PNG); see docs/REPRODUCTION.md.
"""

import sys

from evoik_pin.cli import main

if __name__ == "__main__":
    sys.exit(main(["reproduce", "002", *sys.argv[1:]]))
