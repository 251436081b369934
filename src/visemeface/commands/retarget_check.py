"""``visemeface retarget-check``: how the ARKit weights look on a character, measured on its own shapes."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from visemeface.commands._options import Help, print_table

ORDER = 95
#: Sentences with many /p b m/, open and rounded vowels (checked when no --text is given).
SENTENCES = ("bob moves five boats past my pool", "a map of the moon by the blue boom box",
             "we wove two woolly ropes", "papa bought maybe more apples")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "retarget-check",
        help="play the ARKit weights on a character's blendshapes and measure its lips per sound class",
        description="Fit speech onto a blendshape rig (the ICT Face Model's shapes, or RIG: a .glb/.gltf with "
        "morph targets or a folder of OBJ shapes, as --arkit-rig takes), play the weights back on its shapes "
        "as a client does (neutral + sum of weight x shape) and print, on the character in millimetres: the "
        "inner-lip gap at the centre and its minimum across the seam (negative: the lips cross), and per sound "
        "class at each phone's middle the gap and the mouth width relative to rest. Bilabials /p b m/ should "
        "close (|gap| <= 1.5 mm), open vowels open (4-16 mm), rounded vowels /uw w ow/ narrow the mouth "
        "(<= 0.9 of its width).",
        formatter_class=Help,
        epilog="examples:\n  visemeface retarget-check\n  visemeface retarget-check my_avatar.glb --text "
        "\"bob moves five boats\"\n  visemeface retarget-check --json > check.json",
    )
    p.add_argument("rig", nargs="?", type=Path, help="the character's rig (default: the ICT Face Model)")
    p.add_argument("--text", action="append", metavar="TEXT",
                   help="an English sentence to check (repeatable; default: four with many /p b m/ and "
                   "rounded vowels)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--sheet", metavar="PNG", type=Path,
                   help="also render, per sound class of the first sentence, our face beside the character "
                   "played by the weights (mouth view)")
    p.add_argument("--force", action="store_true", help="overwrite --sheet if it exists")
    p.set_defaults(func=run)


def check_rig(rig_path=None, texts=SENTENCES, fps: float = 30.0, sheet=None, force: bool = False) -> list[dict]:
    """Per sentence: the figures of :func:`visemeface.retarget.check.summary` plus the fit's median residual;
    ``sheet``: a PNG of the first sentence's classes, our face beside the character."""
    import numpy as np

    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_visemes
    from visemeface.retarget import check
    from visemeface.retarget.rigs import load_client_rig, reference_rig
    from visemeface.speech.g2p import text_to_utterance
    from visemeface.speech.timeline import MODES, activation_track

    rig = default_rig()
    client = load_client_rig(rig_path) if rig_path else reference_rig()
    if sheet is not None:
        from visemeface.outputs import check_new, check_suffix

        check_suffix(sheet, ".png")
        check_new(sheet, force)
    fit = client.fit()
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    out = []
    for text in texts:
        u = text_to_utterance(text)
        track = activation_track(u, load_visemes(rig=rig), fps=fps, mode=MODES[0], ranges=ranges)
        W, R = client.track_weights(rig.track_matrix(track), rig.path)
        m = check.measure(client.face, fit.play(W))
        row = {"text": text, "residual_median_mm": float(np.median(R) * 1000)}
        frames = check.phone_frames(u.segments, fps, len(W))
        row.update(check.summary(m, frames))
        out.append(row)
        if sheet is not None and len(out) == 1:
            _sheet(sheet, rig, client, rig.clamp(rig.track_matrix(track)), W, m, frames, force)
    return out


def _sheet(path, rig, client, A, W, m, frames, force) -> None:
    from visemeface.commands.sheet import compose_sheet
    from visemeface.render.renderer import Renderer, save_png

    played = client.fit().play(W)
    images, labels = [], []
    with Renderer(rig.face, size=(320, 320), view="mouth") as ours, \
            Renderer(client.face, size=(320, 320), view="mouth") as theirs:
        for cls, idx in frames.items():
            if not idx:
                continue
            f = idx[0]
            images += [ours.render(rig.pose(A[f])), theirs.render(client.face.vertices + played[f])]
            labels += [f"ours: {cls}", f"{client.name}: {m.gap[f]:.1f} mm, width {m.width[f]:.2f}"]
    save_png(path, compose_sheet(images, labels, 2), force=force)


def run(args) -> int:
    rows = check_rig(args.rig, tuple(args.text) if args.text else SENTENCES, sheet=args.sheet, force=args.force)
    if args.json:
        print(json.dumps(rows, indent=1))
        return 0
    table = []
    for r in rows:
        def cls(name, key, fmt):
            return fmt.format(r[name][key]) if name in r else "-"
        table.append((r["text"][:40], f"{r['min_centre_gap_mm']:.1f}", f"{r['min_seam_gap_mm']:.1f}",
                      cls("bilabial", "max_abs_gap_mm", "{:.1f}"), cls("open vowel", "gap_mm", "{:.1f}"),
                      cls("rounded", "width_ratio", "{:.2f}"), f"{r['residual_median_mm']:.2f}"))
    print_table(("sentence", "min gap", "min seam gap", "bilabial |gap|", "open vowel gap", "rounded width",
                 "residual"), table, False)
    print("millimetres on the character; widths relative to rest; residual: the fit's median RMS")
    if args.sheet:
        print(f"wrote {args.sheet}")
    return 0
