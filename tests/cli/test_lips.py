"""``--lips seed`` is Leach & Maddock's (2018) model: the same settings, and so the same figures, as the four
options it replaces (``--seam-elements 0 --rupture-time 0 --no-film-corners --tissue-limit inf``)."""

from __future__ import annotations

import argparse

import pytest

from visemeface.cli import main
from visemeface.commands._options import add_physics_arguments, physics_from_args
from visemeface.errors import InputError

FOUR = ["--seam-elements", "0", "--rupture-time", "0", "--no-film-corners", "--tissue-limit", "inf"]


def _parser():
    p = argparse.ArgumentParser()
    add_physics_arguments(p, "none", ("none", "sticky", "elastic"))
    return p


@pytest.mark.parametrize("physics", ["sticky", "elastic"])
def test_lips_seed_is_the_four_options_and_the_default_is_the_speech_lips(physics):
    from visemeface.physics.drive import PhysicsSettings

    p = _parser()
    seed = physics_from_args(p.parse_args(["--physics", physics, "--lips", "seed"]))
    four = physics_from_args(p.parse_args(["--physics", physics, *FOUR]))
    assert seed == four == PhysicsSettings()
    default = physics_from_args(p.parse_args(["--physics", physics]))
    assert default == physics_from_args(p.parse_args(["--physics", physics, "--lips", "default"]))
    assert default == PhysicsSettings.speech() != seed
    # an option given with --lips changes that model: the seed's with the speech lips' rupture time
    tweaked = physics_from_args(p.parse_args(["--physics", physics, "--lips", "seed", "--rupture-time", "0.03"]))
    assert tweaked.saliva.rupture_time == 0.03 and tweaked.seam_elements == seed.seam_elements


def test_lips_needs_a_physical_face():
    with pytest.raises(InputError, match="--lips seed needs --physics sticky or elastic"):
        physics_from_args(_parser().parse_args(["--lips", "seed"]))


def test_simulate_and_speak_offer_lips():
    from visemeface.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    for command in ("speak", "say", "simulate"):
        assert "--lips" in sub.choices[command].format_help()


@pytest.mark.slow
def test_lips_seed_gives_the_four_options_figures(tmp_path, monkeypatch):
    """A short sticky run on a coarse face: the saliva figures and the exported motion are the same bits."""
    from visemeface.face.procedural import default_face
    from visemeface.runtime import set_threads

    set_threads(1)
    monkeypatch.chdir(tmp_path)
    default_face(resolution=1500).save(tmp_path / "coarse.obj")
    (tmp_path / "tiny.txt").write_text("0.00 0.05 _\n0.05 0.25 aa\n0.25 0.30 _\n")
    base = ["speak", "tiny.txt", "--face", "coarse.obj", "--physics", "sticky", "--no-video", "-q"]
    assert main([*base, "--lips", "seed", "--measures", "seed.csv", "--pc2", "seed.pc2"]) == 0
    assert main([*base, *FOUR, "--measures", "four.csv", "--pc2", "four.pc2"]) == 0
    seed, four = (tmp_path / "seed.csv").read_bytes(), (tmp_path / "four.csv").read_bytes()
    assert seed == four and len(seed.splitlines()) > 5
    assert (tmp_path / "seed.pc2").read_bytes() == (tmp_path / "four.pc2").read_bytes()
