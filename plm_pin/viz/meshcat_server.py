"""Where a meshcat scene goes: a meshcat server bound to 127.0.0.1, or an in-memory scene for static HTML.

The server is meshcat's own (tornado for the web page, ZeroMQ for the drawing commands),
run in a subprocess (``python -m plm_pin.viz.meshcat_server --port N``) whose web and
ZeroMQ sockets both listen on 127.0.0.1 only: meshcat's ``meshcat-server`` listens for the
web page on every interface. Every request to a server has a time-out, so a dead or
foreign server raises :class:`ViewerError` instead of hanging the caller.

meshcat is optional (``pip install 'plm-pin[viz]'``) and imported only when a scene is made.
"""

from __future__ import annotations

import argparse
import functools
import importlib
import ipaddress
import os
import queue
import subprocess
import sys
import tempfile
import threading
import time
import urllib.parse
import weakref
import webbrowser
from collections.abc import Callable, Sequence
from pathlib import Path
from types import ModuleType
from typing import IO, Any, TypeVar

from ..exceptions import InvalidInput, ViewerError
from .legend import ENTRIES, with_legend

LOCALHOST = "127.0.0.1"
"""The only address a server started here listens on."""

DEFAULT_PORT = 7000
"""First web port tried when none is asked for (meshcat's default)."""

PORT_ATTEMPTS = 100
"""Ports tried, from the one asked for upwards, before giving up."""

START_TIMEOUT = 30.0
"""Longest wait for a new server to report its addresses [s]."""

REPLY_TIMEOUT = 10.0
"""Longest wait for a server to answer one request [s]."""

PARENT_CHECK_MS = 1000
"""Period at which a server checks that the process that started it is alive [ms]."""

VIZ_EXTRA = "pip install 'plm-pin[viz]'"

T = TypeVar("T")


def require_meshcat() -> ModuleType:
    """Import meshcat, or raise :class:`ViewerError` saying how to install it."""
    try:
        return importlib.import_module("meshcat")
    except ImportError as exc:
        raise ViewerError(
            f"the meshcat viewer needs meshcat, which cannot be imported ({exc}): {VIZ_EXTRA}"
        ) from None


def check_port(port: int) -> int:
    """Return ``port`` after checking it is a port number.

    Raises:
        InvalidInput: when ``port`` is not in 1..65535.
    """
    if not 1 <= port <= 65535:
        raise InvalidInput(f"port must be in 1..65535, got {port}")
    return port


def first_free(start: int, bind: Callable[[int], T], attempts: int = PORT_ATTEMPTS) -> T:
    """``bind(port)`` on the first port from ``start`` where it does not raise :class:`OSError`.

    The bind itself is the test, so that no other process can take the port between a check
    and the bind.

    Raises:
        InvalidInput: when ``start`` is not a port number.
        ViewerError: when the ``attempts`` ports from ``start`` are all busy.
    """
    last = min(check_port(start) + attempts, 65536)
    for port in range(start, last):
        try:
            return bind(port)
        except OSError:
            continue
    raise ViewerError(f"ports {start} to {last - 1} on {LOCALHOST} are all busy; choose another with --port")


class MeshcatServer:
    """A meshcat server in a subprocess, listening on 127.0.0.1 only; closed at exit at the latest.

    Attributes:
        requested_port: the web port asked for, or None.
        port: the web port served (the next free one when the requested port is busy: the
            server binds the first port it can from the requested one up).
        zmq_url: address of the drawing commands (``tcp://127.0.0.1:...``).
        web_url: address of the page (``http://127.0.0.1:.../static/``).
    """

    def __init__(self, port: int | None = None, *, timeout: float = START_TIMEOUT) -> None:
        """Start a server on ``port`` (default: the first free port from 7000 up).

        Raises:
            ViewerError: meshcat missing, no free port, or the server did not start within
                ``timeout`` [s] (the message quotes its error output).
        """
        require_meshcat()
        self.requested_port = port
        start = check_port(DEFAULT_PORT if port is None else port)
        log = tempfile.TemporaryFile()
        process = subprocess.Popen(
            [sys.executable, "-m", __name__, "--port", str(start), "--parent", str(os.getpid())],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=log,
            start_new_session=True,  # an interrupted notebook cell does not take the server down
        )
        self._process = process
        self._finalizer = weakref.finalize(self, _stop, process, log)
        assert process.stdout is not None
        try:
            lines = _read_lines(process.stdout, 2, timeout)
            if len(lines) < 2:
                raise ViewerError(
                    f"the meshcat server did not start within {timeout:g} s: {_tail(log) or 'no output'}"
                )
        except BaseException:
            self.close()
            raise
        self.zmq_url = lines[0].removeprefix("zmq_url=")
        self.web_url = lines[1].removeprefix("web_url=")
        self.port = int(urllib.parse.urlsplit(self.web_url).port or start)

    @property
    def moved(self) -> bool:
        """Whether the requested port was busy, so that another one is served."""
        return self.requested_port is not None and self.port != self.requested_port

    @property
    def running(self) -> bool:
        """Whether the server process is alive."""
        return self._process.poll() is None

    def wait(self) -> int:
        """Block until the server process ends (Ctrl-C interrupts); returns its exit code."""
        return self._process.wait()

    def close(self) -> None:
        """Stop the server process and reap it (idempotent)."""
        self._finalizer()

    def __enter__(self) -> MeshcatServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "running" if self.running else "stopped"
        return f"MeshcatServer({self.web_url!r}, zmq_url={self.zmq_url!r}, {state})"


