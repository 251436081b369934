"""``visemeface live`` from the command line: bad input in one line (exit 2), Ctrl-C (exit 130), and the
3 s GRID recording streamed at 1x through a pipe to a loopback UDP port.

Every address used is 127.0.0.1 (or, for the unreachable case, the broadcast address, to which a
connect is refused before anything is sent).
"""

import io
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import soundfile as sf

from visemeface.cli import main

ROOT = Path(__file__).resolve().parents[2]


def _env():
    return dict(os.environ, PYTHONPATH=str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", ""))


def _one_error_line(err: str) -> str:
    lines = [ln for ln in err.splitlines() if not ln.startswith("visemeface: warning:")]
    assert len(lines) == 1 and lines[0].startswith("visemeface: error: "), err
    return lines[0]


@pytest.fixture
def wav(tmp_path, vowels_wav):
    return vowels_wav


def _free_udp_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def test_a_websocket_port_in_use_is_one_line_exit_2(wav, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen(1)
    try:
        code = main(["live", str(wav), "--fast", "--websocket", f"127.0.0.1:{busy.getsockname()[1]}",
                     "--arkit", "out.csv"])
    finally:
        busy.close()
    assert code == 2 and "in use" in _one_error_line(capsys.readouterr().err)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("target,why", [("no-such-host.invalid:9000", "does not resolve"),
                                        ("255.255.255.255:9000", "unreachable")])
def test_an_unresolvable_or_unreachable_address_is_one_line_exit_2(wav, capsys, target, why):
    assert main(["live", str(wav), "--fast", "--vmc", target]) == 2
    assert why in _one_error_line(capsys.readouterr().err)


def test_an_absent_microphone_is_one_line_exit_2(capsys, monkeypatch):
    import types

    class PortAudioError(Exception):
        pass

    def query_devices(device=None, kind=None):
        raise PortAudioError("Error querying device -1")

    fake = types.SimpleNamespace(query_devices=query_devices, PortAudioError=PortAudioError)
    monkeypatch.setitem(sys.modules, "sounddevice", fake)
    assert main(["live", "--mic", "--vmc", f"127.0.0.1:{_free_udp_port()}"]) == 2
    assert "no microphone" in _one_error_line(capsys.readouterr().err)


def test_without_portaudio_the_microphone_names_the_extra(capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "sounddevice", None)          # import fails
    assert main(["live", "--mic", "--vmc", f"127.0.0.1:{_free_udp_port()}"]) == 2
    assert "visemeface[live]" in _one_error_line(capsys.readouterr().err)


@pytest.mark.parametrize("fmt,data", [
    ("s16le", (0.3 * np.sin(np.arange(16000) / 7)).astype("<f4").tobytes()),
    ("f32le", (0.3 * np.sin(np.arange(16000) / 7) * 32767).astype("<i2").tobytes()),
    ("s16le", b""),
])
def test_a_stream_of_the_wrong_sample_format_is_one_line_exit_2_and_writes_nothing(tmp_path, fmt, data):
    proc = subprocess.run([sys.executable, "-m", "visemeface", "live", "-", "--format", fmt, "-q",
                           "--vmc", f"127.0.0.1:{_free_udp_port()}", "--arkit", "out.csv"],
                          input=data, capture_output=True, env=_env(), cwd=tmp_path, timeout=300)
    assert proc.returncode == 2, proc.stderr
    _one_error_line(proc.stderr.decode())
    assert not (tmp_path / "out.csv").exists() and [p.name for p in tmp_path.iterdir()] == []


def _wav_stream(realdata, clip="swwp2s"):
    from visemeface.speech.audio import read_audio

    samples, rate = read_audio(realdata / f"{clip}.mpg")
    buf = io.BytesIO()
    sf.write(buf, samples, rate, format="WAV", subtype="PCM_16")
    raw = buf.getvalue()
    return raw[:44], raw[44:], rate


def _start(cmd, cwd):
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env=_env(), cwd=cwd)
    ready = proc.stdout.readline().decode()
    assert ready.startswith("live:"), ready + proc.stderr.read().decode()
    return proc


@pytest.mark.slow
@pytest.mark.realdata
def test_ctrl_c_ends_it_at_once_with_one_line_exit_130_and_the_recording_of_what_was_sent(realdata, tmp_path):
    from visemeface.live.loopback import Listener, vmc_frames

    header, pcm, rate = _wav_stream(realdata)
    listener = Listener()
    proc = _start([sys.executable, "-m", "visemeface", "live", "-", "--vmc", f"127.0.0.1:{listener.port}",
                   "--arkit", "rec.csv"], tmp_path)
    proc.stdin.write(header)
    second = rate * 2
    for k in range(150):                                   # 1.5 s at 1x, then Ctrl-C with the pipe open
        proc.stdin.write(pcm[k * second // 100 // 2 * 2:(k + 1) * second // 100 // 2 * 2])
        proc.stdin.flush()
        time.sleep(0.01)
    time.sleep(0.3)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    listener.close()
    assert proc.returncode == 130, err
    lines = err.decode().strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("visemeface: interrupted after "), lines
    import pandas as pd

    sent = vmc_frames(listener.messages())
    recorded = pd.read_csv(tmp_path / "rec.csv")
    assert sent and len(recorded) >= len(sent)              # a busy machine sends fewer frames
    for f in sent:
        k = int(round(f["time"] * 30))
        assert abs(recorded["jawOpen"][k] - f["values"]["jawOpen"]) < 1e-5


@pytest.mark.slow
@pytest.mark.realdata
def test_the_grid_clip_streamed_at_1x_moves_the_jaw_as_offline_and_closes_the_bilabials(realdata, tmp_path):
    import pandas as pd

    from visemeface.live.loopback import Listener, feed_realtime, vmc_frames
    from visemeface.muscles.measure import inner_opening
    from visemeface.muscles.rig import default_rig
    from visemeface.retarget import ShapeFit, moving_vertices, vocabulary
    from visemeface.speech.transcripts import read_utterance

    header, pcm, rate = _wav_stream(realdata)
    wav = tmp_path / "swwp2s.wav"
    wav.write_bytes(header + pcm)
    subprocess.run([sys.executable, "-m", "visemeface", "speak", str(wav), "--no-video", "--arkit", "off.csv", "-q"],
                   check=True, env=_env(), cwd=tmp_path, timeout=600)
    offline = pd.read_csv(tmp_path / "off.csv")["jawOpen"].to_numpy()
    listener = Listener()
    proc = _start([sys.executable, "-m", "visemeface", "live", "-", "--vmc", f"127.0.0.1:{listener.port}",
                   "--save-transcript", "live.TextGrid", "--arkit", "rec.csv"], tmp_path)
    feed_realtime(proc.stdin, header, pcm, rate * 2)
    proc.stdin = None
    out, err = proc.communicate(timeout=120)
    time.sleep(0.05)
    listener.close()
    assert proc.returncode == 0, err
    messages = listener.messages()
    assert messages and {a for _, a, _ in messages} <= {"/VMC/Ext/T", "/VMC/Ext/Blend/Val", "/VMC/Ext/Blend/Apply"}
    frames = vmc_frames(messages)
    assert len(frames) >= 15                   # of 90: a busy machine skips frames rather than send them late
    assert "eyeBlinkLeft" not in frames[0]["values"] and "jawOpen" in frames[0]["values"]
    k = np.array([int(round(f["time"] * 30)) for f in frames])
    assert (np.diff(k) > 0).all() and k[-1] == len(offline) - 1
    jaw = np.array([f["values"]["jawOpen"] for f in frames])
    assert np.corrcoef(jaw, offline[k])[0, 1] >= 0.8
    recorded = pd.read_csv(tmp_path / "rec.csv")
    assert len(recorded) == len(offline) and np.allclose(recorded["jawOpen"].to_numpy()[k], jaw, atol=1e-5)
    rig = default_rig()
    vocab = vocabulary("arkit", rig)
    fit = ShapeFit(vocab, moving_vertices(rig))
    by_frame = dict(zip(k, frames))
    seg = read_utterance(tmp_path / "live.TextGrid").segments
    closures = [(s + e) / 2 for s, e, p in seg[["start", "end", "phoneme"]].itertuples(index=False)
                if p in ("p", "b", "m")]
    assert closures, "no bilabial recognised"
    for c in closures:                 # the frame sent, or (skipped on a busy machine) the one recorded for it
        j = int(round(c * 30))                                  # the frame nearest its centre
        f = by_frame.get(j)
        w = (np.array([f["values"].get(n, 0.0) for n in vocab.names]) if f is not None
             else recorded[vocab.names].to_numpy()[j])
        assert inner_opening(rig.face, rig.face.vertices + fit.play(w[None])[0])["height"] <= 0, f"open at {c:.2f} s"
