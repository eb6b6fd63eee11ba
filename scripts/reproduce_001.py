"""Reproduce paper 001's experiments (thin wrapper over `evoik reproduce 001`).

Usage: python scripts/reproduce_001.py [--quick] [--seed S] [--out DIR] [--no-progress]
Writes DIR/001/report.md, results.json, one CSV per table and the figures (PNG); see docs/REPRODUCTION.md.
"""

import sys

from evoik_pin.cli import main

if __name__ == "__main__":
    sys.exit(main(["reproduce", "001", *sys.argv[1:]]))