def _stop(process: subprocess.Popen[bytes], log: IO[bytes]) -> None:
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=5.0)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
    if process.stdout is not None:
        process.stdout.close()
    log.close()


def _read_lines(stream: IO[bytes], count: int, timeout: float) -> list[str]:
    """Up to ``count`` lines of ``stream``: fewer when it ends or ``timeout`` [s] passes first."""
    lines: queue.Queue[str | None] = queue.Queue()

    def pump() -> None:
        for raw in stream:
            lines.put(raw.decode("utf-8", "replace").strip())
        lines.put(None)

    threading.Thread(target=pump, daemon=True).start()  # ends at EOF: the server closes its stdout
    out: list[str] = []
    deadline = time.monotonic() + timeout
    while len(out) < count:
        try:
            line = lines.get(timeout=max(deadline - time.monotonic(), 0.0))
        except queue.Empty:
            break
        if line is None:
            break
        out.append(line)
    return out


def _tail(log: IO[bytes], lines: int = 5) -> str:
    log.seek(0)
    return " | ".join(log.read().decode("utf-8", "replace").strip().splitlines()[-lines:])


def check_local_url(zmq_url: str) -> str:
    """Return ``zmq_url`` after checking it is ``tcp://`` on a loopback address.

    Raises:
        InvalidInput: another scheme, or a host that is not loopback.
    """
    parsed = urllib.parse.urlsplit(zmq_url)
    host = parsed.hostname or ""
    try:
        local = host == "localhost" or ipaddress.ip_address(host).is_loopback
    except ValueError:
        local = False
    if parsed.scheme != "tcp" or not local or parsed.port is None:
        raise InvalidInput(
            f"zmq_url must be tcp://127.0.0.1:PORT (a server on this machine), got {zmq_url!r}"
        )
    return zmq_url


class ServerWindow:
    """meshcat's window protocol to a running server, with time-outs (for ``meshcat.Visualizer(window=...)``).

    Attributes:
        zmq_url: the server's command address.
        web_url: the page's address.
    """

    def __init__(self, zmq_url: str, web_url: str | None = None, *, timeout: float = REPLY_TIMEOUT) -> None:
        """Connect to the server at ``zmq_url`` (loopback only); ask it its page address if not given.

        Raises:
            InvalidInput: when ``zmq_url`` is not a loopback ``tcp://`` address.
            ViewerError: meshcat missing, or the server does not answer within ``timeout`` [s].
        """
        require_meshcat()
        self._zmq = importlib.import_module("zmq")
        self._msgpack = importlib.import_module("umsgpack")
        self.zmq_url = check_local_url(zmq_url)
        self._timeout_ms = round(timeout * 1000.0)
        self._socket = self._connect()
        if web_url is None:
            web_url = self._request(b"url").decode("utf-8")
            # as meshcat does: after a "url" request the server ignores this socket until it reconnects
            self._socket.close()
            self._socket = self._connect()
        self.web_url = web_url

    def _connect(self) -> Any:
        sock = self._zmq.Context.instance().socket(self._zmq.REQ)
        sock.setsockopt(self._zmq.LINGER, 0)
        sock.setsockopt(self._zmq.RCVTIMEO, self._timeout_ms)
        sock.setsockopt(self._zmq.SNDTIMEO, self._timeout_ms)
        sock.connect(self.zmq_url)
        return sock

    def _request(self, *frames: bytes) -> bytes:
        try:
            self._socket.send_multipart(list(frames))
            return bytes(self._socket.recv())
        except self._zmq.Again:
            self._socket.close()  # a REQ socket without its reply cannot be used again
            raise ViewerError(
                f"the meshcat server at {self.zmq_url} did not answer within {self._timeout_ms / 1000:g} s"
            ) from None

    def send(self, command: Any) -> None:
        """Send one meshcat command (``SetObject``, ``SetTransform``, ...)."""
        data = command.lower()
        self._request(data["type"].encode("utf-8"), data["path"].encode("utf-8"), self._msgpack.packb(data))

    def get_scene(self) -> str:
        """The server's current scene as self-contained HTML."""
        return self._request(b"get_scene").decode("utf-8")

    def open(self) -> None:
        """Open the page in a web browser."""
        webbrowser.open(self.web_url, new=2)

    def close(self) -> None:
        """Close the connection (the server keeps running)."""
        self._socket.close()


