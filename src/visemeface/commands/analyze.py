"""``visemeface analyze``: mouth-opening profile of a video or frame folder (Leach & Maddock 2019, §4)."""

from __future__ import annotations

from visemeface.commands import _options as opt

ORDER = 80

#: Overlay frames of a small mouth are enlarged (nearest neighbour, whole pixels) to at least this many
#: pixels across the mouth box, so the outlines and the label above the box are legible and the label
#: fits inside the crop (a 40 px GRID mouth is otherwise a 60 px image with its label cut off).
OVERLAY_MIN_BOX = 200

#: Below this natural mouth width (px) analyze warns that openings may be missed. Chosen from one
#: measurement, not tuned: swwp2s's first second (37 px mouth) shrunk to 25 / 19 / 12 px gave height
#: correlations 0.91 / 0.84 / no opening at all against the original.
MIN_MOUTH_PX = 20

#: Largest margin --pad takes, in mouth widths: ten widths hold any face around its mouth (the region is
#: clipped to the frame anyway); more is a mistyped number (1e308 overflowed the pixel arithmetic).
MAX_PAD = 10.0


def _ranges(frames: list[int]) -> str:
    """``[3, 4, 5, 9]`` -> ``"frames 3-5, 9"`` (at most 5 runs, then "...")."""
    runs, start = [], frames[0]
    for a, b in zip(frames, frames[1:] + [None]):
        if b != a + 1:
            runs.append(f"{start}-{a}" if a > start else f"{start}")
            start = b
    return "frames " + ", ".join(runs[:5]) + (", ..." if len(runs) > 5 else "")


