"""`gyrofilter run --serve / --udp` as a user runs it: bad values refused before any output, the
warning for a view open to the network, and a paced replay watched by 16 stream clients (three
never read) while requests that must be refused come in: the run writes exactly the rows that
`replay --out` writes, and a client that reads gets every one of them."""
import argparse
import ipaddress
import json
import os
import re
import socket
import sys
import threading

import numpy as np
import pytest

from gyrofilter.cli import live, main
from gyrofilter.cli.outlets import Outlets
from gyrofilter.view.address import is_loopback
from gyrofilter.view.sink import RunInfo
from gyrofilter.recording import read_recording
from support import REPO
from support.live import EventReader, StalledClient, get, request, start_run, status, wait_for

BUNDLED = REPO / "gyrofilter" / "data" / "mpu6050_static_100s.csv.gz"


@pytest.fixture
def busy_port():
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        sock.listen()
        yield sock.getsockname()[1]


@pytest.mark.parametrize("options, words", [
    (["--serve", "70000"], "--serve '70000': the port must be a whole number from 0 to 65535"),
    (["--serve", "http://x:80"], "--serve 'http://x:80': give [HOST:]PORT without http:// or a path"),
    (["--serve", "999.1.1.1:8000"], "'999.1.1.1' is not an IPv4 address"),
    (["--serve", "BUSY"], "cannot listen there: Address already in use (another program uses this port"),
    (["--udp", "0"], "--udp '0': the port must be a whole number from 1 to 65535"),
    (["--udp", "bad host!:9870"], "'bad host!' is not a host name"),
    (["--udp-format", "teleplot"], "--udp-format: give --udp HOST:PORT too"),
    (["--serve", "8000", "--udp", "127.0.0.1:99999"], "--udp '127.0.0.1:99999': the port must be"),
])
def test_a_bad_value_is_one_line_and_exit_2_before_any_output(tmp_path, capsys, busy_port, options, words):
    options = [str(busy_port) if o == "BUSY" else o for o in options]
    out = tmp_path / "out.csv"
    code = main(["run", "--source", "sim:seed=1,realtime=0,duration=5", "--out", str(out), *options])
    captured = capsys.readouterr()
    assert code == 2 and captured.out == ""
    assert len(captured.err.splitlines()) == 1 and words in captured.err, captured.err
    assert not out.exists()


def test_a_view_open_to_the_network_says_so_in_one_warning_line(tmp_path, capsys):
    code = main(["run", "--source", "sim:seed=1,realtime=0,duration=3", "--serve", "0.0.0.0:0", "--quiet",
                 "--out", str(tmp_path / "out.csv")])
    err = capsys.readouterr().err
    assert code == 0
    warnings = [line for line in err.splitlines() if "warning" in line]
    assert len(warnings) == 1 and "anyone on the network can watch" in warnings[0]
    assert "live view http://0.0.0.0:" in err  # the summary
    # issue 38: only the port was said; now the addresses to open, this machine's own last
    opened = [line for line in err.splitlines() if line.startswith("gyrofilter run: live view on ")]
    assert len(opened) == 1, err
    urls = opened[0].removeprefix("gyrofilter run: live view on ").split(", ")
    port = warnings[0].split(", port ")[1].split(":")[0]
    assert urls[-1] == f"http://127.0.0.1:{port}/"
    for url in urls:
        host = url.removeprefix("http://").rsplit(":", 1)[0]
        assert url.endswith(f":{port}/") and not ipaddress.ip_address(host).is_unspecified, url