class StaticWindow:
    """meshcat's window protocol kept in memory: the scene becomes static HTML, no server or socket.

    The commands update the same scene tree a server keeps, and the HTML is written by the
    server's own code, so it is the page ``get_scene`` of a server would return.
    """

    web_url = None

    def __init__(self) -> None:
        """An empty scene.

        Raises:
            ViewerError: when meshcat is missing.
        """
        require_meshcat()
        self._packb = packer()
        self._bridge = _recorder_class()()

    def send(self, command: Any) -> None:
        """Apply one meshcat command to the scene."""
        data = command.lower()
        self._bridge.handle_zmq(
            [data["type"].encode("utf-8"), data["path"].encode("utf-8"), self._packb(data)]
        )

    def get_scene(self) -> str:
        """The scene as self-contained HTML (meshcat's JavaScript included)."""
        self._bridge.handle_zmq([b"get_scene"])
        return self._bridge.reply.decode("utf-8")

    def open(self) -> None:
        """Refuse: a static scene has no page to open."""
        raise ViewerError("a static scene has no server page; write it with static_html() or write_html()")

    def close(self) -> None:
        """Nothing to close."""


@functools.cache
def packer() -> Callable[[Any], bytes]:
    """The packer of meshcat's commands: the compiled ``msgpack`` if installed, else ``umsgpack``.

    Both write the same bytes (the MessagePack format leaves no choice for these values:
    strings, floats as float64, lists, maps and meshcat's typed-array extensions); the
    compiled one is some ten times faster on an animation's thousands of transforms.
    """
    umsgpack = importlib.import_module("umsgpack")
    try:
        msgpack = importlib.import_module("msgpack")
    except ImportError:
        return umsgpack.packb

    def default(obj: Any) -> Any:
        if isinstance(obj, umsgpack.Ext):
            return msgpack.ExtType(obj.type, obj.data)
        raise TypeError(f"cannot pack {type(obj).__name__} for meshcat")

    return functools.partial(msgpack.packb, default=default, use_bin_type=True)


@functools.cache
def _recorder_class() -> type:
    """The meshcat server bridge without sockets: it records the scene and answers into ``reply``."""
    zmqserver = importlib.import_module("meshcat.servers.zmqserver")
    tree = importlib.import_module("meshcat.servers.tree")

    class Recorder(zmqserver.ZMQWebSocketBridge):  # type: ignore[name-defined]
        def __init__(self) -> None:
            self.tree = tree.SceneTree()
            self.websocket_pool: set[Any] = set()
            self.zmq_socket = self
            self.reply = b""

        def send(self, data: bytes) -> None:  # the bridge answers its ZeroMQ socket: here, itself
            self.reply = data

    return Recorder


def _local_bridge(port: int) -> Any:
    """The meshcat server bridge with its web page served on 127.0.0.1 only (ZeroMQ already is).

    The page is served on the first port from ``port`` up that can be bound (meshcat's own
    search, binding each port in turn, as it does for the ZeroMQ port).

    The page is meshcat's with the legend of every mark a viewer draws (:mod:`plm_pin.viz.legend`).
    """
    zmqserver = importlib.import_module("meshcat.servers.zmqserver")
    web = importlib.import_module("tornado.web")
    routing = importlib.import_module("tornado.routing")
    zmqserver.DEFAULT_FILESERVER_PORT = port  # type: ignore[attr-defined]  # where meshcat's search starts
    viewer_page = Path(zmqserver.VIEWER_ROOT, zmqserver.VIEWER_HTML).read_text(encoding="utf-8")
    page = with_legend(viewer_page, list(ENTRIES.values()))

    class ViewerPage(web.RequestHandler):  # type: ignore[name-defined]
        def get(self) -> None:
            self.set_header("Cache-Control", "no-store, no-cache, must-revalidate, max-age=0")
            self.write(page)

    class LocalBridge(zmqserver.ZMQWebSocketBridge):  # type: ignore[name-defined]
        def make_app(self) -> Any:
            app = super().make_app()
            rule = routing.Rule(routing.PathMatches(r"/static/(?:index\.html)?"), ViewerPage)
            app.wildcard_router.rules.insert(0, app.wildcard_router.process_rule(rule))  # before the files
            app.listen = functools.partial(app.listen, address=LOCALHOST)  # tornado's default: all
            return app

    return LocalBridge(host=LOCALHOST)


def main(argv: Sequence[str] | None = None) -> None:
    """Run a meshcat server on 127.0.0.1 (the subprocess of :class:`MeshcatServer`).

    Prints ``zmq_url=...`` and ``web_url=...`` on stdout, then closes stdout (later output
    goes to stderr) and serves until terminated.
    """
    parser = argparse.ArgumentParser(prog=f"python -m {__name__}", description=main.__doc__)
    parser.add_argument("--port", type=int, required=True, help="first web port tried")
    parser.add_argument("--parent", type=int, help="stop when this process is gone (its pid)")
    args = parser.parse_args(argv)
    bridge = _local_bridge(args.port)
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # nobody reads the pipe any more
    if args.parent is not None:  # a killed parent cannot stop us: notice it is gone (we are re-parented)

        def stop_if_orphaned() -> None:
            if os.getppid() != args.parent:
                bridge.ioloop.stop()

        importlib.import_module("tornado.ioloop").PeriodicCallback(stop_if_orphaned, PARENT_CHECK_MS).start()
    bridge.run()


if __name__ == "__main__":
    main()
