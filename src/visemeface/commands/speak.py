"""``visemeface speak TRANSCRIPT``: a timed transcript to a talking-face video and exports.

``say`` (text in) shares everything after the transcript: :func:`add_animation_arguments`
adds the options, :func:`animate_utterance` runs the job through the one
streaming loop (:func:`visemeface.pipeline.run`).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from visemeface.commands import _options as opt

ORDER = 20

EPILOG = """\
examples:
  visemeface speak one_five_zero_zero_six.txt                     # -> one_five_zero_zero_six.mp4
  visemeface speak a.TextGrid --audio a.wav --emotion happiness=0.6 -o a.mp4
  visemeface speak a.lab --no-video --gltf a.glb --arkit a.csv --rhubarb a.tsv
  visemeface speak a.txt --frames a_frames          # PNG frames too; after Ctrl-C:
  visemeface speak a.txt --frames a_frames --resume   # keeps the finished frames
  visemeface speak a.txt --face my_head.obj -o mine.mp4   # any mesh with a .landmarks.json
  visemeface speak a.txt --physics sticky -o sticky.mp4   # after Ctrl-C: --resume continues the simulation
  visemeface speak take.wav --text "set white with p two soon"   # a recording: aligned, its sound muxed
  visemeface speak take.wav --save-transcript take.TextGrid      # no text: phones recognised; keep them

