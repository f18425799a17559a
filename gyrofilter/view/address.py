"""``[HOST:]PORT`` as ``--serve`` and ``--udp`` take it: checked, then resolved.

HOST is an IPv4 address (``127.0.0.1``, ``0.0.0.0``), an IPv6 address in brackets (``[::1]``)
or a host name (letters, digits, ``-`` and ``.``, RFC 1123); without it, ``127.0.0.1``. PORT is
a whole number written in digits. Anything else is refused with a SettingsError naming the
option and the value, before a name is looked up (a string of digits and dots that is no IPv4
address never reaches the resolver).
"""
from __future__ import annotations

import ipaddress
import re
import socket

from ..errors import SettingsError
from ..inputs import quote

DEFAULT_HOST = "127.0.0.1"
MAX_PORT = 65535
_LABEL = re.compile(r"^(?!-)[A-Za-z0-9-]{1,63}(?<!-)$")
MAX_HOST_CHARS = 253


def split_address(text, option, *, min_port=0):
    """``(host, port)`` of ``text`` (``[HOST:]PORT``) for ``option`` (its name, for messages);
    ``port`` in [``min_port``, 65535]. SettingsError for anything else."""
    text = str(text)
    where = f"{option} {quote(text)}"
    if "/" in text:
        raise SettingsError(f"{where}: give [HOST:]PORT without http:// or a path, e.g. 127.0.0.1:8000")
    host, port_text = DEFAULT_HOST, text
    if text.startswith("["):
        inside, bracket, rest = text[1:].partition("]")
        if not bracket or not rest.startswith(":"):
            raise SettingsError(f"{where}: expected [IPV6]:PORT, e.g. [::1]:8000")
        host, port_text = inside, rest[1:]
        _check_ipv6(host, where)
    elif ":" in text:
        host, _, port_text = text.rpartition(":")
        _check_host(host, where)
    if not port_text.isascii() or not port_text.isdigit() or len(port_text) > 5 or not min_port <= int(port_text) <= MAX_PORT:
        raise SettingsError(f"{where}: the port must be a whole number from {min_port} to {MAX_PORT}, "
                            f"got {quote(port_text)}")
    return host, int(port_text)


def _check_ipv6(host, where):
    try:
        ipaddress.IPv6Address(host)
    except ValueError:
        raise SettingsError(f"{where}: {quote(host)} is not an IPv6 address") from None


def _check_host(host, where):
    if not host:
        raise SettingsError(f"{where}: the host is empty (give HOST:PORT, or PORT alone for {DEFAULT_HOST})")
    if ":" in host:
        raise SettingsError(f"{where}: an IPv6 address goes in brackets, e.g. [::1]:8000")
    if re.fullmatch(r"[0-9.]+", host):
        try:
            ipaddress.IPv4Address(host)
        except ValueError:
            raise SettingsError(f"{where}: {quote(host)} is not an IPv4 address") from None
        return
    labels = host.removesuffix(".").split(".")
    if not host.isascii() or len(host) > MAX_HOST_CHARS or not all(_LABEL.match(label) for label in labels):
        raise SettingsError(f"{where}: {quote(host)} is not a host name or address "
                            "(letters, digits, '-' and '.', e.g. localhost, 127.0.0.1, [::1])")


def resolve(host, port, option, kind):
    """``(family, sockaddr)`` of ``host``:``port`` for a socket of ``kind`` (socket.SOCK_STREAM or
    SOCK_DGRAM): the resolver's first answer. SettingsError naming ``option`` when it has none."""
    try:
        found = socket.getaddrinfo(host, port, type=kind)
    except (socket.gaierror, UnicodeError) as exc:
        raise SettingsError(f"{option} {host}:{port}: cannot find the host {quote(host)} "
                            f"({getattr(exc, 'strerror', None) or exc})") from None
    family, _, _, _, sockaddr = found[0]
    return family, sockaddr


def _ip(host):
    """The address ``host`` writes (an IPv4-mapped IPv6 address, ``::ffff:127.0.0.1``, as the
    IPv4 address it maps: RFC 4291 section 2.5.5.2, what a socket bound to it reaches), or None
    for a name."""
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        return None
    return getattr(address, "ipv4_mapped", None) or address


def is_loopback(host):
    """True when ``host`` can only be reached from this machine (127.0.0.0/8, ::1, localhost, and
    127.0.0.0/8 mapped into IPv6, ``::ffff:127.0.0.1``)."""
    if host == "localhost":
        return True
    address = _ip(host)
    return address is not None and address.is_loopback


def is_wildcard(host):
    """True for the addresses that mean every interface of this machine (0.0.0.0, ::, ::ffff:0.0.0.0)."""
    address = _ip(host)
    return address is not None and address.is_unspecified


#: documentation addresses (RFC 5737, RFC 3849) that a UDP socket is connected to, to learn which
#: address of this machine the default route goes out from: connecting a UDP socket sends nothing
_PROBE = {socket.AF_INET: ("192.0.2.1", 9), socket.AF_INET6: ("2001:db8::1", 9)}


def url(host, port):
    """``http://HOST:PORT/``, an IPv6 address in brackets."""
    return f"http://{f'[{host}]' if ':' in host else host}:{port}/"


def loopback(family):
    """This machine's own address in ``family``: 127.0.0.1 or ::1."""
    return "::1" if family == socket.AF_INET6 else "127.0.0.1"


def machine_addresses(family):
    """The addresses of this machine in ``family`` (socket.AF_INET or AF_INET6) that another machine
    would open a view listening on every interface at (0.0.0.0, ::): the one the default route
    goes out from, else those its host name resolves to; loopback ones left out; [] when it has none."""
    found = []
    try:
        with socket.socket(family, socket.SOCK_DGRAM) as probe:
            probe.connect(_PROBE[family])
            found.append(probe.getsockname()[0])
    except (OSError, KeyError):
        pass
    if not found:
        try:
            found = [info[4][0] for info in socket.getaddrinfo(socket.gethostname(), None, family, socket.SOCK_STREAM)]
        except (OSError, UnicodeError):
            pass
    addresses = []
    for address in found:
        address = address.split("%")[0]  # an IPv6 link-local address's zone
        if address not in addresses and not ipaddress.ip_address(address).is_loopback:
            addresses.append(address)
    return addresses
