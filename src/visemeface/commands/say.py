"""``visemeface say "TEXT"``: English text to a talking-face video (same machinery as ``speak``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from visemeface.commands._options import Help
from visemeface.commands.speak import add_animation_arguments, animate_utterance, check_early, check_rig_and_emotions

ORDER = 21

EPILOG = """\
examples:
  visemeface say "one five zero zero six"                        # -> say.mp4
  visemeface say "Hello there." --emotion happiness=0.6 -o hello.mp4
  visemeface say "[anger 0.8] Bob moves five boats. [happiness] One five zero zero six!" -o tags.mp4
  visemeface say "Hello there." --audio hello.wav -o hello.mp4   # the words aligned to the recording
  visemeface say "Hello there." --silent -o quiet.mp4           # no synthesised voice

With the optional extra installed (pip install "visemeface[tts]": eSpeak NG, GPL-3.0) the text is
spoken, the phones are aligned to that sound (or, where it does not align, timed by the
synthesiser's own phone events) and it is muxed into the video; without it the video is silent
and the phones are timed by the duration model (--rate).
"""


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "say",
        help="animate English text (words -> phonemes -> video)",
        description="Turn English text into phonemes (CMU dictionary, numbers, ordinals and money spelled out, "
        "a letter-to-sound fallback for unknown words), time them (--rate, or aligned to a recording of them, --audio) and "
        "animate the face. Takes every option of `visemeface speak` after the transcript.",
        epilog=EPILOG, formatter_class=Help)
    p.add_argument("text", metavar="TEXT", help="what to say (quote it)")
    p.add_argument("--rate", type=float, metavar="WPM", default=None,
                   help="speaking rate in words per minute (not with --audio, which times the text)")
    p.add_argument("--silent", action="store_true",
                   help="no synthesised voice even with the tts extra: the duration model times the text")
    add_animation_arguments(p, "say.mp4")
    p.set_defaults(func=run)


def run(args) -> int:
    import sys
    import tempfile

    from visemeface.errors import InputError
    from visemeface.speech import tts
    from visemeface.speech.g2p import text_to_utterance
    from visemeface.speech.transcripts import timed_text

    if not args.text.strip():
        raise InputError("nothing to say: the text is empty")
    if args.rate is not None and args.audio is not None:
        raise InputError("--rate and --audio both time the text; give one")
    sinks, render, physics, saved = check_early(args, Path.cwd() / "say.mp4")
    speak_aloud = args.audio is None and not args.silent
    if not speak_aloud or not tts.available():
        utterance = timed_text(args.text, args.rate, args.audio)
        status = animate_utterance(utterance, args, sinks, render, physics, saved=saved)
        if speak_aloud and not args.quiet and any(s.name == "video" for s in sinks):
            print(f"visemeface: note: {tts.HINT}", file=sys.stderr)   # after the run: an error stays the only line
        return status
    text_to_utterance(args.text, rate_wpm=args.rate)        # the text's own errors first (tags, rate)
    rig = check_rig_and_emotions(args)                      # and the face's and emotions' before speaking
    with tempfile.TemporaryDirectory(prefix="visemeface-") as folder:
        synthesis = tts.synthesise(args.text, Path(folder) / "say.wav", rate_wpm=args.rate)
        utterance, how = tts.utterance_of(synthesis, args.text, args.rate)
        status = animate_utterance(utterance, args, sinks, render, physics, audio=synthesis.path, saved=saved,
                                   rig=rig)
    if how != "aligned" and not args.quiet:                  # after the run: an error stays the only line
        print(f"visemeface: note: the synthesised speech timed by {'its phone events' if how == 'events' else how}"
              " (its sound did not align to the text)", file=sys.stderr)
    return status
