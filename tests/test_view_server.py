"""The live view's HTTP server on a real socket on 127.0.0.1, fed from the test as the run loop
feeds it: the endpoints and their JSON, what it refuses, and clients that read slowly or never."""
import contextlib
import json
import socket
import threading
import time

import numpy as np
import pytest

from gyrofilter.view import server as server_module
from gyrofilter.view.server import MAX_STREAM_CLIENTS, ClientQueue, LiveServer
from gyrofilter.view.sink import RunInfo, Step
from support.live import EventReader, StalledClient, get, request, status, wait_for

INFO = RunInfo(source="sim:seed=1", sample_rate_hz=100.0, block_len=5, output_rate_hz=20.0, preset="recommended")


def step(i, n=10):
    """Samples i*n .. (i+1)*n - 1 at 100 Hz and the two rows they complete (stand-ins)."""
    t = (i * n + np.arange(n)) / 100.0
    rows_t = t[4::5]
    return Step(t_s=t, gyro_dps=np.full((n, 3), 0.25), temp_c=np.full(n, 30.5), rows_t_s=rows_t,
                rows_dps=np.full((len(rows_t), 3), 0.001 * i), samples_in=(i + 1) * n, rows_out=2 * (i + 1),
                lost_samples=3, rejected_outliers=(0, 1, 0), calibration="calibrated", bias_dps=(0.25, 0.25, 0.25))


@pytest.fixture
def live():
    server = LiveServer(socket.AF_INET, ("127.0.0.1", 0))
    server.start(INFO)
    yield server
    server.close()


@pytest.fixture(scope="module")
def idle():
    """One server for the tests that feed it nothing."""
    server = LiveServer(socket.AF_INET, ("127.0.0.1", 0))
    server.start(INFO)
    yield server
    server.close()


def test_the_page_and_its_files_come_from_the_package(idle):
    port = idle.address[1]
    code, head, body = get(port, "/")
    assert code == 200 and "text/html" in head and "Content-Security-Policy: default-src 'none'" in head
    page = body.decode()
    for element in ("plot-x", "plot-y", "plot-z", "rows-out", "samples-in", "lost-samples", "calibration"):
        assert f'id="{element}"' in page
    for path, kind in (("/view.js", "text/javascript"), ("/view.css", "text/css")):
        code, head, body = get(port, path)
        assert code == 200 and kind in head and body
    for text in (page, get(port, "/view.js")[2].decode(), get(port, "/view.css")[2].decode()):
        assert "http://" not in text and "https://" not in text and "//cdn" not in text


def test_status_and_stream_carry_the_rows_and_counters(live):
    port = live.address[1]
    reader = EventReader(port)
    reader.start()
    reader.connected.wait(10)
    for i in range(30):
        live.feed(step(i))
    wait_for(lambda: sum(len(e["rows"]) for e in reader.named("rows")) == 60, what="60 rows on the stream")
    got = status(port)
    assert got["samples_in"] == 300 and got["rows_out"] == 60 and got["lost_samples"] == 3
    assert got["sample_rate_hz"] == 100.0 and got["calibration"] == "calibrated" and got["clients"] == 1
    assert got["temp_c"] == 30.5 and got["bias_dps"] == [0.25, 0.25, 0.25] and got["running"] is True
    rows = [r for e in reader.named("rows") for r in e["rows"]]
    assert [r[0] for r in rows] == pytest.approx([(5 * k + 4) / 100 for k in range(60)])
    assert rows[-1][1:] == [0.029, 0.029, 0.029]
    raw = [r for e in reader.named("rows") for r in e["raw"]]
    assert len(raw) == 60 and all(r[1:] == [0.25, 0.25, 0.25] for r in raw)
    assert reader.events[0][0] == "hello" and reader.events[0][1]["history_s"] == 60
    wait_for(lambda: reader.named("status") and reader.named("status")[-1]["samples_in"] == 300, what="a status event")
    reader.stop()


def test_a_client_that_connects_later_gets_the_history_first(live):
    port = live.address[1]
    for i in range(10):
        live.feed(step(i))
    wait_for(lambda: status(port)["rows_out"] == 20, what="the publisher")
    reader = EventReader(port)
    reader.start()
    wait_for(lambda: reader.events, what="the hello event")
    name, hello = reader.events[0]
    assert name == "hello" and len(hello["rows"]) == 20 and len(hello["raw"]) == 20
    assert hello["status"]["rows_out"] == 20
    reader.stop()


