"""Safe output files: never overwrite without ``force``, never leave half a file.

Every command that writes files goes through :func:`atomic_output` (one file)
or :func:`atomic_dir` (a folder of files): the work is written under a
temporary name next to the target and renamed into place only when it is
complete, so an error or Ctrl-C leaves nothing half written.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from tqdm import tqdm

from visemeface.errors import InputError


def _umask_mode(mode: int) -> int:
    umask = os.umask(0)
    os.umask(umask)
    return mode & ~umask


def check_new(path: str | Path, force: bool = False) -> Path:
    """Return ``path`` as a Path; refuse it if it exists and ``force`` is false."""
    path = Path(path)
    if path.exists() and not force:
        raise InputError("output exists; use --force to overwrite", path)
    parent = path.parent
    if not parent.exists():
        raise InputError("output folder does not exist", parent)
    if not parent.is_dir():
        raise InputError("output folder is not a folder", parent)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError("output folder is not writable", parent)
    return path


def check_suffix(path: str | Path, *suffixes: str) -> Path:
    """Refuse an output whose name does not end in one of ``suffixes`` (e.g. ".png")."""
    path = Path(path)
    if path.suffix.lower() not in suffixes:
        raise InputError(f"the output must end in {' or '.join(suffixes)}", path)
    return path


def _temporary(make, path: Path):
    """Run ``make()`` (mkstemp/mkdtemp beside ``path``); OS refusals become InputError."""
    try:
        return make()
    except OSError as exc:
        raise InputError(f"cannot write here: {exc.strerror}", path) from None


@contextlib.contextmanager
def atomic_output(path: str | Path, force: bool = False) -> Iterator[Path]:
    """Yield a temporary path to write; rename it to ``path`` on success.

    The temporary file keeps the target's suffix (tools such as ffmpeg pick the
    format from it) and lives in the same folder, so the final rename is atomic.
    """
    path = check_new(path, force)
    fd, tmp = _temporary(lambda: tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix,
                                                 dir=path.parent), path)
    os.close(fd)
    tmp = Path(tmp)
    try:
        yield tmp
        # mkstemp makes 0600 files; give the result the mode a plain open() would.
        os.chmod(tmp, _umask_mode(0o666))
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextlib.contextmanager
def atomic_dir(path: str | Path, force: bool = False) -> Iterator[Path]:
    """Yield a temporary folder to fill; move it to ``path`` on success."""
    path = check_new(path, force)
    tmp = Path(_temporary(lambda: tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent), path))
    try:
        yield tmp
        os.chmod(tmp, _umask_mode(0o777))
        if path.exists():
            shutil.rmtree(path) if path.is_dir() else path.unlink()
        os.replace(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def progress(iterable=None, total: int | None = None, desc: str | None = None, unit: str = "frame", **kw):
    """A tqdm progress bar on stderr, silent when stderr is not a terminal."""
    return tqdm(iterable, total=total, desc=desc, unit=unit, disable=None, dynamic_ncols=True, **kw)