Frames are streamed (pose or simulate, render, write one at a time): memory does
not grow with the length of the utterance, and all outputs appear together when
the run is complete. --frames DIR renders into DIR.partial/ and --resume reuses
the frames there whose settings match; with --physics the simulation saves its
state after every frame in OUT.mp4.checkpoint/ and --resume continues from it.
"""


def add_animation_arguments(p: argparse.ArgumentParser, video_default: str) -> None:
    """Options shared by ``speak`` and ``say``: animation, face, physics, rendering, outputs."""
    from visemeface.physics import PHYSICS
    from visemeface.speech.timeline import MODES

    anim = p.add_argument_group("animation")
    anim.add_argument("--emotion", action="append", metavar="NAME[=W]",
                      help="blend an emotion over the whole utterance, e.g. happiness=0.6 "
                      "(repeatable; see `visemeface emotions`)")
    anim.add_argument("--interp", choices=MODES, default=MODES[0],
                      help="interpolation between visemes (default: Cohen-Massaro coarticulation)")
    anim.add_argument("--fps", type=float, default=30.0, help="frame rate (default 30)")
    anim.add_argument("--no-blink", action="store_true",
                      help="do not blink (default: about 17 blinks a minute, at word boundaries, the same every run)")
    anim.add_argument("--articulation", type=float, default=1.0, metavar="A",
                      help="0..2: how much the recording's loudness and formants (else the text's stress and "
                      "*emphasis*) widen or narrow each phone's jaw and lips (JALI; default 1, 0 = the tabled visemes)")
    anim.add_argument("--no-gestures", action="store_true",
                      help="keep the head, brows and gaze still (default: nods on pitch accents, a head pose per "
                      "phrase, brow raises, gaze saccades; the same every run)")
    anim.add_argument("--audio", type=Path, metavar="WAV",
                      help="a recording to mux into the MP4 (starts at t=0): plain text is aligned to it; the "
                      "face rests after the last phone until it ends")
    anim.add_argument("--save-transcript", type=Path, metavar="OUT",
                      help="also write the timed phones (read, aligned or recognised): .txt, .lab, .TextGrid or .json")
    opt.add_face_arguments(p)
    opt.add_physics_arguments(p, "none", ("none",) + tuple(PHYSICS))
    opt.add_render_arguments(p)
    opt.add_output_arguments(p, video_default, resumable="continue an interrupted run: keep the frames "
                             "rendered into --frames DIR, continue a --physics simulation from its checkpoint")


def check_early(args, default_video: Path, inputs=(), recording: Path | None = None):
    """Everything that needs no transcript or rig: outputs, render settings, fps, audio, physics.

    Returns (sinks, render settings, physics settings or None, the staged ``--save-transcript`` or None);
    refuses an output that is one of ``inputs`` (paths), the words of ``recording``
    (:func:`~visemeface.commands._options.check_not_words`) or another output.
    """
    from visemeface.errors import InputError
    from visemeface.export.sinks import check_physics_outputs
    from visemeface.outputs import check_not_inputs
    from visemeface.pipeline import check_audio

    sinks = opt.sinks_from_args(args, default_video)
    render = opt.render_from_args(args)
    opt.check_fps_option(args.fps)
    if args.audio is not None:
        check_audio(args.audio)
    saved = _transcript_target(args)
    targets = [t for s in sinks for t in s.targets()]
    written = targets + ([saved.path] if saved is not None else [])
    check_not_inputs(written, [*inputs, *([args.audio] if args.audio is not None else [])])
    if recording is not None:
        opt.check_not_words(written, recording, args.text_file)
    if saved is not None and Path(saved.path).resolve() in {Path(t).resolve() for t in targets}:
        raise InputError("--save-transcript and another output are the same path", saved.path)
    physics = opt.physics_from_args(args)
    check_physics_outputs([s.name for s in sinks], physics)
    from visemeface.speech.articulation import check_articulation

    check_articulation(args.articulation)
    return sinks, render, physics, saved


def check_rig_and_emotions(args):
    """The rig of ``--face``/``--landmarks``/``--rig`` with ``--emotion`` checked against its expressions
    (before work that needs neither, such as synthesising and aligning speech)."""
    from visemeface.animate import parse_emotions
    from visemeface.postures.library import load_expressions

    rig = opt.build_rig(args)
    parse_emotions(args.emotion, load_expressions(rig=rig).index)
    return rig


def animate_utterance(utterance, args, sinks, render, physics, audio=None, saved=None, rig=None) -> int:
    """Utterance -> the sinks through :func:`visemeface.animate.animate`; prints a summary.

    ``audio`` (default ``--audio``) is the sound muxed into the video; ``saved`` the staged
    ``--save-transcript`` (:func:`check_early`), written with the other outputs or not at all.
    """
    from visemeface import pipeline
    from visemeface.animate import animate
    from visemeface.runtime import landing
    from visemeface.speech.writers import format_of, write_transcript

    try:
        if saved is not None:
            write_transcript(utterance, saved.open(), fmt=format_of(saved.path), force=True)
        stats = None if not sinks else animate(   # no sinks: only the timed phones (--no-video --save-transcript)
            utterance, sinks, render, rig=opt.build_rig(args) if rig is None else rig, emotions=args.emotion, interp=args.interp,
            fps=args.fps, audio=args.audio if audio is None else audio, physics=args.physics,
            physics_settings=physics, checkpoint=lambda motion: opt.checkpoint_of(motion, sinks, args),
            resume=args.resume, show_progress=not args.quiet, source=str(getattr(args, "transcript", None) or "text"),
            blink=not args.no_blink, articulation=args.articulation, gestures=not args.no_gestures,
            also=[saved] if saved is not None else [], final=True)
        if stats is None and saved is not None:
            with landing(final=True):
                saved.commit()
    except BaseException:
        if saved is not None:
            saved.abort()
        raise
    if not args.quiet:
        if stats is not None:
            print(pipeline.summary(stats, args.fps))
        if saved is not None:
            print(f"timed phones -> {saved.path}")
    return 0


def register(subparsers) -> None:
    from visemeface.speech.transcripts import FORMATS

    p = subparsers.add_parser(
        "speak",
        help="animate a timed transcript: MP4 video (+ audio) and PNG/OBJ/PC2/glTF exports",
        description="Animate the face along a timed phoneme transcript (timed text, HTK .lab, TIMIT .PHN, "
        "Praat/MFA TextGrid, MFA JSON/CSV, DECtalk string, or plain English text) or a recording "
        "(its phones aligned to --text, else recognised; its sound muxed) and write an MP4 "
        "(TRANSCRIPT's stem + .mp4 in the current folder unless -o) and any exports.",
        epilog=EPILOG, formatter_class=opt.Help)
    p.add_argument("transcript", type=Path, metavar="TRANSCRIPT",
                   help="timed phoneme transcript, or a recording (WAV/FLAC/OGG/MP3, a video's sound)")
    src = p.add_argument_group("transcript")
    src.add_argument("--format", choices=("auto",) + FORMATS, default="auto",
                     help="transcript format (default: detected from the content)")
    src.add_argument("--tier", help="TextGrid tier with the phones (default: the phone tier)")
    src.add_argument("--sample-rate", type=int, default=16000,
                     help="sample rate of TIMIT .PHN sample indices (default 16000)")
    src.add_argument("--alphabet", help="phone alphabet of the labels: dectalk, arpabet, timit, ipa/mfa "
                     "(default: detected)")
    src.add_argument("--rate", type=float, metavar="WPM",
                     help="plain-text transcripts only: speaking rate in words per minute "
                     "(with --audio the text is timed to the recording instead)")

    opt.add_text_arguments(src)
    add_animation_arguments(p, "TRANSCRIPT's stem + .mp4")
    p.set_defaults(func=run)


def _transcript_target(args):
    """The staged --save-transcript output (checked before any work), or None."""
    if args.save_transcript is None:
        return None
    from visemeface.outputs import Staged
    from visemeface.speech.writers import format_of

    format_of(args.save_transcript)
    return Staged(args.save_transcript, args.force)


def _read_input(args):
    """(Utterance, sound to mux or None) of the transcript or recording."""
    from visemeface.errors import InputError
    from visemeface.speech.audio import is_recording
    from visemeface.speech.transcripts import read_utterance

    if is_recording(args.transcript):
        if args.audio is not None:
            raise InputError("--audio: a recording is its own sound; leave --audio out")
        bad = [o for o, v in (("--format", args.format != "auto"), ("--tier", args.tier), ("--rate", args.rate),
                              ("--alphabet", args.alphabet)) if v]
        if bad:
            raise InputError(f"{bad[0]} applies to transcripts, not to a recording")
        return opt.recording_utterance(args.transcript, args.text, args.text_file, args.quiet), args.transcript
    if args.text is not None or args.text_file is not None:
        raise InputError("--text/--text-file give the words of a recording; the input is a transcript")
    fmt = None if args.format == "auto" else args.format
    return read_utterance(args.transcript, fmt=fmt, tier=args.tier, sample_rate=args.sample_rate,
                          alphabet=args.alphabet, rate_wpm=args.rate, audio=args.audio), None


def run(args) -> int:
    import tempfile

    from visemeface.errors import InputError
    from visemeface.speech.audio import is_recording, media_wav

    if not args.transcript.is_file():
        raise InputError("transcript is a folder, not a file" if args.transcript.is_dir() else "transcript not found",
                         args.transcript)
    sinks, render, physics, saved = check_early(
        args, Path.cwd() / (args.transcript.stem + ".mp4"), inputs=[args.transcript],
        recording=args.transcript if is_recording(args.transcript) else None)
    rig = check_rig_and_emotions(args) if is_recording(args.transcript) else None   # before the alignment
    utterance, recording = _read_input(args)
    with tempfile.TemporaryDirectory(prefix="visemeface-") as folder:
        sound = None if recording is None else media_wav(recording, folder)
        return animate_utterance(utterance, args, sinks, render, physics, audio=sound, saved=saved, rig=rig)
