"""The OSC encoder against the OSC 1.0 specification's own examples, bundles, and target parsing."""

import struct

import pytest

from visemeface.errors import InputError
from visemeface.live import osc


def test_the_specifications_first_example_is_encoded_byte_for_byte():
    # OSC 1.0 spec, "Examples": /oscillator/4/frequency ,f 440.0
    expected = bytes.fromhex("2f6f7363696c6c61746f722f342f6672657175656e6379002c66000043dc0000")
    assert osc.message("/oscillator/4/frequency", 440.0) == expected


def test_the_specifications_second_example_is_encoded_byte_for_byte():
    # /foo ,iisff 1000 -1 "hello" 1.234 5.678
    expected = bytes.fromhex("2f666f6f" "00000000" "2c696973" "66660000" "000003e8" "ffffffff"
                             "68656c6c" "6f000000" "3f9df3b6" "40b5b22d")
    assert osc.message("/foo", 1000, -1, "hello", 1.234, 5.678) == expected


def test_messages_and_bundles_read_back():
    packet = osc.bundle([osc.message("/VMC/Ext/Blend/Val", "jawOpen", 0.25), osc.message("/VMC/Ext/Blend/Apply")])
    assert packet.startswith(b"#bundle\0") and struct.unpack(">Q", packet[8:16])[0] == osc.IMMEDIATELY
    assert osc.parse(packet) == [("/VMC/Ext/Blend/Val", ["jawOpen", 0.25]), ("/VMC/Ext/Blend/Apply", [])]


def test_a_long_frame_is_split_into_datagrams_in_order_within_the_limit():
    msgs = [osc.message("/VMC/Ext/Blend/Val", f"shape{i:02d}", i / 100) for i in range(60)]
    msgs.append(osc.message("/VMC/Ext/Blend/Apply"))
    packets = osc.bundles(msgs)
    assert len(packets) > 1 and all(len(p) <= osc.MAX_DATAGRAM for p in packets)
    read = [m for p in packets for m in osc.parse(p)]
    assert [a for a, _ in read] == ["/VMC/Ext/Blend/Val"] * 60 + ["/VMC/Ext/Blend/Apply"]
    assert osc.parse(packets[-1])[-1][0] == "/VMC/Ext/Blend/Apply"
    assert [args[0] for _, args in read[:60]] == [f"shape{i:02d}" for i in range(60)]


@pytest.mark.parametrize("text,expected", [("127.0.0.1:39539", ("127.0.0.1", 39539)), ("9000", ("127.0.0.1", 9000)),
                                           ("[::1]:9000", ("::1", 9000)), ("localhost:1", ("localhost", 1))])
def test_targets_parse(text, expected):
    assert osc.parse_target(text, "--osc") == expected


@pytest.mark.parametrize("text", ["127.0.0.1:0", "127.0.0.1:70000", "host:port", "localhost"])
def test_bad_targets_are_refused_in_one_line(text):
    with pytest.raises(InputError, match="--osc"):
        osc.parse_target(text, "--osc")


def test_an_unresolvable_name_is_refused_before_anything_is_sent():
    with pytest.raises(InputError, match="does not resolve"):
        osc.UdpSender("no-such-host.invalid", 9000, "--vmc")


def test_a_receiver_not_listening_yet_is_counted_not_fatal():
    import socket

    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()                                   # nobody listens there now
    sender = osc.UdpSender("127.0.0.1", port, "--vmc")
    for _ in range(5):
        sender.send([osc.message("/VMC/Ext/Blend/Apply")])
    sender.close()
    assert sender.sent + sender.refused == 5 and sender.refused >= 1
