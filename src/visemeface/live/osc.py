"""Open Sound Control 1.0 messages and bundles, and the UDP socket they travel on.

An OSC packet is a message (an address pattern, a type tag string ``,fis...`` and the arguments) or a
bundle (``#bundle``, a 64-bit NTP time tag, then size-prefixed elements). Strings are ASCII, NUL
terminated and padded to a multiple of 4 bytes; ``i`` is a big-endian int32, ``f`` a big-endian
float32 (Wright & Freed, OSC 1.0 specification, 2002). The VMC protocol (Virtual Motion Capture) is OSC
over UDP. This encoder writes what the senders need and :func:`parse` reads it back (tests, benchmark).
"""

from __future__ import annotations

import errno
import socket
import struct

from visemeface.errors import InputError

#: The time tag "immediately" (OSC 1.0: 63 zero bits then a 1).
IMMEDIATELY = 1
#: Largest datagram a sender writes: a bundle larger than this is split (an Ethernet frame's 1500 bytes
#: less the IP and UDP headers, so no datagram is fragmented on a LAN).
MAX_DATAGRAM = 1472


def _string(s: str) -> bytes:
    b = s.encode("ascii") + b"\0"
    return b + b"\0" * (-len(b) % 4)


def message(address: str, *args) -> bytes:
    """One OSC message: ``address`` then the arguments (float -> ``f``, int -> ``i``, str -> ``s``)."""
    if not address.startswith("/"):
        raise ValueError(f"an OSC address starts with '/': {address!r}")
    tags, data = [","], []
    for a in args:
        if isinstance(a, bool) or isinstance(a, int):
            tags.append("i")
            data.append(struct.pack(">i", int(a)))
        elif isinstance(a, float):
            tags.append("f")
            data.append(struct.pack(">f", a))
        elif isinstance(a, str):
            tags.append("s")
            data.append(_string(a))
        else:                                   # numpy scalars
            try:
                value = float(a)
            except (TypeError, ValueError):
                raise TypeError(f"no OSC type for {type(a).__name__}") from None
            tags.append("f")
            data.append(struct.pack(">f", value))
    return _string(address) + _string("".join(tags)) + b"".join(data)


def bundle(messages, timetag: int = IMMEDIATELY) -> bytes:
    """An OSC bundle of encoded messages (or bundles)."""
    return b"#bundle\0" + struct.pack(">Q", timetag) + b"".join(struct.pack(">i", len(m)) + m for m in messages)


def bundles(messages, limit: int = MAX_DATAGRAM) -> list[bytes]:
    """The messages in order, packed into as few bundles as keep each within ``limit`` bytes."""
    out, current, size = [], [], 16
    for m in messages:
        if current and size + 4 + len(m) > limit:
            out.append(bundle(current))
            current, size = [], 16
        current.append(m)
        size += 4 + len(m)
    if current:
        out.append(bundle(current))
    return out


def _read_string(data: bytes, pos: int) -> tuple[str, int]:
    end = data.index(b"\0", pos)
    return data[pos:end].decode("ascii"), end + 1 + (-(end + 1 - pos) % 4)


def parse(data: bytes) -> list[tuple[str, list]]:
    """The messages ``[(address, [args])]`` of a packet (a bundle's elements in order)."""
    if data.startswith(b"#bundle\0"):
        out, pos = [], 16
        while pos < len(data):
            (n,) = struct.unpack(">i", data[pos:pos + 4])
            out += parse(data[pos + 4:pos + 4 + n])
            pos += 4 + n
        return out
    address, pos = _read_string(data, 0)
    tags, pos = _read_string(data, pos)
    args = []
    for t in tags[1:]:
        if t == "i":
            args.append(struct.unpack(">i", data[pos:pos + 4])[0])
            pos += 4
        elif t == "f":
            args.append(struct.unpack(">f", data[pos:pos + 4])[0])
            pos += 4
        elif t == "s":
            s, pos = _read_string(data, pos)
            args.append(s)
        else:
            raise ValueError(f"OSC type tag {t!r} is not read here")
    return [(address, args)]


def parse_target(text: str, option: str, default_port: int | None = None) -> tuple[str, int]:
    """``HOST:PORT`` (or ``PORT``, or ``[v6]:PORT``) -> (host, port), refused with one line."""
    text = str(text).strip()
    host, sep, port = text.rpartition(":")
    if not sep:
        host, port = ("127.0.0.1", text) if text.isdigit() else (text, str(default_port or ""))
    host = host.strip("[]") or "127.0.0.1"
    try:
        number = int(port)
    except ValueError:
        raise InputError(f"{option} {text!r}: expected HOST:PORT (e.g. 127.0.0.1:39539)") from None
    if not 0 < number < 65536:
        raise InputError(f"{option} {text!r}: the port must be in 1..65535")
    return host, number


class UdpSender:
    """A UDP socket connected to one address (resolved and checked when made).

    Only that address is ever sent to. An unresolvable name or an unreachable network is refused at once
    (:class:`InputError`); a host that has no listener yet (a VMC client started later) is not an error:
    its refusals are counted in :attr:`refused` and sending goes on.
    """

    def __init__(self, host: str, port: int, option: str):
        self.option = option
        try:
            infos = socket.getaddrinfo(host, port, type=socket.SOCK_DGRAM)
        except (socket.gaierror, UnicodeError) as exc:
            raise InputError(f"{option} {host}:{port}: the address does not resolve ({exc.args[-1]})") from None
        family, kind, proto, _, address = infos[0]
        self.address = address
        self.sock = socket.socket(family, kind, proto)
        try:
            self.sock.connect(address)
            self.sock.setblocking(False)
        except OSError as exc:
            self.sock.close()
            raise InputError(f"{option} {host}:{port}: unreachable ({exc.strerror or exc})") from None
        self.refused = 0
        self.sent = 0

    def send(self, packets) -> None:
        for p in packets:
            try:
                self.sock.send(p)
                self.sent += 1
            except (ConnectionRefusedError, BlockingIOError):
                self.refused += 1               # nobody listening yet / the socket buffer full: drop it
            except OSError as exc:
                if exc.errno in (errno.ENETUNREACH, errno.EHOSTUNREACH, errno.EADDRNOTAVAIL):
                    raise InputError(f"{self.option} {self.address[0]}:{self.address[1]}: unreachable "
                                     f"({exc.strerror})") from None
                raise

    def close(self) -> None:
        self.sock.close()
