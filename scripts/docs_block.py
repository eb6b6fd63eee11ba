"""A benchmark script's own section of docs/BENCHMARKS.md: the text between its two markers, replaced on each run."""

from __future__ import annotations

from pathlib import Path


def write_block(docs: Path, begin: str, end: str, text: str, heading: str | None = None) -> None:
    """Put ``text`` between the markers ``begin`` and ``end`` of ``docs``: in place of what stood there, or appended
    under ``heading`` (a Markdown heading line, or None) when the markers are not there yet. The file is made when
    missing."""
    block = f"{begin}\n{text.rstrip(chr(10))}\n{end}"
    doc = docs.read_text(encoding="utf-8") if docs.exists() else "# Benchmarks\n"
    if begin in doc and end in doc:
        doc = doc[: doc.index(begin)] + block + doc[doc.index(end) + len(end):]
    else:
        doc = doc.rstrip("\n") + "\n\n" + (f"{heading}\n\n" if heading else "") + block + "\n"
    docs.parent.mkdir(parents=True, exist_ok=True)
    docs.write_text(doc, encoding="utf-8")
