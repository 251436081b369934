import subprocess
import sys

import pytest

from visemeface import __version__
from visemeface.cli import main


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert __version__ in capsys.readouterr().out


def test_help_lists_commands(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    assert "usage: visemeface" in out
    assert main([]) == 2                          # no command: a usage error, one line
    err = capsys.readouterr().err
    assert "name a command" in err and err.count("\n") == 1


@pytest.mark.slow
def test_console_entry_point_runs():
    proc = subprocess.run([sys.executable, "-m", "visemeface", "--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and __version__ in proc.stdout


def test_simulate_help_gives_the_speech_lips_tissue_limit_the_code_uses(capsys):
    """The epilogue's numbers are typed, the default is materials.TISSUE_LIMIT: they must agree."""
    from visemeface.physics.materials import TISSUE_LIMIT
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert f"stretch of {TISSUE_LIMIT:g} (Gent)" in out and f"default {TISSUE_LIMIT:g}" in out


@pytest.mark.parametrize("status", [0, 2])
def test_a_signal_after_the_work_ends_with_the_commands_own_status_and_says_nothing(status):
    """Once a command's work is done (its outputs whole), a Ctrl-C in the last milliseconds of the process
    (its exit functions) must not report the run as interrupted: 130 there read as a run stopped part way."""
    code = ("import atexit, os, signal, time\n"
            "from visemeface import cli\n"
            "atexit.register(lambda: (os.kill(os.getpid(), signal.SIGINT), time.sleep(5)))\n"
            f"cli._end({status})\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert p.returncode == status and "interrupted" not in p.stderr, (p.returncode, p.stderr)
