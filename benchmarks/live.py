"""``visemeface live`` fed a GRID recording at 1x through a pipe, listened to on a loopback UDP port (JSON lines).

For each clip: the recording (its sound track, as 16-bit PCM at its own rate) is written as a WAV
stream into ``visemeface live - --vmc 127.0.0.1:PORT`` in 10 ms blocks at real time, after the
command says it is ready; a listener on 127.0.0.1 keeps every VMC frame with its arrival time. Printed:

- ``latency``: per frame, arrival minus the instant its sound was written (the stream's start + the
  frame's ``/VMC/Ext/T``), as min / p10 / median / p90 / p95 / max in ms;
- ``jaw_r``: Pearson's r of the streamed jawOpen against the offline run's
  (``visemeface speak CLIP.wav --no-video --arkit``, phones recognised, no text), frame by frame;
- ``bilabials``: for each /p b m/ the decoder found, whether the streamed frame at its centre closes
  the lips (the ARKit weights played on the face, :func:`visemeface.muscles.measure.inner_opening`);
- ``cpu_core``: the live process's CPU seconds over the streaming's wall seconds;
- on the first clip, Ctrl-C 1.5 s into the stream: the exit status, stderr, ms from SIGINT to exit.

::

    PYTHONPATH=src python benchmarks/live.py [--clips swwp2s,bbaf2n,lbax4n] [--latency 0.12] [--frames]

swwp2s was used to choose the default latency and the cepstral-mean update; bbaf2n and lbax4n are held out.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
REALDATA = Path(os.environ.get("VISEMEFACE_REALDATA", ROOT.parent / "shared" / "realdata"))


def _cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT / "src") + os.pathsep + env.get("PYTHONPATH", "")
    return env


def offline_jaw(wav: Path, folder: Path) -> np.ndarray:
    import pandas as pd

    out = folder / "offline.csv"
    subprocess.run([sys.executable, "-m", "visemeface", "speak", str(wav), "--no-video", "--arkit", str(out),
                    "--force", "-q"], check=True, env=_env(), cwd=folder)
    return pd.read_csv(out)["jawOpen"].to_numpy()


def stream(wav: Path, folder: Path, latency: float | None, extra=()) -> dict:
    """Run ``live -`` on ``wav`` at 1x; the listener's frames, timings and the run's outputs."""
    import soundfile as sf

    from visemeface.live.loopback import Listener, feed_realtime, vmc_frames

    data, rate = sf.read(str(wav), dtype="int16")
    buf = io.BytesIO()
    sf.write(buf, data, rate, format="WAV", subtype="PCM_16")
    raw = buf.getvalue()
    header, pcm = raw[:44], raw[44:]
    listener = Listener()
    transcript = folder / "live.TextGrid"
    cmd = [sys.executable, "-m", "visemeface", "live", "-", "--vmc", f"127.0.0.1:{listener.port}",
           "--save-transcript", str(transcript), "--force", *extra]
    if latency is not None:
        cmd += ["--latency", str(latency)]
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env=_env(), cwd=folder)
    ready = proc.stdout.readline().decode()
    if not ready.startswith("live:"):
        proc.kill()
        raise SystemExit(f"live did not start: {ready}{proc.stderr.read().decode()}")
    cpu0 = _cpu_seconds(proc.pid)
    start = feed_realtime(proc.stdin, header, pcm, rate * 2)
    wall_end = time.monotonic()
    cpu1 = _cpu_seconds(proc.pid)
    proc.stdin = None                           # closed by feed_realtime
    out, err = proc.communicate(timeout=120)
    time.sleep(0.05)
    listener.close()
    frames = vmc_frames(listener.messages())
    return {"code": proc.returncode, "stdout": out.decode(), "stderr": err.decode(), "frames": frames,
            "start": start, "cpu_core": (cpu1 - cpu0) / max(wall_end - start, 1e-9), "transcript": transcript}


def bilabial_closures(frames, transcript: Path, fps: float = 30.0) -> list[dict]:
    """Each /p b m/ of the transcript: is the lip opening of the streamed frame at its centre closed?"""
    from visemeface.muscles.measure import inner_opening
    from visemeface.muscles.rig import default_rig
    from visemeface.retarget import ShapeFit, moving_vertices, vocabulary
    from visemeface.speech.transcripts import read_utterance

    rig = default_rig()
    vocab = vocabulary("arkit", rig)
    fit = ShapeFit(vocab, moving_vertices(rig))
    seg = read_utterance(transcript).segments
    out = []
    by_time = {round(f["time"] * fps): f for f in frames}
    for s, e, ph in seg[["start", "end", "phoneme"]].itertuples(index=False):
        if ph not in ("p", "b", "m"):
            continue
        k = int(round((s + e) / 2 * fps))                 # the frame nearest its centre
        f = by_time.get(k)
        if f is None:
            continue
        w = np.array([f["values"].get(n, 0.0) for n in vocab.names])
        v = rig.face.vertices + fit.play(w[None])[0]
        opening = inner_opening(rig.face, v)
        out.append({"phone": ph, "start": round(float(s), 3), "end": round(float(e), 3), "frame": k,
                    "height_mm": round(float(opening["height"]) * 1000, 3), "closed": bool(opening["height"] <= 0)})
    return out


def interrupt(wav: Path, folder: Path) -> dict:
    """Ctrl-C 1.5 s into a 1x stream: the exit status, stderr's lines, and ms from SIGINT to exit."""
    import signal
    import soundfile as sf

    from visemeface.live.loopback import Listener

    data, rate = sf.read(str(wav), dtype="int16")
    listener = Listener()
    proc = subprocess.Popen([sys.executable, "-m", "visemeface", "live", "-", "--format", "s16le", "--sample-rate",
                             str(rate), "--vmc", f"127.0.0.1:{listener.port}"], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env(), cwd=folder)
    proc.stdout.readline()
    pcm = data.astype("<i2").tobytes()
    step = rate // 100 * 2
    start = time.monotonic()
    for k in range(150):
        proc.stdin.write(pcm[k * step:(k + 1) * step])
        proc.stdin.flush()
        time.sleep(max(0.0, start + (k + 1) / 100 - time.monotonic()))
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=60)
    exit_ms = (time.monotonic() - t0) * 1000
    err = proc.stderr.read().decode().strip().splitlines()
    listener.close()
    return {"interrupt": True, "code": proc.returncode, "exit_ms": round(exit_ms, 1), "stderr": err,
            "load1": round(os.getloadavg()[0], 2)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clips", default="swwp2s,bbaf2n,lbax4n")
    ap.add_argument("--latency", type=float, default=None, help="--latency of live (default: its default)")
    ap.add_argument("--frames", action="store_true", help="also print every frame's latency and jawOpen")
    ap.add_argument("--no-interrupt", action="store_true", help="skip the Ctrl-C timing on the first clip")
    args = ap.parse_args()
    sys.path.insert(0, str(ROOT / "src"))
    from visemeface.runtime import configure
    from visemeface.speech.audio import read_audio

    configure()
    import soundfile as sf

    for clip in args.clips.split(","):
        with tempfile.TemporaryDirectory(prefix="visemeface-live-") as tmp:
            folder = Path(tmp)
            samples, rate = read_audio(REALDATA / f"{clip}.mpg")
            wav = folder / f"{clip}.wav"
            sf.write(str(wav), samples, rate, subtype="PCM_16")
            reference = offline_jaw(wav, folder)
            res = stream(wav, folder, args.latency)
            if res["code"] != 0:
                raise SystemExit(f"live exited {res['code']}: {res['stderr']}")
            frames = res["frames"]
            lat = np.array([(f["arrival"] - res["start"] - f["time"]) * 1000 for f in frames])
            # frames skipped to catch up (a loaded machine) are left out; the others pair by frame number
            pairs = [(f["values"].get("jawOpen", 0.0), reference[k]) for f in frames
                     if (k := int(round(f["time"] * 30.0))) < len(reference)]
            jaw, ref = np.array(pairs).T
            r = float(np.corrcoef(jaw, ref)[0, 1])
            closures = bilabial_closures(frames, res["transcript"])
            if args.frames:
                for f, ms in zip(frames, lat):
                    print(json.dumps({"clip": clip, "t": round(f["time"], 4), "latency_ms": round(float(ms), 1),
                                      "jawOpen": round(f["values"].get("jawOpen", 0.0), 4)}))
            print(json.dumps({
                "clip": clip, "held_out": clip != "swwp2s", "latency_setting_s": args.latency, "frames": len(frames),
                "offline_frames": len(reference), "stdout": res["stdout"].strip().splitlines()[-1:],
                "latency_ms": {k: round(float(v), 1) for k, v in zip(
                    ("min", "p10", "median", "p90", "p95", "max"), np.percentile(lat, [0, 10, 50, 90, 95, 100]))},
                "jaw_r": round(r, 3), "bilabials": closures,
                "bilabials_closed": f"{sum(c['closed'] for c in closures)}/{len(closures)}",
                "cpu_core": round(res["cpu_core"], 3), "load1": round(os.getloadavg()[0], 2)}))
            if not args.no_interrupt and clip == args.clips.split(",")[0]:
                print(json.dumps({"clip": clip, **interrupt(wav, folder)}))
            sys.stdout.flush()


if __name__ == "__main__":
    main()
