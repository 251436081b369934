"""``visemeface lipsync RECORDING``: the timed phones of a recording, written as a transcript.

Only the timing (no video): forced alignment of the words (``--text``,
``--text-file``, or a same-named ``.txt`` beside the recording), else phone
recognition. ``speak RECORDING`` shares :func:`add_text_arguments` and
:func:`recording_utterance`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

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


def add_text_arguments(g) -> None:
    """``--text``, ``--text-file`` (the words of a recording)."""
    g.add_argument("--text", metavar="WORDS", help="what the recording says: forced alignment (accurate); "
                   "default: the text of a same-named .txt beside the recording, else phone recognition")
    g.add_argument("--text-file", type=Path, metavar="TXT", help="read the words from a text file")


def text_of(recording: Path, text, text_file, quiet: bool = False):
    """The words for ``recording``: ``text``, the file's, a same-named .txt beside it, or None."""
    from visemeface.errors import InputError
    from visemeface.textfile import read_text

    if text is not None and text_file is not None:
        raise InputError("--text and --text-file both give the words; give one")
    if text is not None:
        if not text.strip():
            raise InputError("--text is empty")
        return text, None
    beside = recording.with_suffix(".txt")
    path = text_file if text_file is not None else (beside if beside.is_file() else None)
    if path is None:
        return None, None
    words = read_text(path, "text file")
    if text_file is None and not quiet:
        import sys

        print(f"visemeface: aligning the words of {path}", file=sys.stderr)
    return words, path


def recording_utterance(recording: Path, text, text_file, quiet: bool = False):
    """Utterance of a recording: aligned to its words if any, else recognised."""
    from visemeface.speech.align import utterance_from_audio

    words, path = text_of(recording, text, text_file, quiet)
    return utterance_from_audio(recording, words, text_where=path)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "lipsync",
        help="timed phones of a recording (forced alignment or recognition) as a transcript",
        description="Find when each phone of a recording is spoken, offline (pocketsphinx's US-English model): "
        "forced alignment of the words if given, else phone recognition. Writes a transcript that "
        "`visemeface speak` animates.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("recording", type=Path, metavar="RECORDING", help="sound file or video with speech")
    add_text_arguments(p)
    p.add_argument("-o", "--output", type=Path, metavar="OUT",
                   help="transcript to write: .txt, .lab, .TextGrid or .json (default RECORDING's stem + "
                   ".TextGrid in the current folder)")
    p.add_argument("--force", action="store_true", help="overwrite the output")
    p.add_argument("-q", "--quiet", action="store_true", help="no summary")
    p.set_defaults(func=run)


def run(args) -> int:
    from visemeface.errors import InputError
    from visemeface.outputs import check_new
    from visemeface.speech.writers import format_of, write_transcript

    if not args.recording.is_file():
        raise InputError("recording not found", args.recording)
    out = args.output if args.output is not None else Path.cwd() / (args.recording.stem + ".TextGrid")
    format_of(out)
    check_new(out, args.force)
    utterance = recording_utterance(args.recording, args.text, args.text_file, args.quiet)
    write_transcript(utterance, out, force=args.force)
    if not args.quiet:
        seg = utterance.segments
        n = int((seg["phoneme"] != "_").sum())
        how = "aligned" if utterance.source_format == "aligned" else "recognised (no text)"
        print(f"{n} phones, {len(utterance.words)} words {how} over {utterance.end:.2f} s -> {out}")
    return 0
