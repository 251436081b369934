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
  visemeface speak a.lab --no-video --gltf a.glb --pc2 a.pc2 --track a.csv
  visemeface speak a.txt --frames a_frames          # PNG frames too; after Ctrl-C:
  visemeface speak a.txt --frames a_frames --resume   # keeps the finished frames
  visemeface speak a.txt --face my_head.obj -o mine.mp4   # any mesh with a .landmarks.json
  visemeface speak a.txt --physics sticky -o sticky.mp4   # after Ctrl-C: --resume continues the simulation

Frames are streamed (pose or simulate, render, write one at a time): memory does
not grow with the length of the utterance, and all outputs appear together when
the run is complete. --frames DIR renders into DIR.partial/ and --resume reuses
the frames there whose settings match; with --physics the simulation saves its
state after every frame in OUT.mp4.checkpoint/ and --resume continues from it.
"""

#: Longest utterance one run animates (s): longer means wrong units far more often than a 3-hour take.
MAX_UTTERANCE_S = 3 * 3600


def add_animation_arguments(p: argparse.ArgumentParser, video_default: str) -> None:
    """Options shared by ``speak`` and ``say``: animation, face, physics, rendering, outputs."""
    from visemeface.physics.drive import PHYSICS
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
    anim.add_argument("--audio", type=Path, metavar="WAV",
                      help="sound to mux into the MP4 (starts at t=0; padded or cut to the animation)")
    opt.add_face_arguments(p)
    opt.add_physics_arguments(p, "none", ("none",) + tuple(PHYSICS))
    opt.add_render_arguments(p)
    opt.add_output_arguments(p, video_default, resumable="continue an interrupted run: keep the frames "
                             "rendered into --frames DIR, continue a --physics simulation from its checkpoint")


def check_early(args, default_video: Path):
    """Everything that needs no transcript or rig: outputs, render settings, fps, audio, physics.

    Returns (sinks, render settings, physics settings or None).
    """
    from visemeface.pipeline import check_audio

    sinks = opt.sinks_from_args(args, default_video)
    render = opt.render_from_args(args)
    opt.check_fps_option(args.fps)
    if args.audio is not None:
        check_audio(args.audio)
    return sinks, render, opt.physics_from_args(args)


def parse_emotions(specs, known) -> dict[str, float]:
    """``["happiness=0.6", "anger"]`` -> ``{"happiness": 0.6, "anger": 1.0}``, names checked."""
    from visemeface.errors import InputError, close_matches
    from visemeface.postures.library import parse_weights

    emotions = parse_weights(specs)
    known = list(known)
    for name in emotions:
        if name not in known:
            raise InputError(f"unknown emotion {name!r}{close_matches(name, known)}")
    return emotions


def _warn_audio_length(audio, track, fps) -> None:
    import warnings

    from visemeface.pipeline import check_audio

    audio_s, video_s = check_audio(audio), len(track) / fps
    if abs(audio_s - video_s) > 1.0 / fps:
        what = "padded with silence" if audio_s < video_s else "cut"
        warnings.warn(f"{audio}: the audio lasts {audio_s:.2f} s, the animation {video_s:.2f} s; "
                      f"the audio is {what} to the animation", stacklevel=3)


def animate_utterance(utterance, args, sinks, render, physics) -> int:
    """Utterance -> activation track -> motion (rig or FEM face) -> the sinks; prints a summary."""
    from visemeface import pipeline
    from visemeface.errors import InputError
    from visemeface.motion import KinematicMotion
    from visemeface.postures.library import load_expressions, load_visemes
    from visemeface.speech.timeline import activation_track

    if utterance.end > MAX_UTTERANCE_S:
        raise InputError(f"the transcript lasts {utterance.end:.0f} s, over the {MAX_UTTERANCE_S} s limit of one "
                         "run (wrong time units? try --format / --sample-rate)")
    rig = opt.build_rig(args)
    emotions = parse_emotions(args.emotion, load_expressions(rig=rig).index)
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    track = activation_track(utterance, load_visemes(rig=rig), fps=args.fps, mode=args.interp,
                             emotions=emotions or None, ranges=ranges)
    if not args.no_blink:
        from visemeface.speech.blinks import blink_utterance
        track = blink_utterance(track, rig, utterance)
    if args.audio is not None and any(s.name == "video" for s in sinks):
        _warn_audio_length(args.audio, track, args.fps)
    if physics is None:
        motion = KinematicMotion(rig, track)
    else:
        motion = opt.simulation_of(rig, track, args.physics, physics)
    checkpoint = opt.checkpoint_of(motion, sinks, args)
    stats = pipeline.run(motion, sinks, render,
                         info=dict(audio=args.audio, rig=rig, track=track, end_time=utterance.end,
                                   extra={"motion_key": motion.key()}),
                         checkpoint=checkpoint, resume=args.resume, show_progress=not args.quiet)
    if not args.quiet:
        print(pipeline.summary(stats, args.fps))
    return 0


def register(subparsers) -> None:
    from visemeface.speech.transcripts import FORMATS

    p = subparsers.add_parser(
        "speak",
        help="animate a timed transcript: MP4 video (+ audio) and PNG/OBJ/PC2/glTF exports",
        description="Animate the face along a timed phoneme transcript (timed text, HTK .lab, TIMIT .PHN, "
        "Praat/MFA TextGrid, MFA JSON/CSV, DECtalk string, or plain English text) and write an MP4 "
        "(TRANSCRIPT's stem + .mp4 in the current folder unless -o) and any exports.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("transcript", type=Path, metavar="TRANSCRIPT", help="timed phoneme transcript")
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
    add_animation_arguments(p, "TRANSCRIPT's stem + .mp4")
    p.set_defaults(func=run)


def run(args) -> int:
    from visemeface.errors import InputError
    from visemeface.speech.transcripts import read_utterance

    if not args.transcript.is_file():
        raise InputError("transcript not found", args.transcript)
    sinks, render, physics = check_early(args, Path.cwd() / (args.transcript.stem + ".mp4"))
    fmt = None if args.format == "auto" else args.format
    utterance = read_utterance(args.transcript, fmt=fmt, tier=args.tier, sample_rate=args.sample_rate,
                               alphabet=args.alphabet, rate_wpm=args.rate, audio=args.audio)
    return animate_utterance(utterance, args, sinks, render, physics)
