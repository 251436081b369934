"""What the senders put on the wire: VMC frames, plain OSC, the WebSocket stream, and the meter line."""

import base64
import io
import json
import os
import socket
import struct
import time

import numpy as np
import pytest

from visemeface.errors import InputError
from visemeface.live import senders
from visemeface.live.loopback import Listener, vmc_frames
from visemeface.live.mouth import LiveFrame
from visemeface.live.session import Meter

NAMES = ["jawOpen", "eyeBlinkLeft", "mouthClose"]


def _frame(t=0.5, values=(0.4, 0.0, 0.1), vocabulary="arkit"):
    return LiveFrame(15, t, {vocabulary: np.array(values)}, np.zeros(3), "aa", -20.0)


def _received(listener, n=1, timeout=5.0):
    end = time.monotonic() + timeout
    while len(listener.packets) < n and time.monotonic() < end:
        time.sleep(0.01)
    listener.close()
    return listener.messages()


def test_a_vmc_frame_is_its_time_the_driven_shapes_then_apply():
    listener = Listener()
    s = senders.VmcSender("127.0.0.1", listener.port)
    s.configure("arkit", NAMES, [True, False, True])
    s.send(_frame())
    s.close()
    frames = vmc_frames(_received(listener))
    assert len(frames) == 1 and frames[0]["time"] == pytest.approx(0.5)
    assert frames[0]["values"] == pytest.approx({"jawOpen": 0.4, "mouthClose": 0.1})


def test_vrm0_names_are_the_vrm0_presets():
    listener = Listener()
    s = senders.VmcSender("127.0.0.1", listener.port, senders.vrm0_names())
    s.configure("vrm", ["aa", "ou", "surprised"], [True, True, True])
    s.send(_frame(values=(0.7, 0.2, 0.5), vocabulary="vrm"))
    s.close()
    assert vmc_frames(_received(listener))[0]["values"] == pytest.approx({"A": 0.7, "U": 0.2})


def test_plain_osc_has_time_viseme_level_and_one_address_per_shape():
    listener = Listener()
    s = senders.OscSender("127.0.0.1", listener.port, "/face/")
    s.configure("arkit", NAMES, [True, False, True])
    s.send(_frame())
    s.close()
    got = {a: args for _, a, args in _received(listener)}
    assert got["/face/viseme"] == ["aa"] and got["/face/time"] == [pytest.approx(0.5)]
    assert got["/face/jawOpen"] == [pytest.approx(0.4)] and "/face/eyeBlinkLeft" not in got


@pytest.mark.parametrize("prefix", ["/", "/a b", "/x*", "/é"])
def test_a_bad_osc_prefix_is_refused(prefix):
    with pytest.raises(InputError, match="--osc-prefix"):
        senders.check_prefix(prefix)


def test_the_accept_key_is_rfc_6455s_example():
    assert senders.ws_accept_key("dGhlIHNhbXBsZSBub25jZQ==") == "s3pPLMBiTxaQ9kYGzzhZRbK+xOo="


def _ws_client(port):
    c = socket.create_connection(("127.0.0.1", port), timeout=5)
    key = base64.b64encode(os.urandom(16)).decode()
    c.sendall((f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
               f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
    head = b""
    while b"\r\n\r\n" not in head:
        head += c.recv(1)
    assert head.startswith(b"HTTP/1.1 101") and senders.ws_accept_key(key).encode() in head
    return c


def _ws_read(c):
    b0, b1 = c.recv(2, socket.MSG_WAITALL)
    assert b0 == 0x81 and b1 & 0x80 == 0
    n = b1 & 0x7F
    if n == 126:
        n = struct.unpack(">H", c.recv(2, socket.MSG_WAITALL))[0]
    return c.recv(n, socket.MSG_WAITALL).decode()


def test_a_websocket_client_gets_each_frame_as_json():
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    server = senders.WebSocketSender("127.0.0.1", port)
    server.configure("arkit", NAMES, [True, False, True])
    try:
        client = _ws_client(port)
        end = time.monotonic() + 5
        while not server.clients and time.monotonic() < end:
            time.sleep(0.01)
        server.send(_frame())
        doc = json.loads(_ws_read(client))
        assert doc["t"] == 0.5 and doc["viseme"] == "aa" and doc["weights"] == {"jawOpen": 0.4, "mouthClose": 0.1}
        client.close()
    finally:
        server.close()


def test_the_meter_redraws_one_line_with_the_level_and_viseme():
    out = io.StringIO()
    meter = Meter(out, width=10)
    meter.show(1.25, -30.0, "aa", force=True)
    meter.show(1.3, -120.0, "m", force=True)
    meter.clear()
    text = out.getvalue()
    assert "\n" not in text and text.count("\r") == 3
    assert "[#####-----]" in text and " -30 dB  aa" in text and "[----------]" in text and "m" in text
