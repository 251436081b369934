"""Where live frames go: the VMC protocol, plain OSC messages, a WebSocket JSON stream.

VMC (Virtual Motion Capture protocol, read by VSeeFace, VNyan, Warudo, VMagicMirror)
    OSC over UDP: per frame ``/VMC/Ext/T`` (the frame's time, s), one ``/VMC/Ext/Blend/Val name value``
    per blend shape the face can make, then ``/VMC/Ext/Blend/Apply``, in bundles of at most one Ethernet
    datagram (the last holds ``Apply``). Names are ARKit's (``jawOpen``, for "perfect sync" avatars),
    VRM 1.0's (``aa ih ou ee oh``) or VRM 0.x's (``A I U E O``, ``data/live/vrm0_names.csv``).
OSC
    Per frame ``PREFIX/time f``, ``PREFIX/viseme s`` (the DECtalk phone under the frame),
    ``PREFIX/level f`` (dB re full scale) and ``PREFIX/<name> f`` per blend shape.
WebSocket
    A server on a local port (127.0.0.1 unless told): every client gets each frame as one JSON text
    message ``{"t": time, "viseme": ..., "level": ..., "weights": {name: value}}`` (RFC 6455; written here,
    no dependency).
"""

from __future__ import annotations

import base64
import csv
import errno
import hashlib
import json
import socket
import struct
import threading

import numpy as np

from visemeface.errors import InputError
from visemeface.live import osc
from visemeface.resources import data_path

#: ``--vmc-names`` choices.
VMC_NAMES = ("arkit", "vrm", "vrm0")


def vrm0_names() -> dict[str, str]:
    """VRM 1.0 preset name -> VRM 0.x clip name (``data/live/vrm0_names.csv``)."""
    with open(data_path("live", "vrm0_names.csv"), encoding="utf-8", newline="") as fh:
        rows = csv.DictReader(line for line in fh if not line.startswith("#"))
        return {r["vrm1"]: r["vrm0"] for r in rows}


class Sender:
    """Base of the live outputs. Made from the options alone (its socket opened, so a bad address is
    refused before any slow work); :meth:`configure` then gives it the vocabulary it sends (its name, the
    shape names, which of them the mouth drives); :meth:`send` a frame, :meth:`close`; ``what`` names it."""

    what = ""
    vocabulary = "arkit"

    def configure(self, vocabulary: str, names, driven) -> None:
        self.vocabulary = vocabulary
        self.index = np.flatnonzero(np.asarray(driven, bool))
        self.names = [names[i] for i in self.index]

    def send(self, frame) -> None:
        raise NotImplementedError

    def close(self) -> None:
        pass


def check_prefix(prefix: str) -> str:
    """``--osc-prefix`` as an OSC address (``/name/...``, no pattern characters), or one line refusing it."""
    text = "/" + str(prefix).strip().strip("/")
    if text == "/" or not all(c.isascii() and c.isprintable() for c in text) or any(c in text for c in " #*,?[]{}"):
        raise InputError(f"--osc-prefix {prefix!r}: an OSC address of plain characters, e.g. /visemeface")
    return text


class VmcSender(Sender):
    """Blend shapes as VMC messages to one UDP address (the module docstring)."""

    def __init__(self, host: str, port: int, rename: dict | None = None):
        self.udp = osc.UdpSender(host, port, "--vmc")
        self.what = f"VMC {host}:{port}"
        self.rename = rename

    def configure(self, vocabulary: str, names, driven) -> None:
        super().configure(vocabulary, names, driven)
        if self.rename is not None:                 # VRM 0.x: the presets it has, under its names
            keep = [k for k, n in enumerate(self.names) if n in self.rename]
            self.index = self.index[keep]
            self.names = [self.rename[self.names[k]] for k in keep]

    def send(self, frame) -> None:
        w = np.asarray(frame.weights[self.vocabulary])[self.index]
        msgs = [osc.message("/VMC/Ext/T", float(frame.time))]
        msgs += [osc.message("/VMC/Ext/Blend/Val", n, float(v)) for n, v in zip(self.names, w)]
        msgs.append(osc.message("/VMC/Ext/Blend/Apply"))
        self.udp.send(osc.bundles(msgs))

    def close(self) -> None:
        self.udp.close()


