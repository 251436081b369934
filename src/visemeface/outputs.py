"""Safe output files: never overwrite without ``force``, never leave half a file.

Every file or folder a command writes is *staged*: written under a temporary
name beside its target and renamed into place only when complete. One output
uses :func:`atomic_output` (a file) or :func:`atomic_dir` (a folder); a run
with several outputs stages each (:class:`Staged`) and commits them together
only after all of them are complete (:class:`visemeface.pipeline`), so a run
writes all of its outputs or none.

Temporaries are named ``.<target name>.vf<pid>~<suffix>`` (the suffix kept:
ffmpeg picks the format from it). A process killed outright (SIGKILL, power
loss) cannot remove its own; the next run writing the same target removes
every temporary of that target whose process is gone (:func:`remove_stale`).
"""

from __future__ import annotations

import contextlib
import contextvars
import errno
import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path

from tqdm import tqdm

from visemeface.errors import InputError


#: Where :meth:`Staged.commit` notes each output it puts in place while set to a list (the Python API's
#: :class:`visemeface.api.Result` reads it); None, the default, notes nothing.
WRITTEN: contextvars.ContextVar[list | None] = contextvars.ContextVar("visemeface_written", default=None)


def _umask_mode(mode: int) -> int:
    umask = os.umask(0)
    os.umask(umask)
    return mode & ~umask


#: What visemeface's folder outputs hold: frame files (PNG, OBJ) and a frame's temporary left by a killed
#: run (``.frame_000012.png.tmp``), the OBJ sequence's palette and hidden manifests
#: (``.visemeface-frames.json``); staged temporaries (:func:`is_temporary`) too. Six digits: ``images.FRAME_DIGITS``.
_OURS = re.compile(r"^(\.?frame_\d{6}\.(png|obj)(\.tmp)?|face\.mtl|\.visemeface.*)$")


def holds_only_ours(folder: str | Path) -> bool:
    """True if every entry of ``folder`` is a file a visemeface folder output writes (:data:`_OURS`):
    the folders ``--force`` may replace, so a user's own files in them are never deleted."""
    return all((_OURS.match(p.name) or is_temporary(p)) and p.is_file() for p in Path(folder).iterdir())


def output_path(path: str | Path) -> Path:
    """``path`` as a Path with a name: ``.`` and ``..`` (which name no file) made absolute."""
    path = Path(path)
    return Path(os.path.abspath(path)) if path.name in ("", "..") else path


def _holds_cwd(path: Path) -> bool:
    try:
        cwd = Path.cwd().resolve()
    except OSError:
        return False
    return cwd == path.resolve() or path.resolve() in cwd.parents


def check_new(path: str | Path, force: bool = False, folder: bool | None = None, ours=holds_only_ours) -> Path:
    """Return ``path`` as a Path; refuse it if it exists and ``force`` is false.

    ``folder`` True/False also refuses replacing a file by a folder or a folder by
    a file (even with ``force``: that is almost always a typo). An existing folder is
    replaced (``folder`` True) only if ``ours(path)``: by default, if it holds nothing
    but what visemeface writes there (:func:`holds_only_ours`).
    """
    path = output_path(path)
    if path.exists() or path.is_symlink():
        if not force:
            raise InputError("output exists; use --force to overwrite", path)
        if folder is False and path.is_dir():
            raise InputError("output exists and is a folder, not a file", path)
        if folder is True and not path.is_dir():
            raise InputError("output exists and is a file, not a folder", path)
        if folder is True and path.is_symlink():
            raise InputError("output folder is a symbolic link; name the folder it points to", path)
        if folder is True and _holds_cwd(path):
            raise InputError("output folder is the current folder or holds it; name a new folder", path)
        if folder is True and not ours(path):
            raise InputError("output folder holds files visemeface did not write; --force replaces only "
                             "a folder of ours: move them or choose another folder", path)
    parent = path.parent
    if not parent.exists():
        raise InputError("output folder does not exist", parent)
    if not parent.is_dir():
        raise InputError("output folder is not a folder", parent)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError("output folder is not writable", parent)
    _probe(path)
    return path


def _probe(path: Path) -> None:
    """Create and remove the temporary ``path`` would be staged in: access() says yes to root everywhere,
    and some folders take no new file at all (``/proc``), which was found only after the work."""
    from visemeface.runtime import signals_deferred

    probe = _temporary_name(path).with_name(_temporary_name(path).name + "probe")
    with signals_deferred():                # an interrupt between the create and the remove left the probe
        try:
            fd = os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
        except FileExistsError:
            return
        except OSError as exc:
            # the folder exists (checked above), so "no such file" means it takes no new files (/proc, /sys)
            why = "it takes no new files" if exc.errno == errno.ENOENT else exc.strerror
            raise InputError(f"cannot write in the output folder ({why})", path.parent) from None
        os.close(fd)
        os.unlink(probe)


