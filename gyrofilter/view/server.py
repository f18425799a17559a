"""The live view's HTTP server: the page at ``/``, Server-Sent Events at ``/stream``, one JSON
object at ``/status`` (docs/live.md, "The live view").

The standard library's threaded server (a thread per connection, at most
:data:`MAX_CONNECTIONS` at once; more are closed unanswered) in a thread of its own, and a
publisher thread that, every :data:`FRAME_INTERVAL_S`, drains the
:class:`~gyrofilter.view.state.LiveState` the run loop feeds, encodes the new rows once and puts
the frame in every stream client's queue. A queue holds at most :data:`CLIENT_QUEUE_FRAMES`
frames (and the connection's kernel buffer :data:`STREAM_SEND_BUFFER_BYTES`): a slow or stalled
client loses its oldest frames (counted), never the run's samples, and a client that accepts no
byte for :data:`SOCKET_TIMEOUT_S` is disconnected. A request's line and headers must all arrive
within :data:`REQUEST_DEADLINE_S` of the connection (a deadline for the whole request, not per
read: clients trickling a byte at a time cannot hold the :data:`MAX_CONNECTIONS` slots), and when
every slot is taken a new connection closes the oldest one still sending its request, so that
clients that keep reconnecting to trickle cannot shut others out either. Nothing on the run
loop's side waits for a socket.

Read-only and closed: GET and HEAD only (any other method 405), the fixed paths only (404 for
any other; no file is served from a path the client names), at most
:data:`MAX_STREAM_CLIENTS` stream clients (503 beyond), request lines and headers within the
standard library's limits (414, 431). Bound to a loopback address (the address bound decides,
whatever name was given: a host's own name may map to 127.0.1.1), it answers only requests
whose Host is a loopback name or the name it was given (421 otherwise: a web page elsewhere
cannot read the view through DNS rebinding). Every answer carries a Content-Security-Policy that allows the page's own
script and style sheet only.
"""
from __future__ import annotations

import collections
import http.server
import io
import json
import socket
import socketserver
import sys
import threading
import time
from importlib import resources

from .address import is_loopback
from .state import HISTORY_S, LiveState, rounded_rows

MAX_STREAM_CLIENTS = 16
MAX_CONNECTIONS = 64
CLIENT_QUEUE_FRAMES = 64
#: the kernel's send buffer of a stream connection: what a stalled client holds beyond its queue
STREAM_SEND_BUFFER_BYTES = 128 * 1024
FRAME_INTERVAL_S = 0.1
STATUS_INTERVAL_S = 0.5
SOCKET_TIMEOUT_S = 10.0
#: from the connection to the end of the request's headers, however the bytes trickle in
REQUEST_DEADLINE_S = 10.0
CLOSE_GRACE_S = 1.0
POLL_INTERVAL_S = 0.2

#: path -> (file in page/, content type): the only files served
PAGE_FILES = {
    "/": ("index.html", "text/html; charset=utf-8"),
    "/view.js": ("view.js", "text/javascript; charset=utf-8"),
    "/view.css": ("view.css", "text/css; charset=utf-8"),
}
SECURITY_HEADERS = (
    ("Cache-Control", "no-store"),
    ("X-Content-Type-Options", "nosniff"),
    ("Referrer-Policy", "no-referrer"),
    ("X-Frame-Options", "DENY"),
    ("Content-Security-Policy", "default-src 'none'; script-src 'self'; style-src 'self'; connect-src 'self'; "
                                "img-src 'self' data:; base-uri 'none'; form-action 'none'; frame-ancestors 'none'"),
)
JSON_TYPE = "application/json"
TEXT_TYPE = "text/plain; charset=utf-8"


def to_json(value):
    """Compact JSON bytes (no NaN: the state sends None for what it does not know)."""
    return json.dumps(value, separators=(",", ":"), allow_nan=False).encode()


def sse_event(name, value):
    """One Server-Sent Event: ``event: NAME`` and the JSON of ``value`` on one data line."""
    return b"event: " + name.encode() + b"\ndata: " + to_json(value) + b"\n\n"


