"""The physics configuration file: its documented defaults are the model's, it round-trips, a bad file is
refused in one line naming file, line and key, and what the command line gives wins over it."""

from __future__ import annotations

import argparse
import dataclasses
import re
from pathlib import Path

import pytest

from visemeface.cli import main
from visemeface.commands._options import add_physics_arguments, physics_from_args
from visemeface.errors import InputError
from visemeface.physics.config import KEYS, apply_physics_config, physics_config_text, read_physics_config
from visemeface.physics.drive import PhysicsSettings

DOC = Path(__file__).resolve().parents[2] / "docs" / "formats" / "physics-config.md"


def _doc_blocks():
    return re.findall(r"```toml\n(.*?)```", DOC.read_text(), re.S)


def _parser():
    p = argparse.ArgumentParser()
    add_physics_arguments(p, "none", ("none", "sticky", "elastic"))
    return p


def test_the_documented_file_holds_the_speech_lips_and_turns_the_seed_model_into_them(tmp_path):
    (tmp_path / "p.toml").write_text(_doc_blocks()[0])
    values = read_physics_config(tmp_path / "p.toml")
    assert apply_physics_config(PhysicsSettings(), values) == PhysicsSettings.speech()
    # every key a file may hold is in the documented file (commented out where the default is "absent")
    assert all(re.search(rf"^#? ?{k} = ", _doc_blocks()[0], re.M) for k in KEYS)


@pytest.mark.parametrize("settings", [PhysicsSettings(), PhysicsSettings.speech(),
                                      PhysicsSettings.speech(dt=2e-6, glue_profile="centre=0.18", damping=12.5)])
def test_the_written_file_reads_back_to_the_same_settings(tmp_path, settings):
    (tmp_path / "p.toml").write_text(physics_config_text(settings))
    assert apply_physics_config(PhysicsSettings.speech(), read_physics_config(tmp_path / "p.toml")) == settings


@pytest.mark.parametrize("text, line, message", [
    ("damping = 40\ndampin = 3\n", 2, r"unknown key 'dampin' \(did you mean: damping"),
    ("[salvia]\ndecay = 0.5\n", 1, r"unknown table \[salvia\] \(did you mean: saliva\?\)"),
    ("glue = 0.1\n\n[saliva]\nevaporation = -1\n", 4, r"\[saliva\] evaporation must be from 0 to"),
    ("damping = 1e308\n", 1, r"damping must be from 0 to 10000, got 1e\+308"),
    ("tissue_limit = 1\n", 1, r"tissue_limit must be over 1 \(inf: none\), got 1"),
    ("film_corners = 1\n", 1, r"film_corners must be true or false"),
    ("seam_elements = 4.5\n", 1, r"seam_elements must be a whole number"),
    ("damping = nan\n", 1, r"damping must be a number, got nan"),
    ("glue = 0.1\nglue = 0.2\n", 2, r"not valid TOML"),
    ("[saliva]\nmuscles = 'loads'\n", 2, r"unknown key '\[saliva\] muscles'"),
    ("posture_hz = 5\n", 1, r"unknown key 'posture_hz'"),           # an experiment is no key of the file
    ("glue = 0.1\nglue_profile = 'middle=0.2'\n", 2, r"glue_profile: glue profile 'middle=0.2': unknown place"),
    ("glue_profile = 'centre=1e308'\n", 1, r"glue_profile: glue profile 'centre=1e308'"),
], ids=["typo", "table", "range-in-table", "huge", "limit", "bool", "whole", "nan", "toml", "wrong-table",
        "experiment", "profile-place", "profile-value"])
def test_a_bad_file_names_its_line_and_key(tmp_path, text, line, message):
    path = tmp_path / "p.toml"
    path.write_text(text)
    with pytest.raises(InputError, match=message) as caught:
        read_physics_config(path)
    assert str(caught.value).startswith(f"{path}:{line}: ")


