"""CLI: `visemeface visemes`, `visemeface emotions`, `visemeface sheet`."""

from __future__ import annotations

import io

import numpy as np
import pandas as pd
import pytest

from visemeface.cli import main
from visemeface.commands.sheet import compose_sheet
from visemeface.postures.phonemes import DECTALK


def test_visemes_lists_all_56_with_classes_and_notes(capsys):
    assert main(["visemes", "--csv"]) == 0
    df = pd.read_csv(io.StringIO(capsys.readouterr().out), keep_default_na=False).set_index("symbol")
    assert df.index.tolist() == list(DECTALK)
    assert df.loc["p", "perceptual_class"] == "a /p,b,m/"
    assert df.loc["z", "perceptual_class"] == "h /sh,zh,z/"
    assert df.loc["t", "perceptual_class"] == ""
    assert df.loc["f", "class"] == "labiodental"
    assert "teeth" in df.loc["f", "notes"]
    assert main(["visemes"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[:3] == ["#", "symbol", "class"]
    assert any(line.split()[:2] == ["24", "w"] for line in lines)


def test_emotions_lists_seven_with_action_units(capsys):
    assert main(["emotions"]) == 0
    out = capsys.readouterr().out
    for name in ("happiness", "sadness", "surprise", "fear", "anger", "contempt", "disgust"):
        assert any(line.startswith(name) for line in out.splitlines()), name
    assert "AU12" in out and "AU9" in out
    contempt = out[out.index("contempt"):out.index("disgust")]
    assert "zygomatic_major_left" in contempt and "_right" not in contempt


def test_compose_sheet_tiles_and_labels():
    tiles = [np.full((16, 16, 3), v, np.uint8) for v in (0, 100, 200)]
    sheet = compose_sheet(tiles, ["a", "b", "c"], columns=2, label_height=14)
    assert sheet.shape == (2 * 30, 32, 3)
    assert (sheet[:16, :16] == 0).all() and (sheet[:16, 16:32] == 100).all() and (sheet[30:46, :16] == 200).all()
    assert (sheet[46:, 16:] == 255).all()            # padding of the short last row stays white
    assert (sheet[16:30, :16] < 128).any()           # a label was drawn under the first tile


def _dark_fraction(tile):
    return float((tile.astype(int).sum(axis=2) < 120).mean())


def test_sheet_renders_56_labelled_visemes(tmp_path, capsys):
    out = tmp_path / "v.png"
    assert main(["sheet", "-o", str(out), "--size", "48"]) == 0
    from PIL import Image

    img = np.asarray(Image.open(out).convert("RGB"))
    lh = 14
    assert img.shape == (7 * (48 + lh), 8 * 48, 3)

    def tile(k):
        r, c = divmod(k, 8)
        return img[r * (48 + lh):r * (48 + lh) + 48, c * 48:(c + 1) * 48]

    # open /aa/ shows more dark mouth cavity than closed /p/ and silence
    idx = {s: i for i, s in enumerate(DECTALK)}
    assert _dark_fraction(tile(idx["aa"])) > _dark_fraction(tile(idx["p"])) + 0.02
    assert _dark_fraction(tile(idx["aa"])) > _dark_fraction(tile(idx["_"])) + 0.02
    # no overwrite without --force; with it, fine
    assert main(["sheet", "-o", str(out), "--size", "48"]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["sheet", "-o", str(out), "--size", "32", "--emotions", "--force"]) == 0
    img = np.asarray(Image.open(out).convert("RGB"))
    assert img.shape == (2 * (32 + 14), 4 * 32, 3)  # neutral + 7 emotions in 4 columns


@pytest.mark.parametrize("args, message", [
    (["--emotion", "hapiness=0.5"], "did you mean: happiness"),
    (["--emotion", "happiness=-0.5"], "must not be negative"),
    (["--emotion", "happiness=nan"], "must be finite"),
    (["--emotion", "happiness=lots"], "must be a number"),
    (["--size", "50"], "multiple of 16"),
    (["--emotions", "--weight", "1.5"], "between 0 and 1"),
    (["--emotions", "--weight", "nan"], "between 0 and 1"),
    (["--weight", "0.5"], "give --emotions"),
])
def test_sheet_bad_input_exits_2_with_one_line(tmp_path, capsys, args, message):
    out = tmp_path / "bad.png"
    assert main(["sheet", "-o", str(out), "--size", "32", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err
    assert not out.exists()


def test_sheet_keep_contact_closes_bilabials_under_a_jaw_dropping_emotion(tmp_path):
    from PIL import Image

    idx = DECTALK.index("p")
    r, c = divmod(idx, 8)
    tiles = {}
    for flag in ([], ["--keep-contact"]):
        out = tmp_path / f"s{len(flag)}.png"
        assert main(["sheet", "-o", str(out), "--size", "48", "--emotion", "surprise=0.8", *flag]) == 0
        img = np.asarray(Image.open(out).convert("RGB"))
        tiles[bool(flag)] = img[r * 62:r * 62 + 48, c * 48:(c + 1) * 48]
    assert _dark_fraction(tiles[False]) > _dark_fraction(tiles[True]) + 0.01


def test_sheet_of_the_emotions_at_a_weight(tmp_path):
    from PIL import Image

    full, half = tmp_path / "full.png", tmp_path / "half.png"
    assert main(["sheet", "--emotions", "-o", str(full), "--size", "64", "-q"]) == 0
    assert main(["sheet", "--emotions", "--weight", "0.5", "-o", str(half), "--size", "64", "-q"]) == 0
    a, b = (np.asarray(Image.open(p).convert("RGB"), float) for p in (full, half))
    assert a.shape == b.shape
    # the neutral tile (top left) is the same, the emotions' tiles are not
    assert np.abs(a[:64, :64] - b[:64, :64]).max() == 0
    assert np.abs(a[:64, 64:] - b[:64, 64:]).mean() > 0.5
