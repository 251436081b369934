"""``visemeface lipsync RECORDING``: the timed phones of a recording, written as a transcript.

Only the timing (no video): forced alignment of the words (``--text``,
``--text-file``, or a same-named ``.txt`` beside the recording), else phone
recognition. ``speak RECORDING`` shares :func:`add_text_arguments` and
:func:`recording_utterance`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from visemeface.commands import _options as opt

ORDER = 22

EPILOG = """\
examples:
  visemeface lipsync take.wav --text "set white with p two soon" -o take.TextGrid
  visemeface lipsync take.wav -o take.lab                  # no text: phones recognised (less accurate)
  visemeface lipsync clip.mp4 --text-file clip_words.txt -o clip.json
  visemeface speak take.TextGrid --audio take.wav         # animate it (after correcting it in Praat)

Recordings: WAV, FLAC, OGG, MP3 and the audio track of a video (anything ffmpeg reads).
Outputs (by suffix): .txt timed phones, .lab HTK labels, .TextGrid (words and phones tiers),
.json Montreal-Forced-Aligner JSON. Phones are DECtalk symbols.
"""


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "lipsync",
        help="timed phones of a recording (forced alignment or recognition) as a transcript",
        description="Find when each phone of a recording is spoken, offline (pocketsphinx's US-English model): "
        "forced alignment of the words if given, else phone recognition. Writes a transcript that "
        "`visemeface speak` animates.",
        epilog=EPILOG, formatter_class=opt.Help)
    p.add_argument("recording", type=Path, metavar="RECORDING", help="sound file or video with speech")
    opt.add_text_arguments(p)
    p.add_argument("-o", "--output", type=Path, metavar="OUT",
                   help="transcript to write: .txt, .lab, .TextGrid or .json (default RECORDING's stem + "
                   ".TextGrid in the current folder)")
    p.add_argument("--force", action="store_true", help="overwrite the output")
    opt.add_quiet(p, "no summary")
    p.set_defaults(func=run)


def run(args) -> int:
    from visemeface.errors import InputError
    from visemeface.outputs import check_new, check_not_inputs
    from visemeface.speech.writers import format_of, write_transcript

    if not args.recording.is_file():
        raise InputError("recording not found", args.recording)
    out = args.output if args.output is not None else Path.cwd() / (args.recording.stem + ".TextGrid")
    format_of(out)
    check_not_inputs([out], [args.recording])
    opt.check_not_words([out], args.recording, args.text_file)
    check_new(out, args.force)
    utterance = opt.recording_utterance(args.recording, args.text, args.text_file, args.quiet)
    write_transcript(utterance, out, force=args.force)
    if not args.quiet:
        seg = utterance.segments
        n = int((seg["phoneme"] != "_").sum())
        how = "aligned" if utterance.source_format == "aligned" else "recognised (no text)"
        print(f"{n} phones, {len(utterance.words)} words {how} over {utterance.end:.2f} s -> {out}")
    return 0
