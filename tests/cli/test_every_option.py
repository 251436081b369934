"""Every option of every sub-command, given an invalid value: exit 2, one line, nothing written, refused
before the work (no frame rendered or simulated, no clip, no alignment, no video analysed).

The cases are generated from the argparse parsers, so a new option or command is covered the day
it is added: a value-taking option gets a value of the wrong kind or out of every sensible range
(``nan``, ``-1e308``, ``-7``, a 20-digit integer, just past either end of a bounded number's range,
a choice that does not exist, a path in a folder that does not exist).
"""

import numpy as np
import pytest

from visemeface.cli import build_parser, main

TINY = "0.00 0.05 _\n0.05 0.25 aa\n0.25 0.30 _\n"

#: A valid invocation of each command (the option under test is added to it, or replaces its value).
BASE = {
    "face": ["-o", "f.png"],
    "pose": ["aa", "-o", "p.png"],
    "speak": ["t.txt"],
    "say": ["hi"],
    "muscles": [],
    "visemes": [],
    "emotions": [],
    "sheet": ["-o", "s.png"],
    "simulate": ["part"],
    "analyze": ["frames", "--box", "2,4,12,6", "-o", "a.csv"],
    "compare": ["p1.csv", "p2.csv"],
    "preview": ["a.glb"],
    "batch": ["jobs.csv", "-o", "out"],
    "lipsync": ["a.wav", "--text", "ah ee", "-o", "a.lab"],
    "retarget-check": ["--text", "bob"],
    "convert": ["r.tsv", "o.anim"],
    "live": ["a.wav", "--fast", "--track", "x.csv"],
}
#: Options (or positional arguments, by dest) that take no invalid value, with the reason.
FREE = {("say", "text"): "any text is spoken (letters it cannot say are refused, tested in tests/speech)",
        ("retarget-check", "--text"): "any text is spoken, as say's",
        ("lipsync", "--text"): "any words are aligned (words the recording does not say are refused by the "
                               "alignment, tested in tests/speech)"}


#: Where each command's work begins: a bad value must be refused before any of these is called (this
#: replaced a limit of 3 s, which measured the machine: under load the refusals took up to 11.7 s).
WORK = [("visemeface.pipeline", "run"), ("visemeface.physics.face_model", "build_fem_face"),
        ("visemeface.analysis.profiles", "analyze_source"), ("visemeface.batch.runner", "run"),
        ("visemeface.speech.align", "utterance_from_audio")]


def _work_began(name):
    def began(*args, **kwargs):
        raise AssertionError(f"{name} was called before the bad value was refused")
    return began


def _commands():
    sub = build_parser()._subparsers._group_actions[0]
    return sub.choices


def _bad_values(action):
    if action.choices:
        return ["zz-not-a-choice"]
    kind = getattr(action.type, "__name__", None)
    if kind == "int":
        return ["x", "-7"]
    if kind == "float":
        return ["nan", "-1e308"]
    if kind in ("number", "integer"):                 # visemeface.commands._options.number: its own range
        t = action.type
        bad = ["x", "nan", "-inf", "-1e308"] + ([] if t.infinite else ["inf"])
        if t.low is not None and t.low > -1e308:
            bad.append(f"{t.low - 1 if kind == 'integer' else t.low - 0.5 * max(abs(t.low), 1e-9):g}")
        if t.high is not None:
            bad += ["1e308", f"{t.high + 1 if kind == 'integer' else t.high * 1.5 + 1e-9:g}"]
        if kind == "integer":
            bad += ["99999999999999999999", "1.5"]
        return bad
    return ["/nonexistent-folder/x.bad"]


def _cases():
    for name, parser in _commands().items():
        assert name in BASE, f"add a valid invocation of `{name}` to BASE"
        positional = [a for a in parser._actions if not a.option_strings]
        for k, action in enumerate(positional):          # a missing file, a posture or scenario not known
            if (name, action.dest) not in FREE:
                for value in _bad_values(action):
                    yield pytest.param(name, k, value, id=f"{name} {action.dest.upper()} {value}")
        for action in parser._actions:
            if not action.option_strings or action.nargs == 0 or action.dest == "help":
                continue
            option = action.option_strings[-1]
            if (name, option) in FREE:
                continue
            for value in _bad_values(action):
                yield pytest.param(name, option, value, id=f"{name} {option} {value}")


@pytest.fixture(scope="module")
def prepared(tmp_path_factory, vowels_wav):
    import shutil

    import pandas as pd

    from visemeface.export.images import write_png

    root = tmp_path_factory.mktemp("inputs")
    (root / "t.txt").write_text(TINY)
    (root / "r.tsv").write_text("0.00\tX\n0.05\tD\n0.25\tX\n0.30\tX\n")
    (root / "jobs.csv").write_text("clip,transcript\nc1,t.txt\n")
    (root / "frames").mkdir()
    for i in range(3):
        write_png(root / "frames" / f"f{i}.png", np.full((16, 16, 3), 200, np.uint8))
    profile = pd.DataFrame({"frame": [0, 1, 2], "time": [0.0, 0.04, 0.08], "count": [0, 1, 1],
                            "area": [0.0, 0.1, 0.2], "width": [0.0, 0.5, 0.6], "height": [0.0, 0.1, 0.2]})
    profile.to_csv(root / "p1.csv", index=False)
    profile.to_csv(root / "p2.csv", index=False)
    from visemeface.export.gltf import write_morph_animation_glb

    tri = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    write_morph_animation_glb(root / "a.glb", tri, [[0, 1, 2]], tri[None] * 0.1, ["m"], [0.0, 1.0], [[0.0], [1.0]])
    shutil.copy(vowels_wav, root / "a.wav")
    return root


@pytest.fixture
def inputs(prepared, tmp_path):
    """A fresh copy of the inputs for each case (a case that wrongly succeeds cannot spoil the next)."""
    import shutil

    shutil.copytree(prepared, tmp_path / "in")
    return tmp_path / "in"


def _listing(folder):
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*"))


@pytest.mark.parametrize("command,option,value", list(_cases()))
def test_an_invalid_option_value_is_one_line_exit_2_and_writes_nothing(inputs, monkeypatch, capsys, command,
                                                                      option, value):
    monkeypatch.chdir(inputs)
    before = _listing(inputs)
    argv = list(BASE[command])
    if isinstance(option, int):                            # the k-th positional argument (BASE lists them first)
        argv[option] = value
    elif option in argv:
        argv[argv.index(option) + 1] = value
    else:
        argv += [f"{option}={value}"]
    for module, name in WORK:
        monkeypatch.setattr(f"{module}.{name}", _work_began(f"{module}.{name}"))
    code = main([command] + argv)
    err = capsys.readouterr().err
    assert code == 2, f"exit {code}: {err}"
    lines = [ln for ln in err.splitlines() if not ln.startswith("visemeface: warning:")]
    assert len(lines) == 1 and lines[0].startswith("visemeface: error: "), err
    assert "np.float64" not in err and "Traceback" not in err and not any(len(w) > 40 for w in err.split())
    assert _listing(inputs) == before