def test_the_command_line_wins_over_the_file_and_the_file_over_the_lips(tmp_path):
    (tmp_path / "p.toml").write_text("glue = 0.2\ndamping = 40\nseam_elements = 0\n[saliva]\nrupture_time = 0.05\n")
    p = _parser()
    filed = physics_from_args(p.parse_args(["--physics", "sticky", "--physics-config", str(tmp_path / "p.toml")]))
    assert (filed.glue, filed.damping, filed.seam_elements, filed.saliva.rupture_time) == (0.2, 40.0, None, 0.05)
    assert filed.tissue_limit == PhysicsSettings.speech().tissue_limit           # unset keys: the lips' own
    given = physics_from_args(p.parse_args(["--physics", "sticky", "--physics-config", str(tmp_path / "p.toml"),
                                            "--glue", "0.1", "--rupture-time", "0"]), damping=70.0)
    assert (given.glue, given.damping, given.saliva.rupture_time) == (0.1, 70.0, 0.0)
    seed = physics_from_args(p.parse_args(["--physics", "sticky", "--lips", "seed",
                                           "--physics-config", str(tmp_path / "p.toml")]))
    assert seed == dataclasses.replace(PhysicsSettings(), glue=0.2, damping=40.0,
                                       saliva=dataclasses.replace(PhysicsSettings().saliva, rupture_time=0.05))


def test_a_glue_key_is_refused_for_the_elastic_face_and_any_file_without_a_physical_face(tmp_path):
    (tmp_path / "p.toml").write_text("damping = 40\nglue = 0.2\n")
    p = _parser()
    with pytest.raises(InputError, match="glue sets the glue between the lips"):
        physics_from_args(p.parse_args(["--physics", "elastic", "--physics-config", str(tmp_path / "p.toml")]))
    with pytest.raises(InputError, match="--physics-config needs --physics sticky or elastic"):
        physics_from_args(p.parse_args(["--physics-config", str(tmp_path / "p.toml")]))
    (tmp_path / "d.toml").write_text("damping = 40\n")
    assert physics_from_args(p.parse_args(["--physics", "elastic", "--physics-config",
                                           str(tmp_path / "d.toml")])).damping == 40.0


def test_a_value_the_model_refuses_names_the_file(tmp_path):
    (tmp_path / "p.toml").write_text("[saliva]\ndecay = 1.0\n")           # in the key's range, not the model's
    with pytest.raises(InputError, match=r"p\.toml: force decay must be in \[0, 1\)"):
        physics_from_args(_parser().parse_args(["--physics", "sticky", "--physics-config", str(tmp_path / "p.toml")]))


def test_simulate_refuses_a_bad_file_in_one_line_before_the_work(tmp_path, capsys, monkeypatch):
    import visemeface.physics.face_model as face_model

    def built(*a, **k):
        raise AssertionError("the FEM face was built before the file was refused")

    monkeypatch.setattr(face_model, "build_fem_face", built)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.toml").write_text("damping = 40\nhourglass = 0.1\n")
    assert main(["simulate", "part", "--physics-config", "p.toml", "-o", "s.mp4"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["visemeface: error: p.toml:2: unknown key 'hourglass' (did you mean: hourglass_kappa?); "
                   "known here: " + ", ".join(k for k, s in KEYS.items() if s[0] is None)]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.toml"]


@pytest.mark.slow
def test_a_file_moves_the_simulation_as_the_same_options_do(tmp_path, monkeypatch):
    """The file reaches the solver: its values give the bits of the options that say the same, not the default's."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "d.toml").write_text("damping = 5\n[saliva]\nrupture_time = 0\n")
    run = ["simulate", "part", "--resolution", "800", "--size", "32", "--msaa", "0", "--no-video", "-q"]
    assert main([*run, "--measures", "file.csv", "--physics-config", "d.toml"]) == 0
    assert main([*run, "--measures", "options.csv", "--damping", "5", "--rupture-time", "0"]) == 0
    assert main([*run, "--measures", "default.csv"]) == 0
    assert (tmp_path / "file.csv").read_bytes() == (tmp_path / "options.csv").read_bytes()
    assert (tmp_path / "file.csv").read_bytes() != (tmp_path / "default.csv").read_bytes()


@pytest.mark.parametrize("text, message", [
    ("glue = " + "9" * 5000 + "\n", "a number of over 4300 digits"),
    ("glue = " + "[" * 100000 + "\n", "nested too deeply"),
])
def test_a_toml_file_the_parser_cannot_hold_is_refused_in_one_line(tmp_path, text, message):
    path = tmp_path / "huge.toml"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        read_physics_config(path)


def test_a_glue_file_the_configuration_names_is_read_when_the_configuration_is(tmp_path):
    (tmp_path / "p.toml").write_text("glue_file = 'glue.csv'\n")
    with pytest.raises(InputError, match="glue.csv"):
        read_physics_config(tmp_path / "p.toml")
