"""`gyrofilter run --udp`: one datagram per filtered row, received on a real UDP socket on
127.0.0.1, in PlotJuggler's JSON and in Teleplot's lines."""
import json
import re
import socket
import threading

import numpy as np
import pytest

from gyrofilter.cli import main
from gyrofilter.recording import Recording, read_recording, write_recording
from gyrofilter.view.sink import Step
from gyrofilter.view.udp import UdpSender, plotjuggler_datagram, teleplot_datagram
from support import REPO

BUNDLED = REPO / "gyrofilter" / "data" / "mpu6050_static_100s.csv.gz"
TELEPLOT_LINE = re.compile(r"^(g[xyz]_dps):(-?\d+\.\d{3}):(\S+)$")


class Receiver(threading.Thread):
    """A UDP socket on 127.0.0.1 that collects every datagram until stopped (and drained)."""

    def __init__(self):
        super().__init__(daemon=True)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.datagrams = []
        self.done = threading.Event()

    def run(self):
        while True:  # until stopped and nothing came for 0.2 s
            try:
                self.datagrams.append(self.sock.recv(65536))
            except socket.timeout:
                if self.done.is_set():
                    break
        self.sock.close()

    def stop(self):
        self.done.set()
        self.join(5)
        return self.datagrams


def rows_step(t, rows):
    return Step(t_s=np.empty(0), gyro_dps=np.empty((0, 3)), temp_c=None, rows_t_s=np.asarray(t),
                rows_dps=np.asarray(rows), samples_in=0, rows_out=len(t), lost_samples=0, rejected_outliers=(0, 0, 0),
                calibration="calibrated", bias_dps=(0.0, 0.0, 0.0))


def test_the_two_formats():
    assert json.loads(plotjuggler_datagram(12.345, [0.0123, -4.5e-06, 1 / 3])) == {
        "timestamp": 12.345, "gx_dps": 0.0123, "gy_dps": -4.5e-06, "gz_dps": 0.333333333}
    assert teleplot_datagram(12.345, [0.0123, -4.5e-06, 1 / 3]).decode().split("\n") == [
        "gx_dps:12345.000:0.0123", "gy_dps:12345.000:-4.5e-06", "gz_dps:12345.000:0.333333333"]


@pytest.mark.parametrize("fmt", ["plotjuggler", "teleplot"])
def test_a_datagram_per_row_on_a_real_socket(fmt):
    receiver = Receiver()
    receiver.start()
    rng = np.random.default_rng(1)
    t = 2.0 + 0.05 * np.arange(200)
    rows = 0.1 * rng.standard_normal((200, 3))
    sender = UdpSender(socket.AF_INET, ("127.0.0.1", receiver.port), fmt, f"127.0.0.1:{receiver.port}")
    for a in range(0, 200, 17):
        sender.feed(rows_step(t[a : a + 17], rows[a : a + 17]))
    summary = sender.close()
    got = receiver.stop()
    assert summary == f"udp {fmt} to 127.0.0.1:{receiver.port}: 200 datagrams sent, 0 dropped"
    assert len(got) == 200
    for datagram, t_s, row in zip(got, t, rows):
        if fmt == "plotjuggler":
            d = json.loads(datagram)
            assert d["timestamp"] == t_s
            np.testing.assert_allclose([d["gx_dps"], d["gy_dps"], d["gz_dps"]], row, rtol=1e-8)
        else:
            lines = [TELEPLOT_LINE.match(line).groups() for line in datagram.decode().split("\n")]
            assert [name for name, _, _ in lines] == ["gx_dps", "gy_dps", "gz_dps"]
            assert all(float(ms) == pytest.approx(1000 * t_s) for _, ms, _ in lines)
            np.testing.assert_allclose([float(v) for _, _, v in lines], row, rtol=1e-8)


def test_nobody_listening_is_no_error():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    sender = UdpSender(socket.AF_INET, ("127.0.0.1", port), "plotjuggler", f"127.0.0.1:{port}")
    sender.feed(rows_step([1.0, 1.1], [[0, 0, 0], [1, 1, 1]]))
    assert sender.close().endswith(": 2 datagrams sent, 0 dropped")


def test_a_broadcast_address_is_sent_to():
    """Issue 37: `--udp 255.255.255.255:PORT` dropped every datagram (no SO_BROADCAST: EACCES), said
    only in the final summary. A socket bound to every interface of this machine gets them."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as listener:
        listener.bind(("0.0.0.0", 0))
        listener.settimeout(5)
        port = listener.getsockname()[1]
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
            try:
                probe.sendto(b"probe", ("255.255.255.255", port))
                listener.recv(100)
            except OSError as exc:
                pytest.skip(f"no broadcast on this machine's network ({exc})")
        sender = UdpSender(socket.AF_INET, ("255.255.255.255", port), "plotjuggler", f"255.255.255.255:{port}")
        sender.feed(rows_step([1.0, 1.1], [[0, 0, 0], [1, 1, 1]]))
        assert sender.close().endswith(": 2 datagrams sent, 0 dropped")
        assert [json.loads(listener.recv(1000))["timestamp"] for _ in range(2)] == [1.0, 1.1]


def test_run_sends_the_rows_it_writes(tmp_path, capsys):
    """A paced replay of 20 s of the bundled recording: the datagrams are the rows of --out."""
    rec = read_recording(BUNDLED)
    short = tmp_path / "short.csv"
    write_recording(short, Recording({c: v[:2000] for c, v in rec.columns.items()}, rec.header))
    receiver = Receiver()
    receiver.start()
    out = tmp_path / "run.csv"
    code = main(["run", "--source", f"replay:{short},realtime,speed=10", "--udp", f"127.0.0.1:{receiver.port}",
                 "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    got = receiver.stop()
    assert code == 0, err
    written = read_recording(out)
    assert len(written) == (2000 - 200) // 5 == len(got)
    assert f"udp plotjuggler to 127.0.0.1:{receiver.port}: 360 datagrams sent, 0 dropped" in err
    sent = [json.loads(d) for d in got]
    np.testing.assert_array_equal([d["timestamp"] for d in sent], written.t_s)
    np.testing.assert_allclose([[d["gx_dps"], d["gy_dps"], d["gz_dps"]] for d in sent], written.gyro_dps, rtol=1e-8)
