"""The checkpoint of a resumable run: a folder beside its main output.

``<output>.checkpoint/`` holds

- ``state.npz``: the motion's state after the last finished frame (numpy arrays,
  numbers and strings only; read with ``allow_pickle=False``), the number of
  finished frames and the motion's key;
- ``vertices.f32``: the vertices of every finished frame (float32, appended), so
  a resumed run replays them into the sinks instead of simulating them again;
- ``data.jsonl``: each finished frame's measures, one JSON object a line.

The state is written after the frame's vertices, each time under a temporary
name and renamed, so the folder always describes a consistent prefix of the
run; frames recorded after the last state (an interruption between the two)
are cut off when the run resumes. The folder is removed when the run
completes, and when it diverges (:mod:`visemeface.pipeline`: a resumed run would
diverge at the same step).
"""

from __future__ import annotations

import json
import os
import shutil
import zipfile
from pathlib import Path

import numpy as np

from visemeface.errors import InputError
from visemeface.motion import Frame

STATE, VERTICES, DATA = "state.npz", "vertices.f32", "data.jsonl"
_RESERVED = ("_frames_done", "_key", "_settings")


def checkpoint_folder(output: str | Path) -> Path:
    """``out.mp4`` -> ``out.mp4.checkpoint``."""
    output = Path(output)
    return output.with_name(output.name + ".checkpoint")


class RunCheckpoint:
    """Save and restore a resumable run (see the module docstring).

    Parameters
    ----------
    folder : Path
        The checkpoint folder (:func:`checkpoint_folder` of the main output).
    key : str
        The motion's key: a checkpoint of another run is refused.
    n_vertices : int
    fps : float
    settings : dict, optional
        The run's named settings (:meth:`visemeface.motion.Motion.settings`), saved beside the key so that a
        refused checkpoint can say which of them differ.
    """

    def __init__(self, folder: str | Path, key: str, n_vertices: int, fps: float, settings: dict | None = None):
        self.folder = Path(folder)
        self.key, self.n_vertices, self.fps = key, int(n_vertices), float(fps)
        self.settings = dict(settings or {})
        self._vfile = None
        self._dfile = None

    # ------------------------------------------------------------------ before the run
    def check(self, resume: bool, force: bool) -> None:
        """Refuse to silently discard or wrongly reuse a checkpoint (before any work)."""
        exists = self.folder.exists()
        if exists and not self.folder.is_dir():
            raise InputError("exists and is not a checkpoint folder", self.folder)
        if exists and not resume and not force:
            raise InputError("a checkpoint of an interrupted run is here; use --resume to continue it or "
                             "--force to start over", self.folder)
        if resume and exists:
            self.load()    # validates it

    def load(self) -> tuple[int, dict | None]:
        """(finished frames, motion state) of the checkpoint; (0, None) if there is none."""
        path = self.folder / STATE
        if not path.is_file():
            return 0, None
        try:
            with np.load(path, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
            done, key = data.pop("_frames_done"), data.pop("_key")
            if done.shape or done.dtype.kind not in "iu" or key.shape or key.dtype.kind != "U":
                raise ValueError("wrong type of the frame count or key")
            done, key = int(done), str(key)
            saved = json.loads(str(data.pop("_settings"))) if "_settings" in data else None
            if saved is not None and not isinstance(saved, dict):
                raise ValueError("the settings are no mapping")
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
            raise InputError(f"not a readable checkpoint ({type(exc).__name__}); remove it or use --force "
                             "to start over", path) from None
        if key != self.key:
            raise InputError(f"the checkpoint belongs to a different run ({self._differences(saved)}); use the "
                             "same input and options, or --force to start over", self.folder)
        have = self._frames_on_disk()
        if done < 1 or have < done:
            raise InputError(f"the checkpoint is incomplete ({have} of {done} frames); use --force to start "
                             "over", self.folder)
        state = {k: (v.item() if v.ndim == 0 and v.dtype.kind in "iufb" else v) for k, v in data.items()}
        for k, v in list(state.items()):
            if isinstance(v, np.ndarray) and v.ndim == 0 and v.dtype.kind == "U":
                state[k] = str(v)
        return done, state

    def _differences(self, saved: dict | None) -> str:
        """Which named settings differ from the checkpoint's, e.g. "tissue_limit 2.5 then, inf now"."""
        if not saved or not self.settings:
            return "other input or options"
        names = sorted(k for k in set(saved) | set(self.settings) if saved.get(k) != self.settings.get(k))
        if not names:
            return "other input, the same options"
        said = [f"{k} {saved.get(k, '(none)')} then, {self.settings.get(k, '(none)')} now" for k in names[:3]]
        return "; ".join(said) + (f"; and {len(names) - 3} more" if len(names) > 3 else "")

    def _frames_on_disk(self) -> int:
        try:
            return (self.folder / VERTICES).stat().st_size // (12 * self.n_vertices)
        except OSError:
            return 0

    # ------------------------------------------------------------------ during the run
    def replay(self, index: int) -> Frame:
        """Finished frame ``index`` as it was recorded."""
        with open(self.folder / VERTICES, "rb") as fh:
            fh.seek(12 * self.n_vertices * index)
            v = np.frombuffer(fh.read(12 * self.n_vertices), dtype="<f4").reshape(-1, 3).copy()
        return Frame(index, index / self.fps, v, self._data_rows()[index])

    def _data_rows(self) -> list[dict]:
        if not hasattr(self, "_rows"):
            try:
                lines = (self.folder / DATA).read_text().splitlines()
            except OSError:
                lines = []
            self._rows = [json.loads(ln) for ln in lines]
        return self._rows

    def start(self, done: int) -> None:
        """Open for appending after ``done`` finished frames (cutting off anything later)."""
        self.folder.mkdir(exist_ok=True)
        if done:
            self._data_rows()
        self._vfile = open(self.folder / VERTICES, "r+b" if done else "wb")
        self._vfile.truncate(12 * self.n_vertices * done)
        self._vfile.seek(0, os.SEEK_END)
        rows = self._data_rows()[:done] if done else []
        with open(self.folder / DATA, "w") as fh:
            fh.writelines(json.dumps(r) + "\n" for r in rows)
        self._dfile = open(self.folder / DATA, "a")

    def record(self, frame: Frame) -> None:
        """Append a finished frame's vertices and measures."""
        self._vfile.write(np.asarray(frame.vertices, dtype="<f4").tobytes())
        self._dfile.write(json.dumps(frame.data) + "\n")

    def save(self, state: dict, done: int) -> None:
        """Save the motion's state after ``done`` finished frames (atomically)."""
        self._vfile.flush()
        self._dfile.flush()
        bad = [k for k in state if k in _RESERVED]
        if bad:
            raise ValueError(f"state key {bad[0]!r} is reserved")
        tmp = self.folder / (".tmp." + STATE)
        with open(tmp, "wb") as fh:
            np.savez(fh, _frames_done=np.int64(done), _key=np.str_(self.key),
                     _settings=np.str_(json.dumps(self.settings)), **state)
        os.replace(tmp, self.folder / STATE)

    def close(self) -> None:
        for f in (self._vfile, self._dfile):
            if f is not None:
                f.close()
        self._vfile = self._dfile = None

    def remove(self) -> None:
        self.close()
        shutil.rmtree(self.folder, ignore_errors=True)