def overlay_image(frame, openings, margin, label: str):
    """The mouth box with ``margin`` (Leach & Maddock 2019, Figs. 7-15) cut from an RGB ``frame``, enlarged to
    :data:`OVERLAY_MIN_BOX`, with the box, the opening outlines and ``label`` drawn on it."""
    import dataclasses
    import math

    import cv2
    import numpy as np

    from visemeface.analysis.openings import MouthBox, draw_openings

    box = openings.box
    x0, y0, x1, y1 = box.region(margin, frame.shape[1], frame.shape[0])
    k = max(1, math.ceil(OVERLAY_MIN_BOX / box.w))
    crop = cv2.resize(np.ascontiguousarray(frame[y0:y1, x0:x1]), None, fx=k, fy=k,
                      interpolation=cv2.INTER_NEAREST)
    # frame pixel p -> centre of its k x k block in the crop
    moved = tuple(((c - np.array([x0, y0], np.int32)) * k + (k - 1) // 2).astype(np.int32)
                  for c in openings.contours)
    big = MouthBox((box.x - x0) * k, (box.y - y0) * k, box.w * k, box.h * k)
    return draw_openings(crop, dataclasses.replace(openings, contours=moved, box=big), big, label)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "analyze",
        help="measure mouth openings frame by frame (count, area, width, height) -> CSV and plots",
        description="Measure the mouth openings of every frame of a video (MP4/AVI/MPG/...) or a folder of "
        "PNG/JPG frames. Default method 'mesh': the face mesh's inner-lip contour bounds where the opening can be and, "
        "inside it, the opening is what is unlike the speaker's own lips -- a dark cavity, bright or grey teeth -- "
        "and the tongue between them, measured relative to the lips so that it holds for any skin or lip colour, "
        "with a moustache or beard, in grey video (without a face mesh for a frame: a given box or a close-up, the "
        "bound comes from the lips found by colour). Method 'lips': the lips segmented by colour (redder than "
        "skin, Lab a*) and the region enclosed between them, teeth and tongue included; small, compressed mouths "
        "(40 px in MPEG-1) are resampled first. Method 'seed' is Leach & Maddock's (2019): greyscale, median blur, dark "
        "threshold, top-level "
        "contours. Per frame: number of openings and the largest one's area, width and height, "
        "normalised by the mouth width (the box width: its left/right edges on the mouth corners; "
        "area by the width squared), plus frame differences of area and width. The mouth box comes "
        "from --box, --box-json, or a sidecar <video>.json "
        '({"mouth_box": [x, y, w, h], "fps": 30, "size": [W, H]}; `visemeface face --camera-json` writes '
        "one for the rendered face); without any, it is found automatically in every frame: from MediaPipe's "
        "face mesh (shipped, offline) when the optional extra visemeface[track] is installed -- the box "
        "covers the lips' corners frame by frame, the mouth width is the corner distance at rest -- else "
        "by colour (face by skin, lips by redness; less exact at the corners of compressed video). Widths are "
        "measured along the frame's rows: the face must be upright (the face mesh refuses one turned more than "
        "30 degrees); frames where no face is found are named in a warning. A margin around the box "
        "(--pad) is analysed too, so a box drawn on the rest lips does not cut off a dropped jaw.",
        epilog="examples: visemeface analyze take1.mp4 --box 310,420,400,180 -o take1.csv --plot take1.png "
        "--overlay take1_overlay;  visemeface analyze swwp2s.mpg -o real.csv  (automatic mouth box)",
    )
    p.add_argument("input", metavar="VIDEO_OR_DIR", help="video file or folder of .png/.jpg frames")
    p.add_argument("-o", "--output", required=True, metavar="CSV", help="profile CSV to write")
    p.add_argument("--box", metavar="X,Y,W,H",
                   help="mouth box in pixels (origin top-left); X and X+W on the mouth corners at rest "
                   "(default: the sidecar's, else found automatically in every frame)")
    p.add_argument("--box-json", metavar="FILE",
                   help="sidecar JSON with \"mouth_box\" (default: <input>.json or <input stem>.json if present)")
    p.add_argument("--fps", type=opt.number(0, low_open=True), help="frame rate (default: the video's, the sidecar's, or 30 for folders)")
    p.add_argument("--method", choices=("mesh", "lips", "seed"), default="mesh",
                   help="'mesh' (default): inside the face mesh's inner-lip contour, what is unlike the speaker's "
                   "own lips (dark cavity, bright or grey teeth) and what lies between it, whatever the skin or "
                   "lip colour (without a face mesh -- a given box, a close-up -- between the lips found by colour); "
                   "'lips': the region enclosed between the lips segmented by colour (redder than skin), teeth and "
                   "tongue included; 'seed': Leach & Maddock's (2019) dark threshold")
    p.add_argument("--threshold", metavar="N|otsu",
                   help="seed and lips methods only: seed: grey level 0-255 at or below which a pixel is mouth "
                   "opening, or 'otsu' (default); lips: a grey level at or below which a pixel is never lip "
                   "(default: relative to the lips)")
    p.add_argument("--hull", action="store_true", help="use each opening's convex hull (bright reflections)")
    p.add_argument("--teeth", action="store_true",
                   help="seed method only: count bright unsaturated pixels (teeth) touching the opening as "
                   "opening (the mesh and lips methods always count teeth between the lips)")
    p.add_argument("--min-height", type=opt.number(0, 1, high_open=True), metavar="F",
                   help="mesh and lips methods only: an opening nowhere F * mouth_width thick is the seam of "
                   "closed lips, one less than that wide a speck (default 0.05)")
    p.add_argument("--min-area", type=opt.number(0, 1, high_open=True), default=5e-4, metavar="F",
                   help="drop openings smaller than F * mouth_width^2 pixels (default 5e-4)")
    p.add_argument("--pad", default="0.1,0.1,0.1,0.4", metavar="F|L,T,R,B",
                   help="also analyse this margin around the box, in mouth widths (left,top,right,bottom; "
                   f"default 0.1,0.1,0.1,0.4: room for the jaw to drop; each 0 to {MAX_PAD:g}); 0 = exactly the box")
    p.add_argument("--plot", metavar="PNG", help="also plot the profile over time (.png, .pdf or .svg)")
    p.add_argument("--overlay", metavar="DIR", help="write every frame's mouth region with the detected outlines")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    opt.add_quiet(p)
    p.set_defaults(func=run)


def _threshold(text: str):
    from visemeface.errors import InputError

    if text is None or text.strip().lower() == "otsu":
        return "otsu"
    try:
        return opt.check_number(text, "--threshold", 0, 255, what="a grey level, or 'otsu'")
    except InputError:
        raise InputError(f"--threshold must be a grey level 0-255 or 'otsu', got {opt.shown(text)}") from None


def _pad(text: str):
    from visemeface.errors import InputError

    vals = text.split(",")
    if len(vals) not in (1, 4):
        raise InputError(f"--pad must be 1 or 4 numbers (left,top,right,bottom), got {opt.shown(text)}")
    return tuple(opt.check_number(v, "--pad", 0, MAX_PAD, what="mouth widths") for v in vals)


#: The options that only some methods read, and those methods.
METHOD_OPTIONS = {"threshold": ("seed", "lips"), "teeth": ("seed",), "min_height": ("mesh", "lips")}


def _check_applies(args) -> None:
    """An option the chosen method does not read is refused (a user would otherwise believe it changed
    the measure)."""
    from visemeface.errors import InputError

    for dest, methods in METHOD_OPTIONS.items():
        if getattr(args, dest) not in (None, False) and args.method not in methods:
            flag = "--" + dest.replace("_", "-")
            raise InputError(f"{flag} applies to --method {' or '.join(methods)}, not to {args.method} "
                             "(it would change nothing)")


