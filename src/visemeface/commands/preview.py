"""``visemeface preview utt.glb --audio utt.wav -o utt.html``: a self-contained web page that plays a .glb."""

from __future__ import annotations

import argparse
from pathlib import Path

from visemeface.commands import _options as opt

ORDER = 22

EPILOG = """\
examples:
  visemeface speak utt.TextGrid --audio utt.wav --no-video --gltf utt.glb
  visemeface preview utt.glb --audio utt.wav -o utt.html      # open utt.html in any browser, offline
  visemeface speak utt.TextGrid --audio utt.wav --preview utt.html   # the same in one run

The page inlines three.js (MIT licence), the animation and the sound: it opens from file:// with no
network. The animation follows the sound's clock; Play/Pause and the scrubber move both; add #t=1.5
to the address to open at 1.5 s.
"""


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "preview", help="write a self-contained web page (three.js) that plays a .glb with its sound",
        description="Write one HTML page that plays a binary glTF animation (from --gltf) in sync with a "
        "sound file, with play/pause and a scrubber; three.js, the glb and the sound are inlined.",
        epilog=EPILOG, formatter_class=opt.Help)
    p.add_argument("glb", type=Path, metavar="FILE.glb", help="binary glTF animation (speak/say --gltf)")
    p.add_argument("--audio", type=Path, metavar="SOUND",
                   help="sound to play with it (.wav, .mp3, .ogg, .flac, .m4a; starts at t=0)")
    p.add_argument("-o", "--output", type=Path, metavar="FILE.html",
                   help="page to write (default: the glb's stem + .html in the current folder)")
    p.add_argument("--force", action="store_true", help="overwrite the output if it exists")
    opt.add_quiet(p, "print nothing on success")
    p.set_defaults(func=run)


def run(args) -> int:
    from visemeface.errors import InputError
    from visemeface.export.preview import AUDIO_TYPES, glb_duration, write_preview
    from visemeface.outputs import check_new, check_suffix
    from visemeface.pipeline import check_audio

    if not args.glb.is_file():
        raise InputError("glb file not found", args.glb)
    out = args.output or Path.cwd() / (args.glb.stem + ".html")
    check_suffix(out, ".html")
    check_new(out, args.force)
    data = args.glb.read_bytes()
    try:
        duration = glb_duration(data)
    except InputError as exc:
        raise InputError(str(exc), args.glb) from None
    if args.audio is not None:
        if args.audio.suffix.lower() not in AUDIO_TYPES:
            raise InputError(f"a browser cannot play this sound; use one of {', '.join(AUDIO_TYPES)}", args.audio)
        check_audio(args.audio)
    write_preview(out, data, args.audio, title=args.glb.stem, force=args.force)
    if not args.quiet:
        what = f"{duration:.2f} s" if duration > 0 else "a still mesh: the glb has no animation"
        print(f"{out} ({what}{' with ' + str(args.audio) if args.audio else ''})")
    return 0