def test_a_host_name_that_resolves_to_loopback_keeps_the_view_to_this_machine():
    """`--serve NAME:0` where NAME is this machine's own name (127.0.1.1 on Raspberry Pi OS): the
    address bound decides, so no warning and a request for another Host is refused (issue 37)."""
    name = socket.gethostname()
    try:
        found = socket.getaddrinfo(name, 0, type=socket.SOCK_STREAM)
    except socket.gaierror:
        pytest.skip(f"this machine's name {name!r} does not resolve")
    if not is_loopback(found[0][4][0]) or is_loopback(name):
        pytest.skip(f"this machine's name {name!r} is not a loopback address's")
    args = argparse.Namespace(serve=f"{name}:0", udp=None, udp_format=None, calibration=None)
    with Outlets.open(args) as outlets:
        server, = outlets._outlets
        assert outlets._announcements == [f"gyrofilter run: live view on {server.url} (this machine only)"]
        server.start(RunInfo(source="sim", sample_rate_hz=100.0, block_len=5, output_rate_hz=20.0, preset="recommended"))
        port = server.address[1]
        assert get(port, "/status", host="evil.example")[0] == 421
        assert get(port, "/status", host=name)[0] == 200


def test_sixteen_clients_and_hostile_requests_leave_the_rows_as_replay_writes_them(tmp_path, capsys):
    out = tmp_path / "run.csv"
    proc, port = start_run("--source", f"replay:{BUNDLED},realtime,speed=20", "--out", str(out))
    try:
        readers = [EventReader(port) for _ in range(13)]
        for r in readers:
            r.start()
        stalled = [StalledClient(port) for _ in range(3)]
        wait_for(lambda: status(port)["clients"] == 16, what="16 stream clients")
        refused = {
            "17th client": request(port, b"GET /stream HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")[0],
            "POST": request(port, b"POST /status HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 2\r\n\r\n{}")[0],
            "..": request(port, b"GET /../../../../etc/passwd HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")[0],
            "long line": request(port, b"GET /" + b"x" * 100000 + b" HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")[0],
        }
        assert refused == {"17th client": 503, "POST": 405, "..": 404, "long line": 414}
        assert status(port)["running"] is True
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 0, err
    assert "16 stream clients served" in err and "1 refused (more than 16)" in err
    replayed = tmp_path / "replayed.csv"
    assert main(["replay", str(BUNDLED), "--out", str(replayed)]) == 0
    capsys.readouterr()
    got, want = read_recording(out), read_recording(replayed)
    samples = len(read_recording(BUNDLED))
    assert len(got) == len(want) == (samples - 200) // 5
    np.testing.assert_array_equal(got.t_s, want.t_s)
    np.testing.assert_array_equal(got.gyro_dps, want.gyro_dps)
    for reader in readers:
        reader.join(10)
        assert reader.error is None and reader.status_code == 200
        hello = reader.named("hello")[0]
        streamed = {round(r[0], 6): r[1:] for r in hello["rows"] + [r for e in reader.named("rows") for r in e["rows"]]}
        assert sorted(streamed) == pytest.approx(list(want.t_s))
        np.testing.assert_allclose([streamed[k] for k in sorted(streamed)], want.gyro_dps, atol=1e-6)
        final = reader.named("status")[-1]
        assert final["running"] is False and final["rows_out"] == len(want) and final["samples_in"] == samples
    for client in stalled:
        client.close()


def test_a_run_that_fails_is_one_error_line_with_serve_and_udp(tmp_path, capsys):
    """A source that cannot open: its error alone (the view was bound, not announced)."""
    code = main(["run", "--source", f"replay:{tmp_path / 'missing.csv'}", "--serve", "127.0.0.1:0",
                 "--udp", "127.0.0.1:9"])
    captured = capsys.readouterr()
    assert code == 2 and captured.out == ""
    assert len(captured.err.splitlines()) == 1 and "missing.csv" in captured.err, captured.err


