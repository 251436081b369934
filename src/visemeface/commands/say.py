"""``visemeface say "TEXT"``: English text to a talking-face video (same machinery as ``speak``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from visemeface.commands.speak import add_render_arguments, check_early, render_segments

ORDER = 21

EPILOG = """\
examples:
  visemeface say "one five zero zero six"                        # -> say.mp4
  visemeface say "Hello there." --emotion happiness=0.6 -o hello.mp4
  visemeface say "Hello there." --audio hello.wav -o hello.mp4   # timing stretched to the audio
"""


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "say",
        help="animate English text (words -> phonemes -> video)",
        description="Turn English text into phonemes (CMU dictionary, numbers spelled out, a letter-to-sound "
        "fallback for unknown words), time them (--rate, or stretched to --audio) and animate the face. "
        "Takes every render/export option of `visemeface speak`.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("text", metavar="TEXT", help="what to say (quote it)")
    p.add_argument("-o", "--output", type=Path, metavar="OUT.mp4", help="video file (default say.mp4)")
    p.add_argument("--rate", type=float, metavar="WPM", default=None,
                   help="speaking rate in words per minute (ignored with --audio)")
    add_render_arguments(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from visemeface.errors import InputError
    from visemeface.speech.g2p import text_to_segments

    if not args.text.strip():
        raise InputError("nothing to say: the text is empty")
    out, settings = check_early(args, Path.cwd() / "say.mp4")
    segments = text_to_segments(args.text, rate_wpm=args.rate, audio=args.audio)
    return render_segments(segments, args, out, settings)