class ClientQueue:
    """The frames waiting for one stream client: at most ``capacity``; :meth:`put` drops the
    oldest beyond that (``dropped`` counts them) and never waits."""

    def __init__(self, connection, capacity=None):
        self.connection = connection
        self.capacity = capacity or CLIENT_QUEUE_FRAMES
        self.dropped = 0
        self.closed = False
        self._frames = collections.deque()
        self._cond = threading.Condition()

    def put(self, frame, first=False):
        """Queue ``frame`` (bytes) last, or ``first``."""
        with self._cond:
            if len(self._frames) >= self.capacity:
                self._frames.popleft()
                self.dropped += 1
            if first:
                self._frames.appendleft(frame)
            else:
                self._frames.append(frame)
            self._cond.notify()

    def take(self, timeout_s):
        """Every frame queued, waiting up to ``timeout_s`` for one ([] if none came); None once
        the queue is closed and empty."""
        with self._cond:
            if not self._frames and not self.closed:
                self._cond.wait(timeout_s)
            if self._frames:
                frames = list(self._frames)
                self._frames.clear()
                return frames
            return None if self.closed else []

    def close(self):
        with self._cond:
            self.closed = True
            self._cond.notify()


class LiveServer:
    """The live view: an outlet of ``gyrofilter run`` (:mod:`gyrofilter.view.sink`) serving
    :class:`~gyrofilter.view.state.LiveState`. Binding happens here (an OSError for an address
    in use or not of this machine); :meth:`start` starts serving.

    ``family``, ``sockaddr``: what :func:`gyrofilter.view.address.resolve` gave; ``name``: the
    host name given for it, accepted as a Host besides the loopback names. ``loopback_only``
    (set from the address bound): this server is reachable from this machine only, and answers
    only requests addressed to a loopback name or ``name``.
    """

    def __init__(self, family, sockaddr, *, name=None):
        self.state = LiveState()
        folder = resources.files(__package__).joinpath("page")
        self.page = {path: (folder.joinpath(name).read_bytes(), ctype) for path, (name, ctype) in PAGE_FILES.items()}
        self._publish_lock = threading.Lock()
        self._clients = []
        self._gone = threading.Condition(self._publish_lock)  # notified when a client leaves
        self._last_status = -float("inf")
        self._running = True
        self._stop = threading.Event()
        self._threads = []
        self.clients_served = 0
        self.clients_refused = 0
        self.dropped_frames = 0  # of clients that left; status() adds those of the clients still here
        self.errors = 0
        self.last_error = None
        self._httpd = _HTTPServer(family, sockaddr, self)
        self.address = self._httpd.server_address[:2]
        self.loopback_only = is_loopback(self.address[0])
        self.host_names = {_host_name(name)} if name else set()

    @property
    def url(self):
        host, port = self.address
        return f"http://{f'[{host}]' if ':' in host else host}:{port}/"

    # ---------------------------------------------------------------- the run loop's side
    def start(self, info):
        self.state.start(info)
        for target in (lambda: self._httpd.serve_forever(POLL_INTERVAL_S), self._publisher):
            thread = threading.Thread(target=target, name="gyrofilter-view", daemon=True)
            thread.start()
            self._threads.append(thread)

    def feed(self, step):
        self.state.feed(step)

    def close(self):
        """Publish the last rows and a final status (``"running": false``), let the clients read
        them for up to :data:`CLOSE_GRACE_S`, close every connection and the port. Returns a summary."""
        if self._threads:
            self._stop.set()
            self._threads[1].join()
            self._running = False
            self._publish_safely()
            deadline = time.monotonic() + CLOSE_GRACE_S
            with self._publish_lock:
                for client in self._clients:
                    client.close()
                while self._clients and time.monotonic() < deadline:
                    self._gone.wait(max(0.0, deadline - time.monotonic()))
                for client in self._clients:  # stalled: unblock its thread's write
                    _shutdown(client.connection)
            self._httpd.shutdown()
            self._threads[0].join()
        self._httpd.server_close()
        words = [f"{self.clients_served} stream clients served", f"{self.dropped_frames} frames dropped for slow clients"]
        if self.clients_refused:
            words.append(f"{self.clients_refused} refused (more than {MAX_STREAM_CLIENTS})")
        if self.state.inbox_dropped:
            words.append(f"{self.state.inbox_dropped} reads not shown (the view fell behind)")
        if self.errors:
            words.append(f"{self.errors} errors, the last: {self.last_error}")
        return f"live view {self.url}: " + ", ".join(words)

    # ---------------------------------------------------------------- the server's side
    def _publisher(self):
        while not self._stop.wait(FRAME_INTERVAL_S):
            self._publish_safely()

    def _publish_safely(self):
        try:
            self._publish()
        except Exception as exc:  # noqa: BLE001 - the view must never stop the run; the summary says it
            self.record_error(exc)

    def record_error(self, exc):
        self.errors += 1
        self.last_error = " ".join(f"{type(exc).__name__}: {exc}".split())

    def _publish(self):
        with self._publish_lock:
            rows, raw = self.state.drain()
            parts = []
            if len(rows) or len(raw):
                parts.append(sse_event("rows", {"rows": rounded_rows(rows[:, 0], rows[:, 1:]),
                                                "raw": rounded_rows(raw[:, 0], raw[:, 1:])}))
            now = time.monotonic()
            if not self._running or now - self._last_status >= STATUS_INTERVAL_S:
                parts.append(sse_event("status", self._status()))
                self._last_status = now
            if parts:
                frame = b"".join(parts)
                for client in self._clients:
                    client.put(frame)

    def _status(self):
        """The status object (publish lock held)."""
        status = self.state.status()
        status["clients"] = len(self._clients)
        status["dropped_frames"] = self.dropped_frames + sum(c.dropped for c in self._clients)
        status["running"] = self._running
        return status

    def status_json(self):
        with self._publish_lock:
            return to_json(self._status())

    def add_client(self, connection):
        """A new stream client's queue, its first frame the ``hello`` event (the history kept and
        the status); None when :data:`MAX_STREAM_CLIENTS` are connected."""
        with self._publish_lock:
            if len(self._clients) >= MAX_STREAM_CLIENTS or not self._running:
                self.clients_refused += 1
                return None
            client = ClientQueue(connection)
            self._clients.append(client)
            self.clients_served += 1
            status = self._status()
        hello = sse_event("hello", {"history_s": HISTORY_S, **self.state.history(), "status": status})
        client.put(hello, first=True)
        return client

    def remove_client(self, client):
        with self._publish_lock:
            self._clients.remove(client)
            self.dropped_frames += client.dropped
            self._gone.notify_all()


