"""Viewer.block(message): the "Ctrl-C to stop" line is printed where Ctrl-C is already the clean stop.

Printed before ``block()`` was called, a Ctrl-C that came right after the line (a user quick on the keys, a script
that waits for the line and sends SIGINT: tests/test_docs.py) ended ``evoik view`` with a KeyboardInterrupt
traceback and exit status -2 (seen 1 of 1 run under load). No meshcat server is needed: a Viewer of an external
server (``_server is None``) blocks until Ctrl-C, and the Ctrl-C is raised by the stream the message is written to.
"""

import io

import pytest

from evoik_pin.viz import Viewer


class _CtrlCAfterWrite(io.StringIO):
    """A stream that records what is written, then raises KeyboardInterrupt as a Ctrl-C at that moment would."""

    def flush(self):
        raise KeyboardInterrupt


def _bare_viewer() -> Viewer:
    viewer = Viewer.__new__(Viewer)  # no server, no connection: block() waits for Ctrl-C, close() has nothing to do
    viewer.vis, viewer._server = None, None
    return viewer


def test_ctrl_c_right_after_the_message_is_the_clean_stop():
    out = _CtrlCAfterWrite()
    _bare_viewer().block("Press Ctrl-C to stop the viewer.", file=out)  # returns: no KeyboardInterrupt escapes
    assert out.getvalue() == "Press Ctrl-C to stop the viewer.\n"


def test_block_without_a_message_prints_nothing(capsys, monkeypatch):
    def ctrl_c(_seconds):
        raise KeyboardInterrupt

    monkeypatch.setattr("evoik_pin.viz.time.sleep", ctrl_c)
    _bare_viewer().block()
    assert capsys.readouterr() == ("", "")


def test_the_message_goes_to_stdout_by_default(capsys, monkeypatch):
    def ctrl_c(_seconds):
        raise KeyboardInterrupt

    monkeypatch.setattr("evoik_pin.viz.time.sleep", ctrl_c)
    _bare_viewer().block("serving")
    assert capsys.readouterr().out == "serving\n"


def test_a_message_that_is_not_text_is_refused():
    from evoik_pin.errors import OptionError

    with pytest.raises(OptionError, match="message"):
        _bare_viewer().block(3)