class _Terminal:
    """A real pseudo-terminal (os.openpty) as a stream of the command: ``file`` is its side a
    program writes to (isatty() is True), :meth:`text` what appeared on the screen side, read
    while the command writes so that it never blocks."""

    def __init__(self):
        self.master, slave = os.openpty()
        self.file = os.fdopen(slave, "w", encoding="utf-8")
        self._chunks = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        while True:
            try:
                data = os.read(self.master, 65536)
            except OSError:  # the other side closed
                return
            if not data:
                return
            self._chunks.append(data)

    def text(self):
        self.file.close()
        self._reader.join(5)
        os.close(self.master)
        return b"".join(self._chunks).decode("utf-8").replace("\r\n", "\n")  # the terminal's own line ends


@pytest.mark.parametrize("asked", [[], ["--rows"], ["--out", "-"]])
def test_on_a_terminal_the_view_shows_the_rows_and_its_address_stays_in_sight(monkeypatch, capsys, asked):
    """Issue 38: with --serve on a terminal, 20 rows a second scrolled the line that says where
    the view is out of sight at once. Now the rows go to the terminal only when asked."""
    screen = _Terminal()
    monkeypatch.setattr(sys, "stdout", screen.file)
    code = main(["run", "--source", "sim:seed=1,realtime=0,duration=3", "--serve", "127.0.0.1:0", "--quiet", *asked])
    shown, err = screen.text(), capsys.readouterr().err
    assert code == 0
    assert "gyrofilter run: live view on http://127.0.0.1:" in err
    rows = [line for line in shown.splitlines()  # not the comments, not the column names (the sim's ax, ay, az too)
            if line and not line.startswith("#") and not line.startswith("t,gx,gy,gz")]
    if asked:
        assert len(rows) == 20 and "rows are not printed" not in err  # 3 s at 20 Hz, calibration included
    else:
        assert shown == "" and "the rows are not printed on this terminal (the live view shows them); --rows" in err


def test_rows_and_the_status_line_on_one_terminal_never_share_a_line(monkeypatch):
    """Issue 38: the status line (stderr, rewritten in place with \\r) and the rows (stdout) on one
    terminal gave "CPU 66.9%# calibrated: bias...". Where rows are printed on the terminal, the
    status comes as whole lines between them: each is a whole line of its own (no \r, no row in it).
    A status at every read (interval 0), so that there are many."""
    screen = _Terminal()
    monkeypatch.setattr(sys, "stdout", screen.file)
    monkeypatch.setattr(sys, "stderr", screen.file)
    monkeypatch.setattr(live, "STATUS_INTERVAL_S", 0.0)
    code = main(["run", "--source", "sim:seed=1,duration=1.2", "--calibration-s", "0.2", "--udp", "127.0.0.1:9",
                 "--rows"])  # paced: many reads
    lines = screen.text().splitlines()
    assert code == 0
    status = [line for line in lines if "samples/s" in line]
    rows = [line for line in lines if re.fullmatch(r"[0-9.]+(,-?[0-9.e-]+){3}(,-?[0-9]+){0,3}", line)]
    assert len(status) > 5 and len(rows) == 20, lines  # 1.2 s at 20 Hz after the 0.2-s calibration
    for line in status:
        assert re.fullmatch(r" *[0-9.]+ samples/s \(nominal 100\), [a-z0-9 ,]+, CPU +[0-9.]+%", line), line


@pytest.mark.parametrize("spelling, everywhere", [("0x7f000001", False), ("0x0", True), ("0.0.0.0", True)])
def test_the_address_bound_decides_in_every_spelling(spelling, everywhere):
    """Issue 37 (attack 6): ``--serve 0x7f000001:0`` (inet_aton's hex, which the resolver takes)
    bound 127.0.0.1 and kept the view to this machine; ``0x0:0`` bound every interface but was
    announced as listening "on 0x0" at http://0.0.0.0:PORT/, an address no other machine
    opens: the wildcard too is decided on the address bound."""
    args = argparse.Namespace(serve=f"{spelling}:0", udp=None, udp_format=None, calibration=None)
    with Outlets.open(args) as outlets:
        server, = outlets._outlets
        assert server.loopback_only is not everywhere
        said = " ".join(outlets._announcements)
        if everywhere:
            assert "listens on every network interface" in said and "http://0.0.0.0:" not in said, said
        else:
            assert said == f"gyrofilter run: live view on {server.url} (this machine only)"


