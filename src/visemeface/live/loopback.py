"""The receiving end, for checking a live setup: a UDP listener on 127.0.0.1 and a real-time feeder.

:class:`Listener` keeps every OSC packet that arrives on a loopback port with its arrival time;
:func:`vmc_frames` groups VMC messages into frames; :func:`feed_realtime` writes audio into a pipe at
1x (each 10 ms block when it would have been captured). The tests and ``benchmarks/live.py`` use them
to measure what a client gets.
"""

from __future__ import annotations

import socket
import threading
import time

from visemeface.live import osc


class Listener:
    """Packets arriving on ``127.0.0.1:port`` (0: a free port, then :attr:`port`), kept with their
    arrival time (``time.monotonic``) until :meth:`close`."""

    def __init__(self, port: int = 0):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", port))
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.packets: list[tuple[float, bytes]] = []
        self._stop = False
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()

    def _loop(self) -> None:
        while not self._stop:
            try:
                data = self.sock.recv(65536)
            except socket.timeout:
                continue
            except OSError:
                return
            self.packets.append((time.monotonic(), data))

    def close(self) -> None:
        self._stop = True
        self._thread.join()
        self.sock.close()

    def messages(self) -> list[tuple[float, str, list]]:
        """``(arrival, address, args)`` of every message, in arrival order."""
        return [(t, a, args) for t, data in self.packets for a, args in osc.parse(data)]


def vmc_frames(messages) -> list[dict]:
    """VMC frames: ``{"time": /VMC/Ext/T, "arrival": when its Apply came, "values": {name: value}}``."""
    frames, current, t = [], {}, None
    for arrival, address, args in messages:
        if address == "/VMC/Ext/T":
            t, current = float(args[0]), {}
        elif address == "/VMC/Ext/Blend/Val":
            current[str(args[0])] = float(args[1])
        elif address == "/VMC/Ext/Blend/Apply":
            frames.append({"time": t, "arrival": arrival, "values": current})
            current = {}
    return frames


def feed_realtime(pipe, header: bytes, pcm: bytes, bytes_per_second: float, block_s: float = 0.01,
                  frame_bytes: int = 2) -> float:
    """Write ``header`` then ``pcm`` into ``pipe`` (a binary file) in blocks of ``block_s`` at 1x: block
    ``k`` at ``start + (k + 1) · block_s``, as a microphone gives it. Returns ``start`` (monotonic s), the
    instant of the audio's time 0; the pipe is closed at the end."""
    step = int(round(bytes_per_second * block_s))
    step -= step % frame_bytes
    pipe.write(header)
    pipe.flush()
    start = time.monotonic()
    try:
        for k, i in enumerate(range(0, len(pcm), step)):
            due = start + (k + 1) * block_s
            wait = due - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            pipe.write(pcm[i:i + step])
            pipe.flush()
    finally:
        pipe.close()
    return start
