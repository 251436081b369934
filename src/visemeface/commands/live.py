"""``visemeface live [AUDIO]``: mouth shapes from live audio, sent as they are spoken.

Audio from a recording played in real time, a PCM or WAV stream on stdin (``-``), or the default
microphone (``--mic``, the optional extra ``live``); phones recognised as they come
(:mod:`visemeface.live.phones`), the mouth made from them as offline with a short look-ahead
(:mod:`visemeface.live.mouth`), sent over VMC, OSC or a WebSocket (:mod:`visemeface.live.senders`),
and recorded to any offline output when the stream ends.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from visemeface.commands import _options as opt

ORDER = 23

#: Default ``--latency`` (s): swwp2s's streamed jawOpen correlates with the offline run's at r = 0.80 at
#: 0.12 s, as at 0.13 (0.73 at 0.10, 0.86 at 0.15; chosen on swwp2s; the held-out bbaf2n and lbax4n: 0.84,
#: 0.90); the messages leave 15-20 ms after that (benchmarks/live.py, docs/notes/live.md).
LATENCY = 0.12
#: Default ports: the VMC protocol's (a performer sends to 39539, VSeeFace's and VNyan's receiver default).
VMC_PORT = 39539

EPILOG = """\
examples:
  visemeface live --mic --vmc 127.0.0.1:39539                 # VSeeFace/VNyan/Warudo: ARKit "perfect sync"
  visemeface live --mic --vmc 127.0.0.1:39539 --vmc-names vrm0  # a VRM 0.x avatar's A I U E O
  ffmpeg -re -i talk.mp4 -f s16le -ac 1 -ar 16000 - | visemeface live - --osc 127.0.0.1:9000
  visemeface live take.wav --websocket 127.0.0.1:8765 --arkit take_arkit.csv   # played in real time, recorded