def test_a_filter_that_leaves_the_rates_any_gyro_reads_stops_every_outlet_at_its_good_rows(tmp_path, capsys):
    """Attack pass 68: the paper's filter on a fast oscillation grew past +-100000 deg/s (then NaN): `run` to stdout
    and to UDP (teleplot: `gx_dps:...:nan`) passed such rows on and exited 0; plotjuggler's JSON failed with "Out of
    range float values are not JSON compliant", naming nothing; `replay` refused only with --out. Now the filter
    raises at the first such row: every outlet gets the rows before it, those the API returns, and the command
    exits 2 with one line naming the source (or the file's line) and the sample."""
    from gyrofilter import GyroFilter
    from gyrofilter.errors import FilterDiverged
    from gyrofilter.recording import Recording, write_recording

    rng = np.random.default_rng(1)
    n = 40000
    amp, w = rng.uniform(300, 3000), rng.uniform(0.3, 1.5)
    x = rng.normal(0, 0.1, (n, 3))
    x[300:] += amp * np.sin(w * np.arange(n - 300))[:, None]
    x = np.round(x, 4)
    rec_path = tmp_path / "fast.csv"
    t = np.arange(n) / 100.0
    write_recording(rec_path, Recording(columns={"t": t, "gx": x[:, 0], "gy": x[:, 1], "gz": x[:, 2]},
                                        header={"sample_rate_hz": "100", "gyro_unit": "dps"}))
    with pytest.raises(FilterDiverged) as api:
        GyroFilter(100.0, preset="paper").filter(read_recording(rec_path).gyro_dps)
    good, sample = api.value.rows, api.value.sample
    source = f"replay:{rec_path}"
    line = f"gyrofilter: error: source {source}: sample {sample}: the filter's output left the rates any gyro reads"
    receiver = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    receiver.bind(("127.0.0.1", 0))
    receiver.settimeout(1)
    try:
        for fmt in ("teleplot", "plotjuggler"):
            out = tmp_path / f"run_{fmt}.csv"
            code = main(["run", "--source", source, "--preset", "paper", "--quiet", "--out", str(out),
                         "--udp", f"127.0.0.1:{receiver.getsockname()[1]}", "--udp-format", fmt])
            err = capsys.readouterr().err.strip().splitlines()
            assert code == 2 and err[-1].startswith(line) and f"kept the first {len(good)} filtered rows" in err[-1]
            np.testing.assert_allclose(read_recording(out).gyro_dps, good, rtol=1e-8, atol=1e-12)  # (9 digits)
            datagrams = []  # (the kernel may drop some: none is read while the run sends)
            try:
                while True:
                    datagrams.append(receiver.recv(65536).decode())
            except socket.timeout:
                pass
            values = [v for d in datagrams for v in (json.loads(d).values() if fmt == "plotjuggler" else
                                                     (float(x) for line in d.splitlines() for x in line.split(":")[1:]))]
            assert 0 < len(datagrams) <= len(good) and np.all(np.abs(values) <= 1e6), fmt  # one a row, none past them
    finally:
        receiver.close()
    code = main(["run", "--source", source, "--preset", "paper", "--quiet", "--out", "-"])
    printed, err = capsys.readouterr()
    rows = np.array([[float(v) for v in r.split(",")] for r in printed.splitlines() if r[:1].isdigit()])
    assert code == 2 and err.strip() == line + err.strip()[len(line):] and len(err.strip().splitlines()) == 1
    assert len(rows) == len(good) and np.all(np.abs(rows[:, 1:]) <= 1e5)
    code = main(["replay", str(rec_path), "--preset", "paper"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.startswith(f"gyrofilter: error: {rec_path}: line ") and "left the rates any gyro" in err
