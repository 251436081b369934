"""Regressions from a hostile new user's second round (issue 20): one line on stderr, exit 2."""

import subprocess
import sys

import numpy as np
import pytest


def _visemeface(cwd, *argv):
    proc = subprocess.run([sys.executable, "-m", "visemeface", *argv], cwd=cwd, capture_output=True, text=True,
                          timeout=120)
    return proc.returncode, proc.stderr


@pytest.mark.parametrize("command", [["lipsync", "fake.mp3", "-o", "f.lab"],
                                     ["speak", "t.txt", "--audio", "fake.mp3", "-o", "f.mp4"]])
def test_a_fake_mp3_is_one_line_without_decoder_noise(tmp_path, command):
    """libmpg123 printed "[src/libmpg123/parse.c:do_readahead():1083] warning: Cannot read next header,
    a one-frame stream? Duh..." on the C library's stderr before the error line."""
    (tmp_path / "fake.mp3").write_bytes(np.random.default_rng(0).integers(0, 256, 5000, np.uint8).tobytes())
    (tmp_path / "t.txt").write_text("0.00 0.05 _\n0.05 0.25 aa\n0.25 0.30 _\n")
    code, err = _visemeface(tmp_path, *command)
    assert code == 2 and err.count("\n") == 1 and err.startswith("visemeface: error: fake.mp3: "), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fake.mp3", "t.txt"]
