"""Write the papers' arms to robots/<name>.urdf from their DH tables (src/evoik_pin/papers/robots.py).

Usage: python scripts/make_paper_robots.py [--check]
  --check  exit 1 (and write nothing) when a committed file differs from the generator's output.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from evoik_pin.papers.robots import PAPER_ROBOTS

ROBOTS_DIR = Path(__file__).resolve().parents[1] / "robots"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare instead of writing")
    args = parser.parse_args(argv)
    stale = []
    for name, build in PAPER_ROBOTS.items():
        path = ROBOTS_DIR / f"{name}.urdf"
        text = build()
        if args.check:
            if not path.is_file() or path.read_text() != text:
                stale.append(name)
            continue
        path.write_text(text)
        print(f"wrote {path}")
    if stale:
        print(f"out of date: {', '.join(stale)} (run python scripts/make_paper_robots.py)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
