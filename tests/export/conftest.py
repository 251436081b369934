"""One speak run writing every export of this folder's tests (made once per session)."""

import shutil

import pytest

from visemeface.cli import main
from visemeface.resources import transcripts_path

TEXT = "set white with p two soon"
OUTPUTS = {"--gltf": "a.glb", "--arkit": "a.json", "--livelink": "ll.csv", "--vrm": "v.csv", "--oculus": "o.csv",
           "--rhubarb": "r.json", "--obj": "objd", "--pc2": "a.pc2", "--preview": "p.html", "--track": "t.csv"}


@pytest.fixture(scope="session")
def exported(tmp_path_factory):
    root = tmp_path_factory.mktemp("exports")
    (root / "t.txt").write_text(TEXT + "\n")
    shutil.copy(transcripts_path("set_white_with_p_two_soon.wav"), root / "a.wav")   # its words: aligned to it
    args = ["speak", str(root / "t.txt"), "--no-video", "-q", "--audio", str(root / "a.wav")]
    for option, name in OUTPUTS.items():
        args += [option, str(root / name)]
    assert main(args) == 0
    return root


@pytest.fixture(scope="session")
def arkit_glb(tmp_path_factory):
    """A glb with ARKit-named morph targets (``--gltf-shapes arkit``) of a short utterance."""
    root = tmp_path_factory.mktemp("arkit")
    (root / "s.txt").write_text("hi\n")
    assert main(["speak", str(root / "s.txt"), "--no-video", "-q", "--gltf", str(root / "k.glb"),
                 "--gltf-shapes", "arkit"]) == 0
    return root / "k.glb"
