"""A gyro streamed over a serial port as text lines (``serial:/dev/ttyUSB0,baud=115200``):
:class:`SerialSource` opens the port (pyserial, imported only here), waits for the device's header
and reads what arrives; the line protocol and its parser are :mod:`gyrofilter.sources.serial.protocol`.

Reading is chunked: each ``read()`` takes every byte waiting (waiting at most 0.1 s for the
first) and hands it to the parser. A disconnected port ends the source (:class:`SourceEnded`
with the reason) after the rows received so far.
"""
from __future__ import annotations

import time
import urllib.parse

import numpy as np

from ...errors import DeviceError, SourceEnded, one_line
from ...inputs import check_number
from ...recording import T_FROM_COUNTER, T_FROM_KEY, T_FROM_LINES
from ..base import Source
from .protocol import LINE_OUTCOMES, LineParser, UnitsConflict

MAX_WAIT_S = 0.1
MIN_BAUD, MAX_BAUD = 50, 12_000_000  # bit/s: the slowest standard rate to the fastest USB-serial chips
MAX_HEADER_TIMEOUT_S = 3600.0


class SerialSource(Source):
    """Read the line protocol from a serial port (pyserial, imported here only).

    ``port`` is a device path or a pyserial URL; ``gyro_unit``/``lsb_per_dps``/``sample_rate_hz``
    are needed only if the device sends no header. Opening waits up to ``header_timeout_s`` for
    the header and the first data line (asking the device with ``?``).

    Parameters
    ----------
    port : str
        Serial device (``/dev/ttyUSB0``) or pyserial URL (``loop://``, ``socket://...``).
    baudrate : int
        Baud rate (bit/s), a whole number in [MIN_BAUD, MAX_BAUD] (50 .. 12000000).
    gyro_unit : str, optional
        Gyro unit if the device sends no header: ``dps``, ``rad/s`` or ``lsb``.
    lsb_per_dps : float, optional
        LSB per deg/s, with ``gyro_unit="lsb"``.
    sample_rate_hz : float, optional
        Sample rate (Hz) if the device sends no header.
    header_timeout_s : float
        Longest wait (s) for the header and the first data line, in (0, 3600]; DeviceError after it.
    serial_port : object, optional
        An open pyserial-like port (``read``, ``write``, ``in_waiting``, ``close``) used instead
        of opening ``port`` (test seam).
    clock : callable
        Monotonic clock (s) for the header deadline (test seam).

    ``read()`` returns rows ``[t, gx, gy, gz(, temp)]`` (see :meth:`LineParser.feed`).
    """

    def __init__(self, port, baudrate=115200, gyro_unit=None, lsb_per_dps=None, sample_rate_hz=None,
                 header_timeout_s=5.0, *, serial_port=None, clock=time.monotonic):
        self.port_name = str(port)
        baudrate = check_number(baudrate, f"{self.port_name}: baud rate (bit/s, e.g. 115200)", low=MIN_BAUD,
                                high=MAX_BAUD, integer=True)
        header_timeout_s = check_number(header_timeout_s, f"{self.port_name}: header_timeout (s)", low=0,
                                        low_open=True, high=MAX_HEADER_TIMEOUT_S)
        self._parser = LineParser(gyro_unit, lsb_per_dps, sample_rate_hz, where=self.port_name)
        self._ended = None
        self._disconnected = False
        self._pending = []
        self._conflict = None  # a UnitsConflict raised by read() once the rows before it are out
        if serial_port is None:
            try:
                import serial
            except ImportError:
                raise DeviceError("pyserial is not installed (pip install pyserial)") from None
            try:
                serial_port = serial.serial_for_url(self.port_name, baudrate=int(baudrate), timeout=MAX_WAIT_S)
            except (serial.SerialException, OSError, ValueError) as exc:
                raise DeviceError(
                    f"{self.port_name}: cannot open the serial port ({one_line(exc)}); check the device name "
                    "(ls /dev/ttyUSB* /dev/ttyACM*), that no other program holds it, and that you are in the dialout group"
                ) from None
        self._port = serial_port
        self._exceptions = _port_exceptions()
        try:
            if self._parser.header is None:
                try:
                    self._port.write(b"?")
                except self._exceptions:
                    pass
            deadline = clock() + float(header_timeout_s)
            while self._parser.header is None or self._parser.fields is None:
                rows = self._receive()
                if len(rows):
                    self._pending.append(rows)
                if self._conflict is not None:  # the units changed in this read: its rows first (read())
                    if not self._pending:
                        raise self._conflict
                    break
                if self._ended is not None:
                    raise DeviceError(f"{self.port_name}: {self._ended} before the stream started{self._no_sample()}")
                if clock() > deadline:
                    if self._parser.header is None:
                        raise DeviceError(
                            f"{self.port_name}: no '# gyrofilter-serial: 1 ...' header within {header_timeout_s:g} s; "
                            "give the units as options (unit=lsb,lsb_per_dps=131,rate=100 or --gyro-unit/--lsb-per-dps/--sample-rate-hz) "
                            "or check the baud rate and the sketch"
                        )
                    raise DeviceError(f"{self.port_name}: no sample within {header_timeout_s:g} s"
                                      f"{self._no_sample() or ': no data line came'}")
        except BaseException:
            self._close_port()
            raise
        # the device's first header (a later one in the same burst changed `sensor=`...: noted), else the options'
        self.header = dict(self._parser.device_header or self._parser.header)
        self.sample_rate_hz = self._parser.sample_rate_hz
        self.gyro_unit = self.header["gyro_unit"]
        self.lsb_per_dps = float(self.header["lsb_per_dps"]) if self.gyro_unit == "lsb" else None
        self.header.setdefault("sensor", "serial device")
        self.header["serial_port"] = self.port_name
        if self._parser.fields:  # t = counter / rate, or lines of a sample / rate: its jumps are samples the device lost
            self.header[T_FROM_KEY] = T_FROM_COUNTER if "counter" in self._parser.fields else T_FROM_LINES
        self.header["start_time_utc"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        self.columns = self._parser.columns
        self.stats = self._parser.stats
        self.stats.setdefault("disconnects", 0)

    def _no_sample(self):
        """What the lines received before the stream started were, none of them a sample (the parser's counts,
        :data:`~gyrofilter.sources.serial.protocol.LINE_OUTCOMES`, and its first note of a skipped line), or ''
        when no line came: "no data lines after the header" was said of 800 lines of gx,gy,gz and no header."""
        stats = self._parser.stats
        if not stats.get("lines"):
            return ""
        counts = ", ".join(f"{stats[kind]} {kind.replace('_', ' ')}" for kind in LINE_OUTCOMES if stats.get(kind))
        skipped = next((note for note in self._parser.notes if note.startswith("serial: skipped")), None)
        return f" ({stats['lines']} lines received, none a sample: {counts}{'; ' + skipped if skipped else ''})"

    def _receive(self):
        """One chunk from the port through the parser; a port error ends the stream."""
        try:
            waiting = self._port.in_waiting
            data = self._port.read(waiting or 1)
            if data and not waiting:
                more = self._port.in_waiting
                if more:
                    data += self._port.read(more)
        except self._exceptions as exc:
            self._ended = f"serial port disconnected ({one_line(exc)})"
            self._disconnected = True
            return self._parser.finish()
        if not data:
            return self._parser._empty()
        try:
            return self._parser.feed(data)
        except UnitsConflict as exc:  # the stream ends at the header: the rows before it first
            self._conflict = exc
            return exc.rows

    def read(self):
        """Rows that arrived (waits at most 0.1 s); SourceEnded once the port is gone.

        Returns an array of shape (n, len(columns)): t (s), gyro in ``gyro_unit``, temp (deg C);
        shape (0, len(columns)) when nothing arrived. After a disconnect (or ``close()``) the rows
        received so far come first, then :class:`gyrofilter.errors.SourceEnded` saying why.
        """
        if self._pending:
            rows = np.concatenate(self._pending)
            self._pending = []
            return rows
        if self._conflict is not None:
            raise self._conflict
        if self._ended is not None:
            self.stats["disconnects"] = int(self._disconnected)
            raise SourceEnded(f"{self.port_name}: {self._ended} after {self.stats['samples']} samples; everything received is kept")
        return self._receive()

    def finish(self):
        """At a stop (Ctrl-C), the stream ends here: the row of a last line whose counter jumped,
        which waited for the next line, as at a disconnect (:meth:`LineParser.finish`; a cut
        line counted), after any rows not yet read (those that came with the header); nothing
        more after the port is gone (its held line was given out then)."""
        rows = np.concatenate([*self._pending, self._parser.finish()])
        self._pending = []
        return rows

    def pop_notes(self):
        """Events since the last call (gaps, restarts, skipped lines, device messages)."""
        return self._parser.pop_notes()

    def _close_port(self):
        port, self._port = self._port, None
        if port is not None:
            try:
                port.close()
            except Exception:  # noqa: BLE001 - closing a vanished port must not mask the real error
                pass

    def _close(self):
        self._close_port()
        if self._ended is None:
            self._ended = "source closed"


def written_files(port):
    """The files opening ``port`` writes: a pyserial ``spy://`` URL's ``file=`` (its first, as
    pyserial reads it: ``serial.urlhandler.protocol_spy``), which pyserial opens for writing, emptying
    it, before the port opens; none for any other port. The commands check it as an output."""
    if "://" not in port or port.lower().split("://", 1)[0] != "spy":  # pyserial's own test of a URL's protocol
        return []
    return urllib.parse.parse_qs(urllib.parse.urlsplit(port).query, True).get("file", [])[:1]


def _port_exceptions():
    try:
        import serial

        return (serial.SerialException, OSError)
    except ImportError:
        return (OSError,)


