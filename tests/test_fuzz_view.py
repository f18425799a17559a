"""Fuzz of the live view's inputs (issue 25): the ``[HOST:]PORT`` of --serve and --udp, and what a
client may send to the server.

(a) any text is either an address (a host that is a name or an IP address, a port in range) or a
    SettingsError of one line that names the option;
(b) any bytes sent as a request get an answer that is a refusal (or the page or status for a
    well-formed GET of theirs), never a file from elsewhere, and the server keeps answering.

A few derandomized examples by default, many more under ``-m slow``.
"""
import ipaddress
import re
import socket

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gyrofilter.errors import SettingsError
from gyrofilter.view.address import split_address
from gyrofilter.view.server import LiveServer
from gyrofilter.view.sink import RunInfo
from support.live import get, request

FAST = dict(deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
ADDRESS_TEXTS = st.one_of(
    st.text(max_size=40),
    st.from_regex(r"\[?[0-9a-fA-F:.]{0,20}\]?:?-?[0-9]{0,7}", fullmatch=True),
    st.from_regex(r"[a-z0-9.\-_ ]{0,20}:[0-9]{0,6}", fullmatch=True),
    st.builds(lambda h, p: f"{h}:{p}", st.sampled_from(["127.0.0.1", "0.0.0.0", "localhost", "[::1]", "", "a.b"]),
              st.integers(-10, 70000)),
)
HOST_NAME = re.compile(r"^[A-Za-z0-9.-]+$")


def check_address(text):
    try:
        host, port = split_address(text, "--udp", min_port=1)
    except SettingsError as exc:
        message = str(exc)
        assert message.startswith("--udp ") and "\n" not in message and len(message) < 300
        return
    assert 1 <= port <= 65535
    try:
        ipaddress.ip_address(host)
    except ValueError:
        assert HOST_NAME.match(host) and not re.fullmatch(r"[0-9.]+", host)


@settings(max_examples=200, **FAST)
@given(ADDRESS_TEXTS)
def test_an_address_text_is_an_address_or_one_line(text):
    check_address(text)


@pytest.mark.slow
@settings(max_examples=5000, **FAST)
@given(ADDRESS_TEXTS)
def test_an_address_text_is_an_address_or_one_line_many(text):
    check_address(text)


REQUESTS = st.one_of(
    st.binary(max_size=300),
    st.builds(lambda m, p, v, h: f"{m} {p} {v}\r\n{h}\r\n\r\n".encode("utf-8", "surrogateescape"),
              st.sampled_from(["GET", "HEAD", "POST", "PUT", "DELETE", "get", "BREW", "GET GET", ""]),
              st.one_of(st.sampled_from(["/", "/status", "/view.js", "/../etc/passwd", "//etc/passwd", "/%2e%2e/",
                                         "/stream?x=1", "*", "/view.css/..", "C:\\Windows"]),
                        st.text(max_size=30)),
              st.sampled_from(["HTTP/1.1", "HTTP/1.0", "HTTP/2.0", "HTTP/9", "", "FTP/1.0"]),
              st.sampled_from(["Host: 127.0.0.1", "Host: evil.example", "", "Host:", "X: " + "y" * 70000])),
)


@pytest.fixture(scope="module")
def server():
    live = LiveServer(socket.AF_INET, ("127.0.0.1", 0))
    live.start(RunInfo(source="sim", sample_rate_hz=100.0, block_len=5, output_rate_hz=20.0, preset="paper"))
    yield live
    live.close()


def check_request(server, raw):
    port = server.address[1]
    _, answer = request(port, raw, timeout_s=15)
    head = answer[:300]
    assert b"root:" not in answer and b"[project]" not in answer and b"import " not in answer
    if head.startswith(b"HTTP/1.0 200"):
        # only a GET or HEAD of one of the fixed paths is served
        assert re.match(rb"(GET|HEAD) (/|/status|/view\.js|/view\.css|/stream)(\?\S*)? HTTP/1\.[01]\r\n", raw), raw[:80]
    else:
        assert head == b"" or re.match(rb"(HTTP/1\.0 )?(400|404|405|414|421|431|503|505)\b", head), head
    assert get(port, "/status")[0] == 200


@settings(max_examples=60, **FAST)
@given(REQUESTS)
def test_any_request_is_answered_or_refused_and_the_server_goes_on(server, raw):
    if b"/stream" in raw and raw.startswith(b"GET /stream") and b"Host: 127.0.0.1" in raw:
        return  # a valid stream request stays open: the server tests cover it
    check_request(server, raw)


@pytest.mark.slow
@settings(max_examples=1000, **FAST)
@given(REQUESTS)
def test_any_request_is_answered_or_refused_and_the_server_goes_on_many(server, raw):
    if b"/stream" in raw and raw.startswith(b"GET /stream") and b"Host: 127.0.0.1" in raw:
        return
    check_request(server, raw)