def run(args) -> int:
    import contextlib
    import warnings
    from pathlib import Path

    import cv2

    from visemeface.analysis.openings import OpeningDetector
    from visemeface.analysis.profiles import analyze_source, plot_profiles, write_profile
    from visemeface.analysis.video import open_frames, parse_box, read_sidecar, sidecar_path
    from visemeface.errors import InputError
    from visemeface.outputs import atomic_dir, check_new, check_not_inputs, check_suffix

    detector = OpeningDetector(threshold=_threshold(args.threshold), hull=args.hull, teeth=args.teeth,
                               min_area=args.min_area, pad=_pad(args.pad), method=args.method,
                               min_height=0.05 if args.min_height is None else args.min_height)
    _check_applies(args)
    if not Path(args.input).exists():
        raise InputError("no such file or folder", args.input)
    # --box wins; a sidecar found next to the input is only read when no box is given
    side_file = Path(args.box_json) if args.box_json else (None if args.box else sidecar_path(args.input))
    sidecar = read_sidecar(side_file) if side_file else None
    if args.box is not None:
        box = parse_box(args.box)
    elif sidecar is not None:
        box = sidecar.mouth_box
    else:
        box = None              # found automatically, frame by frame
    check_suffix(args.output, ".csv")
    if args.plot:
        check_suffix(args.plot, ".png", ".pdf", ".svg")
    outputs = [args.output] + [p for p in (args.plot, args.overlay) if p]
    if len(set(map(str, outputs))) != len(outputs):
        raise InputError("the CSV, plot and overlay outputs must be different paths")
    check_not_inputs(outputs, [args.input], "the input")
    for out in outputs:
        check_new(out, args.force)

    fps = args.fps if args.fps is None else opt.check_fps_option(args.fps)
    if fps is None and sidecar is not None and Path(args.input).is_dir():
        fps = sidecar.fps
    source = open_frames(args.input, fps)
    try:
        if sidecar is not None and args.box is None and sidecar.size and tuple(sidecar.size) != source.size:
            raise InputError(f"sidecar is for {sidecar.size[0]}x{sidecar.size[1]} frames, the video is "
                             f"{source.size[0]}x{source.size[1]}", side_file)
        if box is not None:
            box.check_inside(*source.size)
    except InputError:
        source.close()
        raise
    with contextlib.ExitStack() as stack:
        on_frame = None
        if args.overlay:
            from visemeface.render.export import frame_name

            overlay_dir = stack.enter_context(atomic_dir(args.overlay, args.force))
            margin = [max(p, 0.15) for p in detector.pad]

            def on_frame(i, frame, openings):
                img = overlay_image(frame, openings, margin, f"frame {i}")
                if not cv2.imwrite(str(overlay_dir / frame_name(i)), cv2.cvtColor(img, cv2.COLOR_RGB2BGR)):
                    raise InputError("cannot write overlay frame", overlay_dir)

        df, boxes = analyze_source(source, box, detector, on_frame, show_progress=not args.quiet)
    write_profile(df, args.output, args.force)
    if args.plot:
        plot_profiles({Path(args.input).name: df}, args.plot, title=f"mouth openings: {Path(args.input).name}",
                      force=args.force)

    n = len(df)
    multi = int((df["count"] >= 2).sum())
    jump = df["d_width"].abs()
    if boxes is None:
        width = f"mouth width {box.w} px"
    else:
        from visemeface.analysis.landmarks import available

        how = "face landmarks" if available() else "by colour; pip install 'visemeface[track]' for landmarks"
        width = f"automatic mouth box ({how}), mouth width {boxes[0].mouth_width} px"
    mouth_px = box.w if boxes is None else boxes[0].mouth_width
    lost = [] if boxes is None else [i for i, b in enumerate(boxes) if not b.found]
    if lost:
        warnings.warn(f"no face in {len(lost)} of {n} frames ({_ranges(lost)}): their box is "
                      "taken from the nearest frames with a face and their openings are likely 0")
    if mouth_px < MIN_MOUTH_PX:
        warnings.warn(f"the mouth is only {mouth_px} px wide (under {MIN_MOUTH_PX}): thin openings "
                      "may be missed; use a larger video or crop")
    msg = (f"{n} frames at {source.fps:g} fps, {width}, method {args.method}: openings max {int(df['count'].max())}, "
           f"{multi} frame(s) with 2 or more; max width {df['width'].max():.3f} w, "
           f"max area {df['area'].max():.4f} w^2")
    if n > 1 and jump.max() > 0:
        k = int(jump.idxmax())
        msg += f"; largest width jump {df['d_width'][k]:+.3f} w at frame {int(df['frame'][k])} ({df['time'][k]:.3f} s)"
    if not args.quiet:
        print(msg)
        print(f"wrote {args.output}" + "".join(f", {p}" for p in (args.plot, args.overlay) if p))
    return 0