class _DeadlineReader(io.RawIOBase):
    """A socket's bytes until ``deadline`` (time.monotonic()): each receive waits at most the
    time left, and none starts after it (TimeoutError, which the handler takes as a timed-out
    request: the connection is closed unanswered)."""

    def __init__(self, connection, deadline):
        super().__init__()
        self._connection = connection
        self._deadline = deadline

    def readable(self):
        return True

    def readinto(self, buffer):
        left = self._deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError("the request did not arrive in time")
        self._connection.settimeout(left)
        return self._connection.recv_into(buffer)


def _shutdown(connection):
    try:
        connection.shutdown(socket.SHUT_RDWR)
    except OSError:
        pass


class _HTTPServer(socketserver.ThreadingMixIn, socketserver.TCPServer):
    """A thread per connection, at most MAX_CONNECTIONS (when all are taken, the oldest one whose
    request has not arrived whole is closed for the new one; none such: the new one is closed);
    no reverse name look-up at bind time (http.server.HTTPServer does one), errors counted
    instead of printed."""

    allow_reuse_address = True
    daemon_threads = True
    request_queue_size = 32

    def __init__(self, family, sockaddr, live):
        self.address_family = family
        self.live = live
        self._count_lock = threading.Lock()
        self._connections = 0
        self._pending = {}  # the connections whose request has not arrived whole, oldest first
        super().__init__(sockaddr, _Handler)

    def process_request(self, request, client_address):
        with self._count_lock:
            oldest = None
            if self._connections >= MAX_CONNECTIONS and self._pending:
                oldest = next(iter(self._pending))
                del self._pending[oldest]
            full = self._connections >= MAX_CONNECTIONS and oldest is None
            if not full:
                self._connections += 1
                self._pending[request] = None
        if oldest is not None:  # its thread reads the end of the stream and leaves
            _shutdown(oldest)
        if full:
            self.shutdown_request(request)
            return
        super().process_request(request, client_address)

    def request_arrived(self, request):
        """The request of the connection ``request`` has arrived whole: it is no longer evictable."""
        with self._count_lock:
            self._pending.pop(request, None)

    def process_request_thread(self, request, client_address):
        try:
            super().process_request_thread(request, client_address)
        finally:
            with self._count_lock:
                self._connections -= 1
                self._pending.pop(request, None)

    def handle_error(self, request, client_address):
        self.live.record_error(sys.exc_info()[1])


