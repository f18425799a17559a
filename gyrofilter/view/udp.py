"""``gyrofilter run --udp HOST:PORT``: each filtered row as one UDP datagram, for PlotJuggler or
Teleplot on this machine or a laptop on the network (docs/live.md, "UDP streams").

Formats (``--udp-format``):

- ``plotjuggler`` (default): one JSON object, what PlotJuggler's "UDP Server" reads with its JSON
  parser (default port 9870; tick "use field [timestamp] if available" to plot on the sensor's
  clock)::

      {"timestamp": 12.345, "gx_dps": 0.0123, "gy_dps": -0.0045, "gz_dps": 0.0007}

- ``teleplot``: Teleplot's ``name:timestamp_ms:value`` lines, one per axis, in one datagram
  (Teleplot listens on port 47269)::

      gx_dps:12345.000:0.0123
      gy_dps:12345.000:-0.0045
      gz_dps:12345.000:0.0007

``timestamp`` is the row's ``t`` (s, the sensor's clock, as in the output file); rates in deg/s
with 9 significant digits. The socket never blocks: a datagram the system cannot take at once is
dropped and counted, and so is one refused by the network (the summary names the last error).
An IPv4 socket may broadcast (``SO_BROADCAST``: 255.255.255.255 or a subnet's broadcast
address, which the address alone does not tell from a host's), and the destination is checked
when the sender is made (a UDP ``connect`` on a socket of its own: no route there is an OSError
before the run, not every datagram dropped after it).
"""
from __future__ import annotations

import json
import socket

FORMATS = ("plotjuggler", "teleplot")
NAMES = ("gx_dps", "gy_dps", "gz_dps")


def plotjuggler_datagram(t_s, rate_dps):
    """The JSON datagram of one row (``t_s``: s; ``rate_dps``: x, y, z in deg/s)."""
    return json.dumps({"timestamp": t_s, **{n: float(f"{v:.9g}") for n, v in zip(NAMES, rate_dps)}},
                      separators=(",", ":"), allow_nan=False).encode()


def teleplot_datagram(t_s, rate_dps):
    """The Teleplot lines of one row: ``name:timestamp_ms:value`` per axis."""
    return "\n".join(f"{n}:{t_s * 1000.0:.3f}:{v:.9g}" for n, v in zip(NAMES, rate_dps)).encode()


ENCODERS = {"plotjuggler": plotjuggler_datagram, "teleplot": teleplot_datagram}


class UdpSender:
    """An outlet of ``gyrofilter run`` (:mod:`gyrofilter.view.sink`): a datagram per filtered row
    to ``sockaddr`` (from :func:`gyrofilter.view.address.resolve`) in ``fmt`` (one of
    :data:`FORMATS`); ``name``: HOST:PORT as given, for the summary."""

    def __init__(self, family, sockaddr, fmt, name):
        self._encode = ENCODERS[fmt]
        self.fmt = fmt
        self.name = name
        self.sockaddr = sockaddr
        self.sent = 0
        self.dropped = 0
        self.last_error = None
        self._sock = _datagram_socket(family)
        try:
            with _datagram_socket(family) as probe:  # sends nothing: the route and the permission to send there
                probe.connect(sockaddr)
        except OSError:
            self._sock.close()
            raise
        self._sock.setblocking(False)

    def start(self, info):
        """Nothing to prepare: the socket is open."""

    def feed(self, step):
        for t_s, row in zip(step.rows_t_s.tolist(), step.rows_dps.tolist()):
            try:
                self._sock.sendto(self._encode(t_s, row), self.sockaddr)
                self.sent += 1
            except (BlockingIOError, InterruptedError):
                self.dropped += 1
            except OSError as exc:  # no route, refused by a firewall, ...: the run goes on
                self.dropped += 1
                self.last_error = exc.strerror or str(exc)

    def close(self):
        self._sock.close()
        text = f"udp {self.fmt} to {self.name}: {self.sent} datagrams sent, {self.dropped} dropped"
        return text + (f" (last error: {self.last_error})" if self.last_error else "")


def _datagram_socket(family):
    """A UDP socket of ``family``; an IPv4 one may send to a broadcast address."""
    sock = socket.socket(family, socket.SOCK_DGRAM)
    if family == socket.AF_INET:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
    return sock
