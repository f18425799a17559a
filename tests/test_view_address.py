"""`[HOST:]PORT` of --serve and --udp: what is taken, and every refusal naming the option and value."""
import socket

import pytest

from gyrofilter.errors import SettingsError
from gyrofilter.view.address import is_loopback, is_wildcard, resolve, split_address


@pytest.mark.parametrize("text, expected", [
    ("8000", ("127.0.0.1", 8000)),
    ("0", ("127.0.0.1", 0)),
    ("127.0.0.1:65535", ("127.0.0.1", 65535)),
    ("0.0.0.0:8000", ("0.0.0.0", 8000)),
    ("localhost:80", ("localhost", 80)),
    ("pi-4.local:8000", ("pi-4.local", 8000)),
    ("[::1]:8000", ("::1", 8000)),
    ("[::]:9870", ("::", 9870)),
])
def test_accepted(text, expected):
    assert split_address(text, "--serve") == expected


@pytest.mark.parametrize("text, words", [
    ("65536", "from 0 to 65535, got '65536'"),
    ("-1", "from 0 to 65535, got '-1'"),
    ("80.5", "from 0 to 65535, got '80.5'"),
    ("1e3", "from 0 to 65535, got '1e3'"),
    ("８０００", "from 0 to 65535"),  # other scripts' digits
    ("", "from 0 to 65535, got ''"),
    ("127.0.0.1:", "got ''"),
    ("127.0.0.1:99999999999999999999", "from 0 to 65535"),
    (":8000", "the host is empty"),
    ("999.1.1.1:8000", "'999.1.1.1' is not an IPv4 address"),
    ("1.2.3:8000", "'1.2.3' is not an IPv4 address"),
    ("bad_host!:8000", "'bad_host!' is not a host name or address"),
    ("-x:8000", "'-x' is not a host name"),
    ("a..b:8000", "'a..b' is not a host name"),
    ("hôte:8000", "is not a host name"),
    ("::1:8000", "an IPv6 address goes in brackets"),
    ("[::1]8000", "expected [IPV6]:PORT"),
    ("[nothing]:8000", "'nothing' is not an IPv6 address"),
    ("[::1", "expected [IPV6]:PORT"),
])
def test_refused_with_the_option_and_the_value(text, words):
    with pytest.raises(SettingsError) as info:
        split_address(text, "--serve")
    message = str(info.value)
    assert message.startswith("--serve ") and words in message and "\n" not in message


def test_a_udp_destination_needs_a_port_above_0():
    assert split_address("9870", "--udp", min_port=1) == ("127.0.0.1", 9870)
    with pytest.raises(SettingsError, match="--udp '0': the port must be a whole number from 1 to 65535"):
        split_address("0", "--udp", min_port=1)


def test_resolve_gives_a_socket_address_or_one_line():
    assert resolve("127.0.0.1", 8000, "--serve", socket.SOCK_STREAM) == (socket.AF_INET, ("127.0.0.1", 8000))
    with pytest.raises(SettingsError, match=r"^--udp no-such-host\.invalid:9870: cannot find the host"):
        resolve("no-such-host.invalid", 9870, "--udp", socket.SOCK_DGRAM)


def test_loopback_and_wildcard():
    assert is_loopback("localhost") and is_loopback("127.1.2.3") and is_loopback("::1")
    assert not is_loopback("0.0.0.0") and not is_loopback("pi.local") and not is_loopback("192.0.2.1")
    assert is_wildcard("0.0.0.0") and is_wildcard("::") and not is_wildcard("127.0.0.1") and not is_wildcard("localhost")


def test_an_ipv4_mapped_loopback_address_is_loopback():
    """Attack pass (issue 37): ``--serve [::ffff:127.0.0.1]:PORT`` binds an address only this
    machine reaches, but was taken for a public one: the Host check was off (a page at
    evil.example could read the sensor through DNS rebinding) and the warning said the
    network could watch. An IPv4-mapped address is judged as the IPv4 address it maps."""
    assert is_loopback("::ffff:127.0.0.1") and is_loopback("::ffff:127.0.1.1")
    assert not is_loopback("::ffff:192.0.2.1") and not is_loopback("::ffff:0.0.0.0")
    assert is_wildcard("::ffff:0.0.0.0") and not is_wildcard("::ffff:127.0.0.1")


def test_a_url_is_not_an_address():
    with pytest.raises(SettingsError, match=r"--serve 'http://127.0.0.1:8000/': give \[HOST:\]PORT without http://"):
        split_address("http://127.0.0.1:8000/", "--serve")
