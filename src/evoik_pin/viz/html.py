"""The static export: the scene (with its animation) as one self-contained HTML file, and reading one back."""

from __future__ import annotations

import base64
import os
import re
from pathlib import Path

from ..errors import ViewerError
from .server import _talks

__all__ = ["html_commands"]

_COMMAND_RE = re.compile(r'fetch\("data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"\)')


def html_commands(html: str) -> list[dict]:
    """The meshcat commands (dicts with ``type``, ``path`` and the payload) the static HTML ``html``
    (:meth:`Viewer.save_html`) replays, in order, decoded from its base64 msgpack blobs."""
    import umsgpack

    return [umsgpack.unpackb(base64.b64decode(m)) for m in _COMMAND_RE.findall(html)]


class HtmlExport:
    """The Viewer's export method."""

    @_talks
    def save_html(self, path: str | os.PathLike) -> Path:
        """Write the scene (with its animation) as one self-contained HTML file (no server needed); return its path."""
        html = self._check_open().static_html()
        html = html.replace("<title>MeshCat</title>", f"<title>evoik_pin: {self.robot.name}</title>", 1)
        out = Path(path).expanduser()
        try:
            out.write_text(html, encoding="utf-8")
        except OSError as exc:
            raise ViewerError(f"cannot write the HTML scene to {str(out)!r}: {exc.strerror or exc}") from exc
        return out