class _Handler(http.server.BaseHTTPRequestHandler):
    server_version = "gyrofilter"
    sys_version = ""
    protocol_version = "HTTP/1.0"
    timeout = SOCKET_TIMEOUT_S
    error_content_type = TEXT_TYPE
    error_message_format = "%(code)d %(message)s\n"

    def version_string(self):
        return self.server_version

    def setup(self):
        """The request is read through a :class:`_DeadlineReader`: its line and headers must all
        arrive within REQUEST_DEADLINE_S (one request per connection: HTTP/1.0)."""
        super().setup()
        self.rfile.close()  # the standard library's reader of the socket, replaced
        self.rfile = io.BufferedReader(_DeadlineReader(self.connection, time.monotonic() + REQUEST_DEADLINE_S))

    def log_message(self, format, *args):  # noqa: A002 - the standard library's signature
        """Nothing: the library never prints (the run's summary counts what matters)."""

    def end_headers(self):
        for name, value in SECURITY_HEADERS:
            self.send_header(name, value)
        super().end_headers()

    def parse_request(self):
        parsed = super().parse_request()  # reads the headers
        self.server.request_arrived(self.connection)  # its line and headers are in (or refused)
        if not parsed:
            return False
        self.connection.settimeout(SOCKET_TIMEOUT_S)  # the request is in; the answer's writes time out per write
        if self.command not in ("GET", "HEAD"):
            self._reply(405, b"405 read-only: GET or HEAD\n", TEXT_TYPE, extra=(("Allow", "GET, HEAD"),))
            return False
        live = self.server.live
        hosts = self.headers.get_all("Host") or [None]  # two: 400, as RFC 9112 3.2 says (attack pass 57)
        if len(hosts) > 1:
            self._reply(400, b"400 more than one Host header\n", TEXT_TYPE)
            return False
        if live.loopback_only and not _loopback_host(hosts[0], live.host_names):
            self._reply(421, b"421 this view answers requests for localhost only\n", TEXT_TYPE)
            return False
        return True

    def do_GET(self):  # noqa: N802 - the standard library's name
        self._route(head_only=False)

    def do_HEAD(self):  # noqa: N802
        self._route(head_only=True)

    def _route(self, head_only):
        live = self.server.live
        path = self.path.split("?", 1)[0]
        if path in live.page:
            body, content_type = live.page[path]
            self._reply(200, body, content_type, head_only)
        elif path == "/status":
            self._reply(200, live.status_json(), JSON_TYPE, head_only)
        elif path == "/stream":
            self._stream(head_only)
        else:
            self._reply(404, b"404 not found: this server has /, /stream and /status\n", TEXT_TYPE, head_only)

    def _reply(self, code, body, content_type, head_only=False, extra=()):
        self.send_response(code)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        for name, value in extra:
            self.send_header(name, value)
        if code >= 400:
            self.send_header("Connection", "close")
            self.close_connection = True
        self.end_headers()
        if not head_only:
            self.wfile.write(body)

    def _stream(self, head_only):
        live = self.server.live
        client = live.add_client(self.connection)
        if client is None:
            self._reply(503, f"503 at most {MAX_STREAM_CLIENTS} stream clients at once\n".encode(), TEXT_TYPE,
                        head_only, extra=(("Retry-After", "5"),))
            return
        try:
            self.connection.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, STREAM_SEND_BUFFER_BYTES)
            self.send_response(200)
            self.send_header("Content-Type", "text/event-stream; charset=utf-8")
            self.send_header("X-Accel-Buffering", "no")
            self.end_headers()
            if head_only:
                return
            self.wfile.write(b"retry: 3000\n\n")
            while (frames := client.take(STATUS_INTERVAL_S)) is not None:
                if frames:
                    self.wfile.write(b"".join(frames))
        except OSError:  # the client went away, or accepted nothing for SOCKET_TIMEOUT_S
            pass
        finally:
            live.remove_client(client)
            self.close_connection = True


def _loopback_host(host_header, names):
    """True when a Host header names a loopback host or one of ``names`` (or is absent, as from an
    HTTP/1.0 client). A Host is ``name`` or ``name:port`` (``[address]:port`` for IPv6, RFC 9110
    section 7.2), the port digits only: ``localhost:80@evil.example`` is no loopback host."""
    if host_header is None:
        return True
    host = host_header.strip()
    if host.startswith("["):
        host, _, port = host[1:].partition("]")
        if port and not (port[:1] == ":" and port[1:].isdigit()):
            return False
    elif ":" in host:
        host, _, port = host.rpartition(":")
        if not port.isdigit():
            return False
    host = _host_name(host)
    return is_loopback(host) or host in names


def _host_name(host):
    """A host name as compared: lower case, without the root's trailing dot."""
    return host.lower().removesuffix(".")