@pytest.mark.parametrize("raw, code", [
    (b"POST / HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 4\r\n\r\nabcd", 405),
    (b"PUT /status HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 405),
    (b"DELETE /stream HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 405),
    (b"OPTIONS * HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 405),
    (b"GET /../../etc/passwd HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 404),
    (b"GET /%2e%2e/%2e%2e/etc/passwd HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 404),
    (b"GET /view.js/../../../pyproject.toml HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 404),
    (b"GET /page/index.html HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 404),
    (b"GET http://evil.example/ HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 404),
    (b"GET /" + b"a" * 70000 + b" HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 414),
    (b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n" + b"X-A: b\r\n" * 120 + b"\r\n", 431),
    (b"GET / HTTP/1.1\r\nHost: attacker.example:8000\r\n\r\n", 421),
    (b"GET / HTTP/1.1\r\nHost: localhost:80@evil.example\r\n\r\n", 421),
    (b"GET / HTTP/1.1\r\nHost: [::1]@evil.example\r\n\r\n", 421),
    (b"GET /status HTTP/1.1\r\nHost: 127.0.0.1\r\nHost: evil.example\r\n\r\n", 400),  # pass 57: the first one
    (b"GET /status HTTP/1.1\r\nHost: evil.example\r\nHost: 127.0.0.1\r\n\r\n", 400),  # was taken
    (b"\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03garbage\r\n\r\n", 400),
])
def test_what_is_refused(idle, raw, code):
    got, answer = request(idle.address[1], raw)
    if got is None:  # a request line that is not HTTP/1.x gets an answer without a status line (HTTP/0.9)
        got = int(answer[:3])
    assert got == code, answer[:200]
    assert b"root:" not in answer and b"[project]" not in answer
    assert get(idle.address[1], "/status")[0] == 200  # and the server goes on


def test_at_most_16_stream_clients_the_17th_gets_503(live):
    port = live.address[1]
    readers = [EventReader(port) for _ in range(MAX_STREAM_CLIENTS)]
    for r in readers:
        r.start()
    wait_for(lambda: status(port)["clients"] == MAX_STREAM_CLIENTS, what="16 clients")
    code, answer = request(port, b"GET /stream HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
    assert code == 503 and b"Retry-After" in answer
    readers[0].stop()
    live.feed(step(0))
    wait_for(lambda: status(port)["clients"] == MAX_STREAM_CLIENTS - 1, what="a client to leave")
    late = EventReader(port)
    late.start()
    wait_for(lambda: late.events, what="the hello of a client taking the free place")
    assert late.status_code == 200
    for r in readers + [late]:
        r.stop()


def test_a_queue_drops_its_oldest_frames_and_counts_them():
    queue = ClientQueue(connection=None, capacity=4)
    for k in range(10):
        queue.put(b"%d" % k)
    assert queue.take(0) == [b"6", b"7", b"8", b"9"] and queue.dropped == 6
    queue.put(b"first", first=True)
    queue.close()
    assert queue.take(0) == [b"first"] and queue.take(0) is None


def test_stalled_clients_never_hold_up_the_feed(live, monkeypatch):
    """Three clients that never read and one that reads: feeding 1500 steps takes no network wait
    (the feed only queues), the reader gets the last rows, the stalled ones lose frames (counted)."""
    monkeypatch.setattr(server_module, "CLIENT_QUEUE_FRAMES", 2)
    port = live.address[1]
    stalled = [StalledClient(port) for _ in range(3)]
    reader = EventReader(port)
    reader.start()
    wait_for(lambda: status(port)["clients"] == 4, what="4 clients")
    done = threading.Event()

    def run_loop():
        for i in range(1500):
            live.feed(step(i, n=100))
            time.sleep(0.001)  # over seconds, so that many frames are published
        done.set()

    thread = threading.Thread(target=run_loop)
    thread.start()
    thread.join(60)
    assert done.is_set()
    wait_for(lambda: status(port)["samples_in"] == 150000, what="the publisher to catch up")
    wait_for(lambda: any(r[0] == pytest.approx(1499.99) for e in reader.named("rows") for r in e["rows"]),
             what="the last row at the reading client")
    wait_for(lambda: status(port)["dropped_frames"] > 0, what="frames dropped for the stalled clients")
    for client in stalled:
        client.close()
    reader.stop()


def test_close_sends_a_final_status_and_frees_the_port():
    live = LiveServer(socket.AF_INET, ("127.0.0.1", 0))
    live.start(INFO)
    port = live.address[1]
    reader = EventReader(port)
    reader.start()
    wait_for(lambda: status(port)["clients"] == 1, what="the client")
    live.feed(step(0))
    summary = live.close()
    reader.join(10)
    assert reader.named("status")[-1]["running"] is False and reader.named("status")[-1]["rows_out"] == 2
    assert summary == f"live view http://127.0.0.1:{port}/: 1 stream clients served, 0 frames dropped for slow clients"
    with socket.socket() as sock:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(("127.0.0.1", port))


def test_a_server_bound_to_all_interfaces_answers_any_host_name():
    live = LiveServer(socket.AF_INET, ("0.0.0.0", 0))
    live.start(INFO)
    try:
        code, _, body = get(live.address[1], "/status", host="raspberrypi.local")
        assert code == 200 and json.loads(body)["running"] is True
    finally:
        live.close()


def test_a_server_bound_to_loopback_through_a_name_answers_that_name_and_loopback_names_only():
    """The address bound decides (issue 37): a Pi's own name maps to 127.0.1.1."""
    live = LiveServer(socket.AF_INET, ("127.0.0.1", 0), name="RaspberryPi.")
    live.start(INFO)
    try:
        port = live.address[1]
        assert live.loopback_only
        for host, code in (("raspberrypi", 200), ("localhost", 200), ("127.0.0.1", 200), ("evil.example", 421),
                           ("raspberrypi.evil.example", 421)):
            assert get(port, "/status", host=host)[0] == code, host
    finally:
        live.close()


def test_a_server_bound_to_an_ipv4_mapped_loopback_address_keeps_the_host_check():
    """Attack pass (issue 37): bound to ::ffff:127.0.0.1 (reachable from this machine only), the
    server answered a request for evil.example (DNS rebinding); it answers loopback names only."""
    try:
        live = LiveServer(socket.AF_INET6, ("::ffff:127.0.0.1", 0, 0, 0))
    except OSError as exc:
        pytest.skip(f"no IPv4-mapped IPv6 socket here ({exc})")
    live.start(INFO)
    try:
        assert live.loopback_only
        port = live.address[1]
        for host, code in (("127.0.0.1", 200), ("localhost", 200), ("evil.example", 421)):
            assert get(port, "/status", host=host)[0] == code, host
    finally:
        live.close()


def test_an_error_inside_the_view_is_counted_not_raised(live, monkeypatch):
    def broken():
        raise RuntimeError("boom")

    monkeypatch.setattr(live.state, "drain", broken)
    live.feed(step(0))
    wait_for(lambda: live.errors > 0, what="the publisher's error")
    assert live.last_error == "RuntimeError: boom"
    monkeypatch.setattr(server_module, "CLOSE_GRACE_S", 0.1)


class Trickler(threading.Thread):
    """A slowloris client: a byte of a request line every 0.2 s, until the server closes the
    connection (``closed`` is set) or :meth:`stop`."""

    def __init__(self, port):
        super().__init__(daemon=True)
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=30)
        self.closed = threading.Event()
        self._halt = threading.Event()

    def run(self):
        try:
            for byte in b"GET /status HTTP/1.1\r\nHost: 127.0.0.1\r\n" + b"X-Slow: " + b"a" * 10000:
                self.sock.sendall(bytes([byte]))
                if self._halt.wait(0.2):
                    return
        except OSError:  # reset by the server
            pass
        finally:
            self.closed.set()

    def stop(self):
        self._halt.set()
        self.sock.close()


def test_clients_trickling_their_requests_cannot_hold_every_connection(monkeypatch):
    """Slowloris (issue 37): as many clients as there are connection slots, each sending a byte
    every 0.2 s, are cut at the whole-request deadline (the socket timeout is per read), and the
    server answers /status again while they go on trickling."""
    with _trickled(monkeypatch, deadline_s=1.0) as (live, port, tricklers):
        wait_for(lambda: all(t.closed.is_set() for t in tricklers), timeout_s=20, what="the server to cut the tricklers")
        assert get(port, "/status")[0] == 200


def test_a_new_client_takes_the_place_of_the_oldest_trickler(monkeypatch):
    """Clients that keep reconnecting to trickle would take every slot freed at the deadline: when
    all slots are taken, a new connection closes the oldest one still sending its request."""
    with _trickled(monkeypatch, deadline_s=60.0) as (live, port, tricklers):
        wait_for(lambda: live._httpd._connections == 4, what="4 trickling connections")
        assert [get(port, "/status")[0] for _ in range(3)] == [200, 200, 200]
        wait_for(lambda: tricklers[0].closed.is_set(), what="the oldest trickler to be closed")


@contextlib.contextmanager
def _trickled(monkeypatch, deadline_s):
    """A live view of 4 connection slots and ``deadline_s`` per request, with 4 clients trickling
    their requests into it: ``(server, port, tricklers)``."""
    monkeypatch.setattr(server_module, "MAX_CONNECTIONS", 4)
    monkeypatch.setattr(server_module, "REQUEST_DEADLINE_S", deadline_s)
    live = LiveServer(socket.AF_INET, ("127.0.0.1", 0))
    live.start(INFO)
    port = live.address[1]
    tricklers = [Trickler(port) for _ in range(4)]
    try:
        for t in tricklers:
            t.start()
        yield live, port, tricklers
    finally:
        for t in tricklers:
            t.stop()
        live.close()
