"""``visemeface sheet``: a labelled contact sheet of the visemes or the emotions."""

from __future__ import annotations

import numpy as np

from visemeface.commands import _options as opt
from visemeface.render import VIEWS

ORDER = 43


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "sheet",
        help="render a labelled contact sheet of all 56 visemes (or of the emotions)",
        description="Render every viseme of the shipped table (or, with --emotions, every emotion) "
        "on the default face (or --face) and tile the pictures, each labelled, into one PNG.",
        epilog="examples:\n  visemeface sheet -o visemes.png\n"
        "  visemeface sheet --emotions -o emotions.png --view face\n"
        "  visemeface sheet --emotion happiness=0.5 -o happy_visemes.png\n"
        "  visemeface sheet --emotion surprise=0.6 --keep-contact -o surprised_visemes.png",
        formatter_class=opt.Help,
    )
    p.add_argument("-o", "--output", required=True, help="PNG file to write")
    p.add_argument("--emotions", action="store_true",
                   help="tile the emotions (and the neutral face) instead of the visemes")
    p.add_argument("--weight", type=float, default=None, metavar="W",
                   help="with --emotions: each emotion at weight W, 0..1 (default 1)")
    p.add_argument("--emotion", action="append", metavar="NAME[=W]", default=None,
                   help="blend every viseme with this emotion at weight W (default 1); repeatable")
    p.add_argument("--keep-contact", action="store_true",
                   help="with --emotion: close the jaw of p b m f v so the lips still touch")
    p.add_argument("--size", type=int, default=192, help="side of each tile in pixels, multiple of 16 "
                   "(default 192)")
    p.add_argument("--view", choices=VIEWS, default=None,
                   help="camera: face, mouth or three-quarter (default: mouth for visemes, face for emotions)")
    opt.add_msaa_argument(p)
    p.add_argument("--columns", type=int, default=None, help="tiles per row (default 8 for visemes, 4 for emotions)")
    opt.add_face_arguments(p)
    p.add_argument("--force", action="store_true", help="overwrite the output if it exists")
    opt.add_quiet(p)
    p.set_defaults(func=run)


def compose_sheet(images: list[np.ndarray], labels: list[str], columns: int,
                  label_height: int | None = None) -> np.ndarray:
    """Tile equally sized RGB images row by row, each with its label underneath.

    Parameters
    ----------
    images : list of uint8 (H, W, 3)
    labels : list of str, one per image
    columns : int
        Tiles per row; the last row is padded with white.
    label_height : int, optional
        Height of the label strip (default ``max(14, H // 8)``).

    Returns
    -------
    uint8 array (rows·(H + label_height), columns·W, 3)
    """
    from PIL import Image, ImageDraw, ImageFont

    if not images:
        raise ValueError("no images to tile")
    h, w = images[0].shape[:2]
    lh = label_height or max(14, h // 8)
    rows = -(-len(images) // columns)
    sheet = Image.new("RGB", (columns * w, rows * (h + lh)), "white")
    draw = ImageDraw.Draw(sheet)
    font = ImageFont.load_default(size=max(10, int(lh * 0.75)))
    for k, (img, label) in enumerate(zip(images, labels)):
        r, c = divmod(k, columns)
        x, y = c * w, r * (h + lh)
        sheet.paste(Image.fromarray(np.ascontiguousarray(img[..., :3])), (x, y))
        tw = draw.textlength(label, font=font)
        draw.text((x + (w - tw) / 2, y + h + 1), label, fill="black", font=font)
    return np.asarray(sheet)


def run(args) -> int:
    from PIL import Image

    from visemeface.animate import parse_emotions
    from visemeface.errors import InputError
    from visemeface.outputs import atomic_output, check_new, check_suffix, progress
    from visemeface.postures.library import load_expressions, load_visemes, posed_vertices
    from visemeface.render.renderer import Renderer

    if args.size < 16 or args.size % 16:
        raise InputError(f"--size must be a positive multiple of 16, got {args.size}")
    from visemeface.pipeline import check_msaa

    check_msaa(args.msaa)
    if args.columns is not None and args.columns < 1:
        raise InputError(f"--columns must be at least 1, got {args.columns}")
    if args.emotions and args.emotion:
        raise InputError("give either --emotions (a sheet of the emotions) or --emotion NAME=W (blend), not both")
    if args.weight is not None and not args.emotions:
        raise InputError("--weight sets the emotions' weight in a sheet of the emotions; give --emotions")
    weight = 1.0 if args.weight is None else float(args.weight)
    if not 0.0 <= weight <= 1.0:
        raise InputError(f"--weight must be between 0 and 1, got {args.weight:g}")
    if args.keep_contact and not args.emotion:
        raise InputError("--keep-contact keeps p b m f v closed under an --emotion; give one")
    check_new(check_suffix(args.output, ".png"), args.force)
    rig = opt.build_rig(args)
    mix = parse_emotions(args.emotion, load_expressions(rig=rig).index)
    if args.emotions:
        names = ["_"] + load_expressions(rig=rig).index.tolist()
        poses = [("_", {})] + [("_", {e: weight}) for e in names[1:]]
        labels = ["neutral"] + [n if weight == 1 else f"{n} {weight:g}" for n in names[1:]]
        view, columns = args.view or "face", args.columns or 4
    else:
        table = load_visemes(rig=rig)
        poses = [(s, mix) for s in table.index]
        labels = [f"{i} {s}" for i, s in enumerate(table.index)]
        view, columns = args.view or "mouth", args.columns or 8
    keep = bool(args.keep_contact)
    # fail on a bad name before rendering anything
    posed_vertices(rig, *poses[-1])
    renderer = Renderer(rig.face, size=(args.size, args.size), view=view, samples=args.msaa)
    images = [renderer.render(posed_vertices(rig, v, e, keep_contact=keep))
              for v, e in progress(poses, desc="rendering", unit="posture", show=not args.quiet)]
    sheet = compose_sheet(images, labels, columns)
    with atomic_output(args.output, args.force) as tmp:
        Image.fromarray(sheet).save(tmp, format="PNG", optimize=True)
    if not args.quiet:
        print(f"wrote {args.output} ({len(images)} postures, {sheet.shape[1]}x{sheet.shape[0]})")
    return 0