def check_not_inputs(targets, inputs, what: str = "an input") -> None:
    """Refuse an output that is one of ``inputs`` or a folder holding one: writing it would overwrite, or
    replacing the folder delete, what the run reads. ``what`` names the input in the message."""
    inputs = [Path(p).resolve() for p in inputs]
    for target in targets:
        r = output_path(target).resolve()
        if any(r == i or r in i.parents for i in inputs):
            raise InputError(f"the output would overwrite {what}; name another output", target)


def check_suffix(path: str | Path, *suffixes: str) -> Path:
    """Refuse an output whose name does not end in one of ``suffixes`` (e.g. ".png")."""
    path = Path(path)
    if path.suffix.lower() not in suffixes:
        raise InputError(f"the output must end in {' or '.join(suffixes)}", path)
    return path


def _temporary_name(path: Path, pid: int | None = None) -> Path:
    return path.with_name(f".{path.name}.vf{os.getpid() if pid is None else pid}~{path.suffix}")


_TEMPORARY = re.compile(r"^\..+\.vf\d+~")


def is_temporary(path: str | Path) -> bool:
    """True for a staged temporary of ours (``.<name>.vf<pid>~<suffix>``)."""
    return _TEMPORARY.match(Path(path).name) is not None


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale(path: str | Path) -> list[Path]:
    """Remove the temporaries of ``path`` left by processes that no longer run; return them."""
    path = Path(path)
    pattern = re.compile(rf"^\.{re.escape(path.name)}\.vf(\d+)~")
    removed = []
    try:
        entries = list(path.parent.iterdir())
    except OSError:
        return removed
    for p in entries:
        m = pattern.match(p.name)
        if m and int(m.group(1)) != os.getpid() and not _pid_alive(int(m.group(1))):
            shutil.rmtree(p, ignore_errors=True) if p.is_dir() and not p.is_symlink() else p.unlink(missing_ok=True)
            removed.append(p)
    return removed


class Staged:
    """One output written under a temporary name, renamed into place by :meth:`commit`.

    The target is checked when the object is made (before any work); :meth:`open`
    creates the temporary (removing stale ones of the same target) and returns it;
    :meth:`commit` renames it into place; :meth:`abort` removes it.

    Parameters
    ----------
    path : str or Path
        The target.
    force : bool
        Replace an existing target (of the same kind).
    folder : bool
        Stage a folder instead of a file.
    ours : callable
        For a folder: whether an existing one may be replaced (:func:`check_new`).
    """

    def __init__(self, path: str | Path, force: bool = False, folder: bool = False, ours=holds_only_ours):
        self.path = check_new(path, force, folder=folder, ours=ours)
        self.force, self.folder = force, folder
        self.tmp: Path | None = None

    def open(self) -> Path:
        remove_stale(self.path)
        tmp = _temporary_name(self.path)
        try:
            if tmp.exists():
                shutil.rmtree(tmp) if tmp.is_dir() else tmp.unlink()
            tmp.mkdir() if self.folder else tmp.touch()
        except OSError as exc:
            raise InputError(f"cannot write here: {exc.strerror}", self.path) from None
        self.tmp = tmp
        return tmp

    def commit(self) -> Path:
        tmp, self.tmp = self.tmp, None
        os.chmod(tmp, _umask_mode(0o777 if self.folder else 0o666))
        if self.folder and self.path.is_dir():
            shutil.rmtree(self.path)          # os.replace cannot replace a non-empty folder
        os.replace(tmp, self.path)
        noted = WRITTEN.get()
        if noted is not None:
            noted.append(self.path)
        return self.path

    def abort(self) -> None:
        tmp, self.tmp = self.tmp, None
        if tmp is None:
            return
        if tmp.is_dir() and not tmp.is_symlink():
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            tmp.unlink(missing_ok=True)


@contextlib.contextmanager
def _staged(path, force: bool, folder: bool) -> Iterator[Path]:
    if is_temporary(path):
        # Already a staged temporary (a sink handing its temporary to a writer): write it in place,
        # so no temporary of a temporary exists that the next run could not recognise.
        yield Path(path)
        return
    out = Staged(path, force, folder)
    tmp = out.open()
    try:
        yield tmp
    except BaseException:
        out.abort()
        raise
    out.commit()


def atomic_output(path: str | Path, force: bool = False):
    """Context manager: yield a temporary file path to write; rename it to ``path`` on success.

    The temporary keeps the target's suffix and lives in the same folder, so the
    rename is atomic; an error or Ctrl-C removes it.
    """
    return _staged(path, force, folder=False)


def atomic_dir(path: str | Path, force: bool = False):
    """Context manager: yield a temporary folder to fill; move it to ``path`` on success."""
    return _staged(path, force, folder=True)


def progress(iterable=None, total: int | None = None, desc: str | None = None, unit: str = "frame",
             show: bool = True, **kw):
    """A tqdm progress bar on stderr, silent when stderr is not a terminal (or ``show`` is false)."""
    return tqdm(iterable, total=total, desc=desc, unit=unit, disable=None if show else True,
                dynamic_ncols=True, **kw)
