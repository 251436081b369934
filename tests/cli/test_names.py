"""One name, one idea: an option several commands take means the same on each (the same destination, the
same kind of value); the options table in the docs is the parsers' own."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))

from options_table import options_by_name  # noqa: E402

#: Options whose commands differ on purpose, with the reason.
DIFFERENT = {
    "--emotion": "pose blends several (repeatable, into `emotions`); the animating commands take one track-wide blend",
}


def _kind(action) -> str:
    return "flag" if action.nargs == 0 else ("choice" if action.choices else "value")


def test_an_option_of_several_commands_is_one_idea():
    clashes = []
    for name, uses in options_by_name().items():
        if name in DIFFERENT:
            continue
        kinds = {(_kind(a), a.dest) for _, a in uses}
        if len(kinds) > 1:
            clashes.append(f"{name}: " + ", ".join(f"{c} {_kind(a)} {a.dest}" for c, a in uses))
    assert not clashes, "\n".join(clashes)


def test_the_exceptions_are_still_exceptions():
    found = options_by_name()
    for name in DIFFERENT:
        assert len({(_kind(a), a.dest) for _, a in found[name]}) > 1, f"{name} is one idea now: drop it from DIFFERENT"


def test_the_options_page_is_what_the_parsers_say():
    done = subprocess.run([sys.executable, str(ROOT / "scripts" / "options_table.py"), "--check"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
