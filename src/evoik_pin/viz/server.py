"""The meshcat server a Viewer draws into: its own subprocess (bound to 127.0.0.1, exiting with its parent) or an
external one (probed first: a silent one is a ViewerError, not a hang)."""

from __future__ import annotations

import functools
import os
import subprocess
import sys
import tempfile
import time
import warnings
import weakref
from pathlib import Path

from ..errors import ViewerError

#: Seconds between two looks at whether a Viewer's own server still runs.
_LIVENESS_POLL = 0.25

# meshcat's own server, its HTTP socket bound to 127.0.0.1 (meshcat binds every interface), exiting with its parent.
_SERVER_SCRIPT = r"""
import os, sys, threading, time
parent = int(sys.argv[1])
def _watch():
    while os.getppid() == parent:
        time.sleep(0.5)
    os._exit(0)
threading.Thread(target=_watch, daemon=True).start()
import tornado.web
from meshcat.servers import zmqserver
_listen = tornado.web.Application.listen
def _listen_local(self, port, address=None, **kwargs):
    return _listen(self, port, address="127.0.0.1", **kwargs)
tornado.web.Application.listen = _listen_local
sys.argv = ["meshcat-server"] + sys.argv[2:]
zmqserver.main()
"""


def _printed(f) -> str:
    """What a subprocess has written so far to file ``f``, read without moving the shared offset."""
    fd = f.fileno()
    return os.pread(fd, os.fstat(fd).st_size, 0).decode(errors="replace")


def _stop_process(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=3)
        except subprocess.TimeoutExpired:  # pragma: no cover - meshcat exits on SIGTERM
            proc.kill()
            proc.wait()


class _Server:
    """A meshcat server subprocess on 127.0.0.1, waited for ``timeout`` s to print its URLs; ``stop()`` ends it."""

    def __init__(self, timeout: float):
        import meshcat

        self._out, self._err = tempfile.TemporaryFile(), tempfile.TemporaryFile()  # a full pipe would block it
        env = dict(os.environ)
        site = str(Path(meshcat.__file__).resolve().parents[1])
        env["PYTHONPATH"] = os.pathsep.join([site, *filter(None, [env.get("PYTHONPATH")])])
        self.proc = subprocess.Popen([sys.executable, "-u", "-c", _SERVER_SCRIPT, str(os.getpid())],
                                     stdin=subprocess.DEVNULL, stdout=self._out, stderr=self._err, env=env)
        self._finalizer = weakref.finalize(self, _stop_process, self.proc)
        deadline, urls = time.monotonic() + timeout, {}
        while True:
            for line in _printed(self._out).splitlines():
                key, _, value = line.strip().partition("=")
                if key in ("zmq_url", "web_url") and value:
                    urls[key] = value
            if len(urls) == 2:
                break
            exited = self.proc.poll() is not None
            if exited or time.monotonic() > deadline:
                printed = _printed(self._out).strip().splitlines()[-2:]
                detail = _printed(self._err).strip().splitlines()[-3:]
                self.stop()
                why = (f"exited (code {self.proc.returncode})" if exited
                       else f"ran {timeout:g} s without printing both of its URLs")
                raise ViewerError(f"the meshcat server {why}: " + (" | ".join(detail) or "nothing on stderr")
                                  + f"; stdout: {' | '.join(printed) or 'nothing'}")
            time.sleep(0.02)
        self.zmq_url, self.web_url = urls["zmq_url"], urls["web_url"]

    def stop(self) -> None:
        self._finalizer()
        for f in (self._out, self._err):
            f.close()


def _probe(zmq_url: str, timeout: float) -> str:
    """The web URL of the meshcat server at ``zmq_url``, or a ViewerError when none answers within ``timeout`` s."""
    import zmq

    sock = zmq.Context.instance().socket(zmq.REQ)
    try:
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.RCVTIMEO, int(timeout * 1000))
        sock.connect(zmq_url)
        sock.send(b"url")
        return sock.recv().decode()
    except zmq.error.Again:
        raise ViewerError(f"no meshcat server answers at {zmq_url} within {timeout:g} s; start one with "
                          "`meshcat-server`, or pass zmq_url=None to let the Viewer start its own") from None
    except zmq.error.ZMQError as exc:
        raise ViewerError(f"cannot reach a meshcat server at {zmq_url!r}: {exc}") from None
    finally:
        sock.close()


class _OwnServerSocket:
    """The REQ socket to a Viewer's own server: ``recv`` waits while the server runs, raising ``zmq.ZMQError`` once
    it exited (``zmq.Again`` after ``hang_s`` s)."""

    def __init__(self, sock, proc: subprocess.Popen, hang_s: float):
        self._sock, self._proc, self._hang_s = sock, proc, hang_s

    def recv(self, *args, **kwargs):
        import zmq

        deadline = time.monotonic() + self._hang_s
        while not self._sock.poll(int(_LIVENESS_POLL * 1000)):
            if self._proc.poll() is not None:
                raise zmq.error.ZMQError(msg=f"the server process exited (code {self._proc.returncode})")
            if time.monotonic() > deadline:
                raise zmq.error.Again()
        return self._sock.recv(*args, **kwargs)

    def __getattr__(self, name):
        return getattr(self._sock, name)


def _connect(zmq_url: str, web_url: str, proc: subprocess.Popen | None, answer_timeout: float, hang_s: float):
    """A ``meshcat.Visualizer`` talking to the server at ``zmq_url``: its own ``proc`` (waited for up to ``hang_s``
    s), or None for an external one (``answer_timeout`` s per answer)."""
    import zmq
    from meshcat.visualizer import ViewerWindow, Visualizer

    # ViewerWindow(zmq_url, start_server=False) would print the URL and leave a first socket open
    window = ViewerWindow.__new__(ViewerWindow)
    window.server_proc, window.zmq_url, window.web_url = None, zmq_url, web_url
    window.connect_zmq()
    window.zmq_socket.setsockopt(zmq.LINGER, 0)
    if proc is None:
        window.zmq_socket.setsockopt(zmq.RCVTIMEO, int(answer_timeout * 1000))
    else:
        window.zmq_socket = _OwnServerSocket(window.zmq_socket, proc, hang_s)
    return Visualizer(window=window)


def _import_meshcat() -> None:
    """Import meshcat and Pinocchio's visualizer once, hiding the pyzmq deprecation meshcat's import triggers."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        import meshcat.visualizer  # noqa: F401
        import pinocchio.visualize  # noqa: F401


def _talks(method):
    """Report a lost meshcat server (a ZeroMQ timeout or error) as a ViewerError."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        import zmq

        try:
            return method(self, *args, **kwargs)
        except zmq.error.ZMQError as exc:
            raise ViewerError(f"the meshcat server at {self.zmq_url} did not answer ({exc}); it may have "
                              "stopped") from None

    return wrapper
