"""``visemeface speak TRANSCRIPT``: a timed transcript to a talking-face video and exports.

The render and export options are shared with ``visemeface say`` (text in):
:func:`add_render_arguments` adds them, :func:`render_segments` runs the job.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

ORDER = 20

VIEWS = ("face", "mouth", "three-quarter")
PHYSICS = ("sticky", "elastic")
INTERPOLATIONS = ("coarticulation", "linear", "cosine")
FORMATS = ("auto", "timed", "lab", "phn", "textgrid", "mfa-json", "mfa-csv", "dectalk", "text")

EPILOG = """\
examples:
  visemeface speak one_five_zero_zero_six.txt                     # -> one_five_zero_zero_six.mp4
  visemeface speak a.TextGrid --audio a.wav --emotion happiness=0.6 -o a.mp4
  visemeface speak a.lab --no-video --gltf a.glb --pc2 a.pc2 --track a.csv
  visemeface speak a.txt --frames a_frames          # PNG frames too; after Ctrl-C:
  visemeface speak a.txt --frames a_frames --resume   # keeps the finished frames

Frames are streamed (pose, render, write one at a time): memory does not grow
with the length of the utterance. --frames DIR renders into DIR.partial/ and
renames it when done; --resume reuses the frames there whose render settings
match (a hidden manifest holds a hash of face, rig, track, size and view).
"""


def add_render_arguments(p: argparse.ArgumentParser) -> None:
    """Options shared by ``speak`` and ``say``: animation, rendering and exports."""
    anim = p.add_argument_group("animation")
    anim.add_argument("--emotion", action="append", metavar="NAME[=W]",
                      help="blend an emotion over the whole utterance, e.g. happiness=0.6 "
                      "(repeatable; see `visemeface emotions`)")
    anim.add_argument("--interp", choices=INTERPOLATIONS, default="coarticulation",
                      help="interpolation between visemes (default: Cohen-Massaro coarticulation)")
    anim.add_argument("--fps", type=float, default=30.0, help="frame rate (default 30)")
    anim.add_argument("--audio", type=Path, metavar="WAV",
                      help="sound to mux into the MP4 (starts at t=0; padded or cut to the animation)")
    phys = p.add_argument_group("physics (sticky lips: a finite-element lower face, saliva between the lips)")
    phys.add_argument("--physics", choices=("none",) + PHYSICS, default="none",
                      help="none (default): the kinematic rig; sticky: the FEM face with saliva that glues "
                      "the lips until it breaks; elastic: the same FEM without glue (both slow: about a minute "
                      "per second of speech on one core)")
    phys.add_argument("--glue", type=float, metavar="G", help="glue strength K_glue (default 0.08)")
    phys.add_argument("--glue-profile", metavar="SPEC", help="glue across the mouth over --glue, e.g. "
                      "centre=0.18 or right=0.3,left=0 (WHERE: centre, left, right, corners, all, a..b)")
    phys.add_argument("--moisture", type=float, metavar="M", help="initial saliva moisture 0M (default 100)")
    phys.add_argument("--evaporation", type=float, metavar="E", help="moisture lost per second (default 0)")
    ren = p.add_argument_group("rendering")
    ren.add_argument("--size", type=int, default=512, help="frame width = height in pixels, a multiple "
                     "of 16 (default 512)")
    ren.add_argument("--view", choices=VIEWS, default="face", help="camera (default face)")
    ren.add_argument("--msaa", type=int, default=4, metavar="N",
                     help="antialiasing samples per pixel (default 4; 0 renders about twice as fast)")
    exp = p.add_argument_group("outputs")
    exp.add_argument("--no-video", action="store_true", help="write no MP4 (only the exports)")
    exp.add_argument("--frames", type=Path, metavar="DIR", help="also write a PNG per frame "
                     "(frame_000000.png, ...)")
    exp.add_argument("--obj", type=Path, metavar="DIR", help="also write an OBJ mesh per frame")
    exp.add_argument("--pc2", type=Path, metavar="FILE.pc2",
                     help="also write a PC2 point cache (Blender Mesh Cache modifier)")
    exp.add_argument("--gltf", type=Path, metavar="FILE.glb",
                     help="also write binary glTF: the face, one morph target per muscle, the jaw as "
                     "sampled morphs, the track as a morph-weight animation")
    exp.add_argument("--track", type=Path, metavar="FILE.csv", help="also write the activation track")
    exp.add_argument("--resume", action="store_true",
                     help="keep frames already rendered into --frames DIR by an interrupted run")
    exp.add_argument("--force", action="store_true", help="overwrite existing outputs")
    exp.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary")


def outputs_from_args(args, default_video: Path):
    """:class:`~visemeface.pipeline.Outputs` from the parsed options."""
    from visemeface.pipeline import Outputs

    video = None if args.no_video else (args.output or default_video)
    return Outputs(video=video, frames=args.frames, obj=args.obj, pc2=args.pc2, gltf=args.gltf,
                   track=args.track, force=args.force, resume=args.resume)


def check_early(args, default_video: Path):
    """Checks that need no rig or transcript: outputs, options, audio. Returns (outputs, settings)."""
    from visemeface.errors import InputError
    from visemeface.pipeline import RenderSettings, check_audio, plan_outputs

    out = outputs_from_args(args, default_video)
    plan_outputs(out)
    if not (args.fps > 0 and args.fps <= 1000):
        raise InputError(f"--fps must be in (0, 1000], got {args.fps:g}")
    if args.size < 16 or args.size % 16:
        raise InputError(f"--size must be a positive multiple of 16, got {args.size}")
    if args.msaa not in (0, 2, 4, 8, 16):
        raise InputError(f"--msaa must be 0, 2, 4, 8 or 16, got {args.msaa}")
    if args.audio is not None:
        check_audio(args.audio)
    settings = RenderSettings(size=args.size, view=args.view, msaa=args.msaa, fps=args.fps, audio=args.audio,
                              show_progress=not args.quiet)
    args.physics_settings = physics_settings(args)
    return out, settings


def physics_settings(args):
    """PhysicsSettings of ``--physics``/``--glue``/... (checked), or None for the kinematic path."""
    from visemeface.errors import InputError

    given = [f"--{n.replace('_', '-')}" for n in ("glue", "glue_profile", "moisture", "evaporation")
             if getattr(args, n, None) is not None]
    physics = getattr(args, "physics", "none")
    if physics == "none":
        if given:
            raise InputError(f"{given[0]} needs --physics sticky or elastic")
        return None
    from visemeface.physics.drive import PhysicsSettings
    from visemeface.physics.saliva import GLUE, SalivaParams

    glue = GLUE if args.glue is None else args.glue
    if not (glue >= 0 and glue < float("inf")):
        raise InputError(f"--glue must be >= 0, got {glue:g}")
    params = {}
    if args.moisture is not None:
        params["initial_moisture"] = args.moisture
    if args.evaporation is not None:
        params["evaporation"] = args.evaporation
    try:
        saliva = dataclasses.replace(SalivaParams(), **params)
    except InputError as e:
        raise InputError(str(e).replace("moisture must", "--moisture must")
                         .replace("evaporation rate must", "--evaporation must")) from None
    return PhysicsSettings(glue=glue, glue_profile=args.glue_profile, saliva=saliva)


#: Longest utterance one run animates (s): longer means wrong units far more often than a 3-hour take.
MAX_UTTERANCE_S = 3 * 3600


def render_segments(segments, args, out, settings) -> int:
    """Segments -> activation track -> video and exports; prints a summary."""
    from visemeface.errors import InputError
    from visemeface.muscles.rig import default_rig
    from visemeface.pipeline import animate, parse_emotions
    from visemeface.postures.library import load_expressions, load_visemes
    from visemeface.speech.timeline import activation_track

    length = float(segments["end"].max()) if len(segments) else 0.0
    if length > MAX_UTTERANCE_S:
        raise InputError(f"the transcript lasts {length:.0f} s, over the {MAX_UTTERANCE_S} s limit of one run "
                         "(wrong time units? try --format / --sample-rate)")
    rig = default_rig()
    emotions = parse_emotions(args.emotion, load_expressions(rig=rig).index)
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    track = activation_track(segments, load_visemes(rig=rig), fps=args.fps, mode=args.interp,
                             emotions=emotions or None, ranges=ranges)
    if settings.audio is not None and out.video is not None:
        import warnings

        from visemeface.pipeline import check_audio

        audio_s, video_s = check_audio(settings.audio), len(track) / args.fps
        if abs(audio_s - video_s) > 1.0 / args.fps:
            what = "padded with silence" if audio_s < video_s else "cut"
            warnings.warn(f"{settings.audio}: the audio lasts {audio_s:.2f} s, the animation {video_s:.2f} s; "
                          f"the audio is {what} to the animation", stacklevel=2)
    poses, key = None, ""
    physics = getattr(args, "physics_settings", None)
    if physics is not None:
        # Build the FEM face and check glue profile, time step etc. before any simulation.
        from visemeface.physics.drive import StickySimulation
        from visemeface.physics.face_model import build_fem_face

        sim = StickySimulation(build_fem_face(rig.face), rig, track, physics=args.physics, settings=physics)
        poses = (fr.display for fr in sim.frames())
        key = f"/{args.physics}/{sim.fingerprint()}"
    stats = animate(track, rig, out, settings, end_time=float(segments["end"].iloc[-1]), poses=poses,
                    poses_key=key)
    if not args.quiet:
        written = [str(p) for p in out.paths().values()]
        extra = f", {stats['kept']} kept from the previous run" if stats["kept"] else ""
        print(f"{stats['frames']} frames ({stats['frames'] / args.fps:.2f} s at {args.fps:g} fps{extra}) "
              f"-> {', '.join(written)}")
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "speak",
        help="animate a timed transcript: MP4 video (+ audio) and PNG/OBJ/PC2/glTF exports",
        description="Animate the face along a timed phoneme transcript (timed text, HTK .lab, TIMIT .PHN, "
        "Praat/MFA TextGrid, MFA JSON/CSV, DECtalk string, or plain English text) and write an MP4 "
        "(TRANSCRIPT's stem + .mp4 in the current folder unless -o) and any exports.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("transcript", type=Path, metavar="TRANSCRIPT", help="timed phoneme transcript")
    p.add_argument("-o", "--output", type=Path, metavar="OUT.mp4", help="video file to write")
    src = p.add_argument_group("transcript")
    src.add_argument("--format", choices=FORMATS, default="auto",
                     help="transcript format (default: detected from the content)")
    src.add_argument("--tier", help="TextGrid tier with the phones (default: the phone tier)")
    src.add_argument("--sample-rate", type=int, default=16000,
                     help="sample rate of TIMIT .PHN sample indices (default 16000)")
    src.add_argument("--alphabet", help="phone alphabet of the labels: dectalk, arpabet, timit, ipa/mfa "
                     "(default: detected)")
    src.add_argument("--rate", type=float, metavar="WPM",
                     help="plain-text transcripts only: speaking rate in words per minute "
                     "(with --audio the text is timed to the recording instead)")
    add_render_arguments(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from visemeface.errors import InputError

    if not args.transcript.is_file():
        raise InputError("transcript not found", args.transcript)
    out, settings = check_early(args, Path.cwd() / (args.transcript.stem + ".mp4"))
    from visemeface.speech.transcripts import read_transcript

    fmt = None if args.format == "auto" else args.format
    segments = read_transcript(args.transcript, fmt=fmt, tier=args.tier, sample_rate=args.sample_rate,
                               alphabet=args.alphabet, rate_wpm=args.rate, audio=args.audio)
    return render_segments(segments, args, out, settings)