Input: a recording (WAV, FLAC, MP3, a video's sound) played in real time; '-' reads stdin: a WAV
stream, or raw PCM of --format/--sample-rate/--channels. Ctrl-C ends it at once (exit status 130); the
recording options (--arkit, --livelink, --track, ...) are written when the stream ends or is
interrupted, from the frames that were sent. Only the addresses given are sent to.
"""


def _latency(text: str) -> float:
    s = str(text).strip().lower()
    try:
        value = float(s[:-2]) / 1000.0 if s.endswith("ms") else float(s.removesuffix("s"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds (0.12) or milliseconds (120ms), got {text!r}") from None
    if not 0.0 <= value <= 2.0:
        raise argparse.ArgumentTypeError(f"must be within 0..2 s, got {text!r}")
    return value


def _recording_skip() -> tuple[str, ...]:
    """Sinks a live recording cannot write: those that render frames or need a simulation."""
    from visemeface.export import SINKS

    return tuple(n for n, c in SINKS.items() if c.needs_image or c.needs_physics or n == "video")


def register(subparsers) -> None:
    from visemeface.export.sinks import add_sink_arguments
    from visemeface.live.audio import FORMATS
    from visemeface.live.senders import VMC_NAMES
    from visemeface.speech.timeline import MODES

    p = subparsers.add_parser(
        "live",
        help="live lip sync: a microphone, stream or recording to VMC/OSC/WebSocket blend shapes",
        description="Recognise the phones of live audio as they are spoken and send the mouth's blend "
        "shapes (ARKit or VRM) with a bounded delay: over the VMC protocol (VSeeFace, VNyan, Warudo, "
        "VMagicMirror), as OSC messages, or as a WebSocket JSON stream; optionally recorded to the "
        "offline outputs.", epilog=EPILOG, formatter_class=opt.Help)
    p.add_argument("audio", nargs="?", metavar="AUDIO",
                   help="a recording played in real time, or '-' for a stream on stdin (omit with --mic)")
    src = p.add_argument_group("input")
    src.add_argument("--mic", action="store_true", help="read the default microphone (needs visemeface[live])")
    src.add_argument("--device", help="with --mic: the input device's name or number (default: the system's)")
    src.add_argument("--format", choices=tuple(FORMATS), default="s16le",
                     help="raw stdin samples: s16le (default), s32le or f32le (a WAV stream says its own)")
    src.add_argument("--sample-rate", type=int, default=16000, help="raw stdin sample rate in Hz (default 16000)")
    src.add_argument("--channels", type=int, default=1, help="raw stdin channels, mixed to mono (default 1)")
    src.add_argument("--fast", action="store_true",
                     help="a recording: read it as fast as it is decoded, not in real time (messages keep "
                     "their times in /VMC/Ext/T)")
    src.add_argument("--duration", type=float, metavar="S", help="stop after S seconds of audio")
    mouth = p.add_argument_group("mouth")
    mouth.add_argument("--latency", type=_latency, default=LATENCY, metavar="S",
                       help=f"delay from a sound to its frame, seconds or '120ms' (default {LATENCY:g}): "
                       "longer looks further ahead and recognises more surely")
    mouth.add_argument("--fps", type=float, default=30.0, help="frames per second sent (default 30)")
    mouth.add_argument("--interp", choices=MODES, default=MODES[0],
                       help="interpolation between visemes (default: Cohen-Massaro coarticulation)")
    mouth.add_argument("--emotion", action="append", metavar="NAME[=W]",
                       help="blend an emotion over the whole stream, e.g. happiness=0.4 (repeatable)")
    opt.add_face_arguments(p)
    out = p.add_argument_group("sent to (only the addresses given)")
    out.add_argument("--vmc", metavar="HOST:PORT",
                     help=f"VMC protocol receiver (OSC over UDP), e.g. 127.0.0.1:{VMC_PORT}")
    out.add_argument("--vmc-names", choices=VMC_NAMES, default="arkit",
                     help="blend shape names over VMC: arkit (52, 'perfect sync'; default), vrm (VRM 1.0 "
                     "aa ih ou ee oh ...), vrm0 (VRM 0.x A I U E O ...)")
    out.add_argument("--osc", metavar="HOST:PORT", help="plain OSC messages to this UDP address")
    out.add_argument("--osc-prefix", default="/visemeface", help="address prefix of --osc (default /visemeface)")
    out.add_argument("--osc-names", choices=("arkit", "vrm"), default="arkit",
                     help="the vocabulary --osc and --websocket send (default arkit)")
    out.add_argument("--websocket", metavar="HOST:PORT",
                     help="serve a WebSocket JSON stream here (e.g. 127.0.0.1:8765)")
    rec = p.add_argument_group("recorded when the stream ends (the frames sent)")
    add_sink_arguments(rec, skip=_recording_skip())
    rec.add_argument("--save-transcript", type=Path, metavar="OUT",
                     help="the phones recognised: .txt, .lab, .TextGrid or .json")
    rec.add_argument("--force", action="store_true", help="overwrite the recordings")
    opt.add_quiet(p, "no meter, no ready line or summary")
    p.set_defaults(func=run)


def _source(args):
    """The audio source of the options (checked; a stream's header is read when streaming starts)."""
    from visemeface.errors import InputError
    from visemeface.live import audio

    if args.mic:
        if args.audio is not None:
            raise InputError("--mic reads the microphone: give no AUDIO as well")
        return audio.MicSource(device=int(args.device) if args.device and args.device.isdigit() else args.device)
    if args.device is not None:
        raise InputError("--device applies to --mic")
    if args.audio is None:
        raise InputError("name the audio: a recording, '-' for stdin, or --mic")
    if args.audio == "-":
        return audio.StreamSource(sys.stdin.fileno(), rate=args.sample_rate, fmt=args.format, channels=args.channels)
    if not Path(args.audio).is_file():
        raise InputError("audio file not found", args.audio)
    return audio.FileSource(args.audio, realtime=not args.fast)


def _check_options(args) -> None:
    """Everything the options alone decide, before any file, socket or rig."""
    from visemeface.animate import parse_emotions
    from visemeface.errors import InputError
    from visemeface.live.audio import check_rate
    from visemeface.live.osc import parse_target
    from visemeface.live.senders import check_prefix
    from visemeface.postures.tables import EMOTIONS

    opt.check_fps_option(args.fps)
    if args.duration is not None and not args.duration > 0:
        raise InputError(f"--duration must be positive, got {args.duration:g}")
    check_rate(args.sample_rate, "--sample-rate")
    if args.channels < 1:
        raise InputError(f"--channels must be at least 1, got {args.channels}")
    for name in ("vmc", "osc", "websocket"):
        if getattr(args, name):
            parse_target(getattr(args, name), f"--{name}", VMC_PORT if name == "vmc" else None)
    check_prefix(args.osc_prefix)
    given = [o for o, on in (("--osc-prefix", args.osc_prefix != "/visemeface"), ("--vmc-names", args.vmc_names != "arkit"))
             if on]
    needs = {"--osc-prefix": args.osc, "--vmc-names": args.vmc}
    for option in given:
        if not needs[option]:
            raise InputError(f"{option} is an option of --{option[2:5]}, which is not given")
    if args.osc_names != "arkit" and not (args.osc or args.websocket):
        raise InputError("--osc-names is an option of --osc and --websocket, neither of which is given")
    raw = [o for o, on in (("--format", args.format != "s16le"), ("--sample-rate", args.sample_rate != 16000),
                           ("--channels", args.channels != 1)) if on]
    if raw and args.audio != "-":
        raise InputError(f"{raw[0]} describes a raw stream on stdin ('-'); a file or microphone says its own")
    if args.fast and (args.audio in (None, "-") or args.mic):
        raise InputError("--fast applies to a recording file (a stream or microphone comes at its own pace)")
    parse_emotions(args.emotion, EMOTIONS)


def _senders(args) -> list:
    """The senders of the options, their sockets open (an address in use or unreachable refused now)."""
    from visemeface.live import senders
    from visemeface.live.osc import parse_target

    out = []
    try:
        if args.vmc:
            host, port = parse_target(args.vmc, "--vmc", VMC_PORT)
            out.append(senders.VmcSender(host, port, senders.vrm0_names() if args.vmc_names == "vrm0" else None))
        if args.osc:
            out.append(senders.OscSender(*parse_target(args.osc, "--osc"), args.osc_prefix))
        if args.websocket:
            out.append(senders.WebSocketSender(*parse_target(args.websocket, "--websocket")))
    except BaseException:
        for s in out:
            s.close()
        raise
    return out


def _vocabulary_of(sender, args) -> str:
    from visemeface.live.senders import VmcSender

    if isinstance(sender, VmcSender):
        return "arkit" if args.vmc_names == "arkit" else "vrm"
    return args.osc_names


def _outputs(args):
    """(recording sinks, the staged --save-transcript or None), every target checked."""
    from visemeface.export.sinks import check_distinct, sinks_from_args
    from visemeface.outputs import Staged, check_not_inputs

    sinks = sinks_from_args(args, force=args.force, skip=_recording_skip(), video=Path.cwd() / "live")
    saved = None
    if args.save_transcript is not None:
        from visemeface.speech.writers import format_of

        format_of(args.save_transcript)
        saved = Staged(args.save_transcript, args.force)
    targets = [t for s in sinks for t in s.targets()] + ([saved.path] if saved else [])
    if args.audio not in (None, "-"):
        check_not_inputs(targets, [Path(args.audio)])
    check_distinct(sinks)
    if saved is not None and Path(saved.path).resolve() in {Path(t).resolve() for s in sinks for t in s.targets()}:
        from visemeface.errors import InputError

        raise InputError("--save-transcript and another output are the same path", saved.path)
    return sinks, saved


def _write_recording(session, rig, sinks, saved, args) -> list:
    """The recording outputs of what was sent (all or none); the paths written."""
    from visemeface.live import session as live
    from visemeface.speech.writers import format_of, write_transcript

    written = []
    try:
        if saved is not None:
            write_transcript(live.recorded_utterance(session), saved.open(), fmt=format_of(saved.path), force=True)
        if sinks:
            written += live.record(session, rig, sinks, args.interp, str(args.audio or "microphone")).written
    except BaseException:
        if saved is not None:
            saved.abort()
        raise
    if saved is not None:
        written.append(saved.commit())
    return written


def run(args) -> int:
    from visemeface.animate import parse_emotions
    from visemeface.errors import InputError
    from visemeface.live import session as live
    from visemeface.live.mouth import LiveMouth
    from visemeface.postures.library import load_expressions

    _check_options(args)
    sinks, saved = _outputs(args)
    recording = bool(sinks or saved)
    senders = _senders(args)
    if not senders and not recording:
        raise InputError("nothing to send: give --vmc, --osc or --websocket (or a recording output)")
    source = None
    try:
        source = _source(args)
        rig = opt.build_rig(args)
        emotions = parse_emotions(args.emotion, load_expressions(rig=rig).index)
        wanted = [_vocabulary_of(s, args) for s in senders] or ["arkit"]
        mouth = LiveMouth(rig, wanted, fps=args.fps, latency=args.latency, interp=args.interp,
                          emotions=emotions or None)
        for s in senders:
            vocab = _vocabulary_of(s, args)
            s.configure(vocab, mouth.names(vocab), mouth.driven(vocab))
    except BaseException:
        for s in senders:
            s.close()
        if source is not None:
            source.close()
        raise
    meter = live.Meter() if not args.quiet and live.stderr_is_terminal() else None
    if not args.quiet:
        where = ", ".join(s.what for s in senders) or "no client"
        print(f"live: {source.what} -> {where}; latency {args.latency:g} s at {args.fps:g} fps; Ctrl-C ends",
              flush=True)
    interrupted = False
    try:
        session = live.run(source, mouth, senders, meter=meter, duration=args.duration, keep=recording)
    except KeyboardInterrupt as exc:
        session = getattr(exc, "session", None)
        if session is None:
            raise
        interrupted = True
    finally:
        for s in senders:
            s.close()
    written = _write_recording(session, rig, sinks, saved, args) if recording and session.times else []
    if interrupted:
        more = f"; recorded {session.n_frames} frames -> {', '.join(map(str, written))}" if written else ""
        from visemeface.cli import interrupted_line

        interrupted_line(f"visemeface: interrupted after {session.audio_s:.2f} s of audio{more}\n")
        return 130
    if not args.quiet:
        refused = sum(getattr(getattr(s, "udp", None), "refused", 0) for s in senders)
        cpu = session.cpu_s / session.audio_s if session.audio_s > 0 else 0.0
        note = f", {refused} refused (no receiver listening)" if refused else ""
        if session.skipped:
            note += f", {session.skipped} skipped to keep up (a busy machine)"
        if not args.fast and session.wall_s + 0.5 < session.audio_s:   # cat FILE | live -: sent as it decoded
            note += f"; the audio came faster than real time, in {session.wall_s:.2f} s"
        rec = f" -> {', '.join(map(str, written))}" if written else ""
        print(f"{session.sent} frames sent over {session.audio_s:.2f} s of audio (CPU {cpu:.0%} of a core at "
              f"real time{note}){rec}")
    return 0