class OscSender(Sender):
    """Plain OSC messages, one address per value (the module docstring)."""

    def __init__(self, host: str, port: int, prefix: str = "/visemeface"):
        self.prefix = check_prefix(prefix)
        self.udp = osc.UdpSender(host, port, "--osc")
        self.what = f"OSC {host}:{port}"

    def configure(self, vocabulary: str, names, driven) -> None:
        super().configure(vocabulary, names, driven)
        self.addresses = [f"{self.prefix}/{n}" for n in self.names]

    def send(self, frame) -> None:
        p = self.prefix
        msgs = [osc.message(f"{p}/time", float(frame.time)), osc.message(f"{p}/viseme", frame.phone),
                osc.message(f"{p}/level", float(frame.level))]
        w = np.asarray(frame.weights[self.vocabulary])[self.index]
        msgs += [osc.message(a, float(v)) for a, v in zip(self.addresses, w)]
        self.udp.send(osc.bundles(msgs))

    def close(self) -> None:
        self.udp.close()


_WS_GUID = "258EAFA5-E914-47DA-95CA-C5AB0DC85B11"


def ws_accept_key(key: str) -> str:
    """The ``Sec-WebSocket-Accept`` answer to a client's ``Sec-WebSocket-Key`` (RFC 6455 §4.2.2)."""
    return base64.b64encode(hashlib.sha1((key.strip() + _WS_GUID).encode("ascii")).digest()).decode("ascii")


def ws_text_frame(text: str) -> bytes:
    """One unmasked, final WebSocket text frame (a server's)."""
    data = text.encode("utf-8")
    n = len(data)
    if n < 126:
        head = struct.pack(">BB", 0x81, n)
    elif n < 1 << 16:
        head = struct.pack(">BBH", 0x81, 126, n)
    else:
        head = struct.pack(">BBQ", 0x81, 127, n)
    return head + data


class WebSocketSender(Sender):
    """A WebSocket server: each client that connects receives every later frame as JSON text."""

    def __init__(self, host: str, port: int):
        self.what = f"WebSocket ws://{host}:{port}"
        try:
            family = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0][0]
        except (socket.gaierror, UnicodeError) as exc:
            raise InputError(f"--websocket {host}:{port}: the address does not resolve ({exc.args[-1]})") from None
        self.server = socket.socket(family, socket.SOCK_STREAM)
        try:
            self.server.bind((host, port))
            self.server.listen(8)
        except OSError as exc:
            self.server.close()
            why = "the port is in use" if exc.errno == errno.EADDRINUSE else (exc.strerror or str(exc))
            raise InputError(f"--websocket {host}:{port}: cannot listen ({why})") from None
        self.clients: list[socket.socket] = []
        self.lock = threading.Lock()
        self.closed = False
        threading.Thread(target=self._accept, name="visemeface-websocket", daemon=True).start()

    def _accept(self) -> None:
        while not self.closed:
            try:
                conn, _ = self.server.accept()
            except OSError:
                return
            threading.Thread(target=self._handshake, args=(conn,), daemon=True).start()

    def _handshake(self, conn: socket.socket) -> None:
        conn.settimeout(5.0)
        try:
            request = b""
            while b"\r\n\r\n" not in request and len(request) < 16384:
                more = conn.recv(4096)
                if not more:
                    raise OSError("closed")
                request += more
            headers = {}
            for line in request.decode("latin-1").split("\r\n")[1:]:
                name, _, value = line.partition(":")
                headers[name.strip().lower()] = value.strip()
            key = headers.get("sec-websocket-key")
            if not key or "websocket" not in headers.get("upgrade", "").lower():
                conn.sendall(b"HTTP/1.1 426 Upgrade Required\r\nContent-Length: 0\r\n\r\n")
                raise OSError("not a WebSocket request")
            conn.sendall(("HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                          f"Sec-WebSocket-Accept: {ws_accept_key(key)}\r\n\r\n").encode("ascii"))
            conn.settimeout(0.5)
        except OSError:
            conn.close()
            return
        with self.lock:
            self.clients.append(conn)

    def send(self, frame) -> None:
        w = np.asarray(frame.weights[self.vocabulary])[self.index]
        doc = {"t": round(float(frame.time), 4), "viseme": frame.phone, "level": round(float(frame.level), 1),
               "weights": {n: round(float(v), 4) for n, v in zip(self.names, w)}}
        packet = ws_text_frame(json.dumps(doc, separators=(",", ":")))
        with self.lock:
            clients = list(self.clients)
        for c in clients:
            try:
                c.sendall(packet)
            except OSError:                 # gone, or too slow to keep up: dropped
                with self.lock:
                    if c in self.clients:
                        self.clients.remove(c)
                c.close()

    def close(self) -> None:
        self.closed = True
        self.server.close()
        with self.lock:
            for c in self.clients:
                c.close()
            self.clients = []
