"""``--serve`` and ``--udp`` of ``gyrofilter run``: where the rows go besides the output (the live
view in a browser, a UDP stream to PlotJuggler or Teleplot; :mod:`gyrofilter.view`).

:meth:`Outlets.open` checks the values and binds or resolves them before the source is opened
and before anything is written, so a bad value (a port out of range or in use, a bad host) is
one refusal line and exit 2. The run loop calls :meth:`Outlets.start` once, which says on stderr
where the view is (or, when it listens beyond this machine, one warning line), and
:meth:`Outlets.feed` after each read; the outlets never make it wait. Leaving the ``with``
block closes them, and their summaries go to stderr after a run that did not fail.
"""
import errno
import socket

from ..errors import SettingsError
from ..view.address import is_wildcard, loopback, machine_addresses, resolve, split_address, url
from ..view.server import LiveServer
from ..view.sink import RunInfo, Step
from ..view.udp import FORMATS, UdpSender
from . import console


def add_arguments(parser):
    parser.add_argument("--serve", metavar="[HOST:]PORT",
                        help="serve a live view while it runs: open http://HOST:PORT/ in a browser (HOST defaults "
                             "to 127.0.0.1, this machine only; 0.0.0.0 lets anyone on the network watch; port 0: any "
                             "free port); /stream and /status for programs (docs/live.md)")
    parser.add_argument("--udp", metavar="HOST:PORT",
                        help="send each filtered row as a UDP datagram to HOST:PORT (HOST defaults to 127.0.0.1)")
    parser.add_argument("--udp-format", choices=FORMATS,
                        help="datagram format of --udp: plotjuggler (JSON, PlotJuggler's UDP server; the default) or "
                             "teleplot (name:timestamp_ms:value lines)")


class Outlets:
    """The outlets a run was given (none, the live view, a UDP stream, or both); see the module
    docstring. ``calibration_loaded``: the filter starts from a saved calibration."""

    def __init__(self, outlets, calibration_loaded, announcements=(), show_rows=""):
        self._outlets = outlets
        self._calibration_loaded = calibration_loaded
        self._announcements = list(announcements)
        #: what shows the rows besides the output, in words ("the live view"), "" for nothing
        self.show_rows = show_rows

    @classmethod
    def open(cls, args):
        if args.udp_format is not None and args.udp is None:
            raise SettingsError("--udp-format: give --udp HOST:PORT too (where to send the datagrams)")
        serve = udp = None  # every value is checked before anything is bound or said
        if args.serve is not None:
            host, port = split_address(args.serve, "--serve")
            serve = host, resolve(host, port, "--serve", socket.SOCK_STREAM)
        if args.udp is not None:
            host, port = split_address(args.udp, "--udp", min_port=1)
            udp = resolve(host, port, "--udp", socket.SOCK_DGRAM)
        outlets, announcements = [], []
        if udp is not None:
            try:
                outlets.append(UdpSender(*udp, args.udp_format or FORMATS[0], args.udp))
            except OSError as exc:
                raise SettingsError(f"--udp {args.udp}: cannot send there: {_why(exc)}") from None
        if serve is not None:
            try:
                server, lines = _open_server(args.serve, *serve)
            except BaseException:
                for outlet in outlets:
                    outlet.close()
                raise
            outlets.append(server)
            announcements.extend(lines)
        shown = [what for what, given in (("the live view", serve), ("the UDP stream", udp)) if given is not None]
        return cls(outlets, args.calibration is not None, announcements, " and ".join(shown))

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        """Close the outlets; their summaries go to stderr after a run that did not fail (a failure
        is one error line)."""
        for outlet in self._outlets:
            summary = outlet.close()
            if summary and exc_type is None:
                console.say(f"gyrofilter run: {summary}")
        return False

    def start(self, source_spec, sample_rate_hz, filt):
        """Start serving once the source is open and the filter made; say where the view is."""
        for line in self._announcements:
            console.say(line)
        info = RunInfo(source=source_spec, sample_rate_hz=float(sample_rate_hz), block_len=filt.settings.block_len,
                       output_rate_hz=filt.output_rate_hz, preset=filt.preset)
        for outlet in self._outlets:
            outlet.start(info)

    def feed(self, t_s, gyro_dps, temp_c, rows_t_s, rows_dps, *, samples_in, rows_out, source, filt):
        """One read of the run loop: the samples (times, deg/s, temperatures or None), the rows
        the filter made of them, and the totals so far."""
        if not self._outlets:
            return
        if filt.calibrating:
            calibration = "calibrating"
        else:
            calibration = "loaded" if self._calibration_loaded else "calibrated"
        step = Step(t_s=t_s, gyro_dps=gyro_dps, temp_c=temp_c, rows_t_s=rows_t_s, rows_dps=rows_dps,
                    samples_in=samples_in, rows_out=rows_out, lost_samples=int(source.stats.get("lost_samples", 0)),
                    rejected_outliers=tuple(int(r) for r in filt.rejected), calibration=calibration,
                    bias_dps=filt.bias_dps)
        for outlet in self._outlets:
            outlet.feed(step)


def _open_server(text, host, resolved):
    """The live view listening at ``text`` (--serve's [HOST:]PORT: ``host`` and its ``resolved``
    (family, sockaddr)), and the lines that tell the user where it is: listening on every
    interface (0.0.0.0), the addresses to open, this machine's first (:func:`machine_addresses`)."""
    family, sockaddr = resolved
    try:
        server = LiveServer(family, sockaddr, name=host)
    except OSError as exc:
        raise SettingsError(f"--serve {text}: cannot listen there: {_why(exc)}") from None
    if server.loopback_only:  # the address bound decides, not the name (raspberrypi -> 127.0.1.1)
        return server, [f"gyrofilter run: live view on {server.url} (this machine only)"]
    everywhere = is_wildcard(server.address[0])  # the address bound, as for loopback (0x0 and 0 are 0.0.0.0)
    where = "every network interface" if everywhere else host
    port = server.address[1]
    urls = [server.url]
    if everywhere:
        urls = [url(address, port) for address in machine_addresses(family)] + [url(loopback(family), port)]
    return server, [f"gyrofilter run: warning: the live view listens on {where}, port {port}: anyone "
                    "on the network can watch this sensor (read-only); use 127.0.0.1 to keep it to this machine",
                    f"gyrofilter run: live view on {', '.join(urls)}"]


_BIND_HINTS = {errno.EADDRINUSE: "another program uses this port; choose another, or 0 for any free port",
               errno.EADDRNOTAVAIL: "no interface of this machine has that address",
               errno.EACCES: "ports below 1024 need root; choose one above 1024"}


def _why(exc):
    """An OSError of bind() in words, with what to do for the usual ones."""
    hint = _BIND_HINTS.get(exc.errno)
    return f"{exc.strerror or exc}" + (f" ({hint})" if hint else "")
