"""Grouped help: ``--help`` lists the options most runs need, ``--help-all`` every one; both stay true to the parser."""

from __future__ import annotations

import argparse
import re

import pytest

from visemeface.cli import BASIC_OPTIONS, build_parser, main


def _listed(text: str) -> set[str]:
    """Option strings that start a line of an argparse options listing."""
    return {m for line in text.splitlines() for m in re.findall(r"^  (-{1,2}[a-z][a-z0-9-]*)", line)}


def _subparsers():
    return next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices


@pytest.mark.parametrize("command", sorted(BASIC_OPTIONS))
def test_help_shows_at_most_25_options_and_help_all_the_rest(command, capsys):
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    assert exc.value.code == 0
    short = capsys.readouterr().out
    with pytest.raises(SystemExit):
        main([command, "--help-all"])
    full = capsys.readouterr().out
    parser = _subparsers()[command]
    every = {a.option_strings[0] for a in parser._actions if a.option_strings}
    shown = {a.option_strings[0] for a in parser._actions if a.option_strings and _listed(short) & set(a.option_strings)}
    assert len(shown) <= 25 and "--help-all" in shown and "-h" in shown
    assert _listed(full) >= every                                      # --help-all: every option
    hidden = len(every) - len(shown)
    assert hidden > 0 and f"{hidden} more options: `visemeface {command} --help-all`" in short
    # the hidden options still work and still name themselves in errors
    assert {"--glue", "--msaa", "--dat-fps"} - shown <= every


def test_a_hidden_option_is_still_accepted():
    args = _subparsers()["speak"].parse_args(["t.txt", "--msaa", "0", "--interp", "linear"])
    assert args.msaa == 0 and args.interp == "linear"
    assert "--msaa" not in _listed(_subparsers()["speak"].format_help())


def test_the_basic_options_are_options_of_their_command():
    for command, options in BASIC_OPTIONS.items():
        known = {s for a in _subparsers()[command]._actions for s in a.option_strings}
        assert set(options) <= known, command


@pytest.mark.parametrize("command", sorted(c for c in _subparsers() if c not in BASIC_OPTIONS))
def test_every_command_takes_help_all_and_lists_every_option(command, capsys):
    """Every command's help names ``--help-all`` (its hint line does), so every command takes it, required
    arguments or not."""
    with pytest.raises(SystemExit) as exc:
        main([command, "--help-all"])
    assert exc.value.code == 0
    parser = _subparsers()[command]
    assert _listed(capsys.readouterr().out) >= {a.option_strings[0] for a in parser._actions if a.option_strings}


@pytest.mark.parametrize("command", sorted(BASIC_OPTIONS))
def test_the_examples_in_help_use_only_the_options_it_shows(command, capsys):
    """A user copies an example from ``--help`` and looks its options up on the same page."""
    with pytest.raises(SystemExit):
        main([command, "--help"])
    short = capsys.readouterr().out
    examples = short.split("examples:", 1)[1].split("\n\n", 1)[0] if "examples:" in short else ""
    used = {o for line in examples.splitlines() for o in re.findall(r"(?<![\w-])(--?[a-z][a-z0-9-]*)", line.split("#")[0])}
    assert used <= _listed(short), sorted(used - _listed(short))
