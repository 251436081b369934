"""Transcript or text to video and exports: the glue behind ``visemeface speak`` and ``say``.

::

    Segments --timeline--> ActivationTrack --rig.pose--> vertices --Renderer--> RGB frame
                                                                 \\--> OBJ / PC2     \\--> MP4 / PNG

Frames are **streamed**: for each row of the activation track the face is
posed, rendered and handed to every writer before the next row is touched, so
memory does not grow with the length of the utterance (only the track itself,
26 floats a frame, is held). The glTF export needs no rendering: it stores the
rig's basis fields as morph targets and the track as morph weights.

Everything the user can get wrong (transcript, emotion names, audio file,
existing outputs, an incompatible ``--resume`` folder) is checked by
:func:`plan_outputs` and the loaders *before* the first frame is rendered.

Resuming
--------
``--frames DIR`` renders into ``DIR.partial/`` next to ``DIR``; each PNG is
written under a temporary name and renamed, so any ``frame_NNNNNN.png`` found
there is complete. A hidden manifest (``.visemeface-frames.json``) records a
SHA-256 *render key* of everything the pixels depend on: the package version,
the frame size, view and antialiasing, the face (vertices, triangles, colours), the rig (its
displacement for each unit activation and for the jaw at several openings) and
the activation track itself. When every frame is written the folder is renamed
to ``DIR``. After an interruption, ``--resume`` reuses the frames in
``DIR.partial/`` (or a finished ``DIR``) whose key matches: rendering is
deterministic, so a kept frame is bit-identical to the one that would be
rendered again. Kept frames are read back (for the MP4), not rendered. A key
mismatch is refused before rendering starts.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import shutil
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from visemeface import __version__
from visemeface.errors import InputError, close_matches
from visemeface.outputs import check_new, progress
from visemeface.render import export

#: Jaw openings (as fractions of the jaw's range) exported as glTF morph targets.
JAW_SAMPLES = 8
MANIFEST = ".visemeface-frames.json"


# --------------------------------------------------------------------------- inputs


def check_audio(path) -> float:
    """Duration in seconds of a sound file; :class:`InputError` if it cannot be read."""
    import soundfile as sf

    path = Path(path)
    if not path.is_file():
        raise InputError("audio file not found", path)
    try:
        info = sf.info(str(path))
    except Exception as exc:  # soundfile raises its own LibsndfileError / RuntimeError
        raise InputError(f"unreadable audio ({str(exc).splitlines()[0]})", path) from None
    if info.frames <= 0 or info.samplerate <= 0:
        raise InputError("audio file holds no samples", path)
    return info.frames / info.samplerate


def parse_emotions(specs, known) -> dict[str, float]:
    """``["happiness=0.6", "anger"]`` -> ``{"happiness": 0.6, "anger": 1.0}``, names checked.

    Parameters
    ----------
    specs : list of str or None
        ``NAME[=WEIGHT]`` items (comma-separated lists allowed).
    known : iterable of str
        Valid emotion names (the expression table's index).
    """
    from visemeface.postures.library import parse_weights

    emotions = parse_weights(specs)
    known = list(known)
    for name in emotions:
        if name not in known:
            raise InputError(f"unknown emotion {name!r}{close_matches(name, known)}")
    return emotions


def track_matrix(track: pd.DataFrame, rig) -> np.ndarray:
    """The track's activations as an (F, M) float array in ``rig.names`` order, clamped
    (:meth:`MuscleRig.track_matrix`, then :meth:`MuscleRig.clamp`)."""
    return rig.clamp(rig.track_matrix(track))


# --------------------------------------------------------------------------- glTF from the rig


def _muscle_bases(rig) -> np.ndarray:
    """(M, N, 3) muscle displacements at activation 1 (unclamped; ``rig.bases``)."""
    return np.asarray(rig.bases, dtype=np.float64)


def _jaw_displacement(rig, value: float) -> np.ndarray:
    return np.asarray(rig.jaw_displacement(value), dtype=np.float64)


def rig_morph_targets(rig, jaw_samples: int = JAW_SAMPLES):
    r"""Morph targets for the rig: one per muscle basis, a few for the (nonlinear) jaw.

    Muscle displacements are linear in the activation (Waters functions are
    evaluated on rest positions), so muscle ``m``'s target is its basis field
    :math:`B_m` = displacement at activation 1, and its morph weight is its
    activation. The jaw is a rotation weighted per vertex, which is not linear
    in its activation and not a single rigid joint either (linear-blend
    skinning of one joint would shrink the arc: :math:`(1-w)x + wR(\theta)x
    \ne R(w\theta)x`). It is exported as ``jaw_samples`` *sampled morphs*: the
    jaw displacement at openings :math:`a_k = k\,u/K` (``u`` the jaw's range
    maximum; a negative range, a clenching jaw, gets samples at the same
    spacing), played with the hat weights of
    :func:`~visemeface.render.export.jaw_sample_weights`; this plays
    identically in every glTF viewer (Blender shape keys, three.js morph
    targets) and deviates from the rig only by the chord sag of one sample
    interval.

    Returns
    -------
    targets : (M - 1 + K, N, 3) float
    names : list of str
        Muscle names, then ``jaw@<opening>``.
    samples : (K,) float
        The jaw openings :math:`a_k`.
    """
    names = list(rig.names)
    j = names.index("jaw")
    ranges = np.asarray(rig.ranges, dtype=np.float64).reshape(len(names), 2)
    lo, hi = ranges[j]
    if not lo <= 0 < hi:
        raise ValueError(f"jaw range must contain 0 and a positive opening, got [{lo}, {hi}]")
    step = hi / jaw_samples
    n_neg = int(np.ceil(-lo / step - 1e-9)) if lo < 0 else 0  # a closing jaw (lo < 0) too
    samples = np.concatenate([lo * np.arange(n_neg, 0, -1) / max(n_neg, 1),
                              step * np.arange(1, jaw_samples + 1)])
    if j != len(names) - 1:
        raise ValueError("the rig's last function must be the jaw")
    targets = list(_muscle_bases(rig)) + [_jaw_displacement(rig, s) for s in samples]
    tnames = [n for n in names if n != "jaw"] + [f"jaw@{s:.4g}" for s in samples]
    return np.stack(targets), tnames, samples


def morph_weights(a: np.ndarray, rig, samples: np.ndarray) -> np.ndarray:
    """(F, M - 1 + K) morph weights for activations ``a`` (F, M) (see :func:`rig_morph_targets`)."""
    names = list(rig.names)
    j = names.index("jaw")
    muscles = np.delete(a, j, axis=1)
    return np.hstack([muscles, export.jaw_sample_weights(a[:, j], samples)])


def write_gltf(path, rig, track: pd.DataFrame, force: bool = False,
               jaw_samples: int = JAW_SAMPLES, end_time: float | None = None) -> None:
    """Write the rig's face with morph targets and ``track`` as a morph animation (.glb).

    Keyframes are the track's rows (one a frame, LINEAR between them). The
    track's last row lies up to one frame before the end of the utterance;
    with ``end_time`` a final keyframe holding the last pose is added there,
    so the animation lasts exactly as long as the utterance.
    """
    a = track_matrix(track, rig)
    targets, names, samples = rig_morph_targets(rig, jaw_samples)
    face = rig.face
    times = track.index.to_numpy(dtype=np.float64)
    if end_time is not None and end_time > times[-1] + 1e-6:
        times = np.append(times, end_time)
        a = np.vstack([a, a[-1:]])
    export.write_morph_animation_glb(path, face.vertices, face.triangles, targets, names, times,
                                     morph_weights(a, rig, samples), colors=face.vertex_colors(),
                                     normals=face.vertex_normals(), force=force)


# --------------------------------------------------------------------------- resumable frames


def _digest(h, array) -> None:
    arr = np.ascontiguousarray(array)
    h.update(str((arr.dtype.str, arr.shape)).encode())
    h.update(arr.tobytes())


def render_key(rig, a: np.ndarray, size: int, view: str) -> str:
    """SHA-256 of everything a rendered frame depends on (see the module docstring)."""
    h = hashlib.sha256()
    h.update(json.dumps({"version": __version__, "size": size, "view": view,
                         "names": list(rig.names)}).encode())
    face = rig.face
    _digest(h, np.asarray(face.vertices, np.float64))
    _digest(h, np.asarray(face.triangles, np.int64))
    _digest(h, np.asarray(face.vertex_colors(), np.float32))
    _digest(h, _muscle_bases(rig))
    for s in (0.25, 0.5, 1.0):
        _digest(h, _jaw_displacement(rig, s))
    _digest(h, np.asarray(a, np.float64))
    return h.hexdigest()


class FrameFolder:
    """A PNG-sequence folder that survives interruption and can be resumed.

    Frames go to ``<folder>.partial`` (each PNG atomically); :meth:`finish`
    renames it to ``folder``. See the module docstring for the mechanism.

    Parameters
    ----------
    folder : Path
        The final folder (``--frames DIR``).
    key : str
        Render key of this run (:func:`render_key`).
    resume : bool
        Reuse matching frames from an interrupted (or finished) run.
    force : bool
        Replace an existing ``folder`` (without ``resume``).
    """

    def __init__(self, folder, key: str, resume: bool = False, force: bool = False):
        self.folder = Path(folder)
        self.partial = self.folder.with_name(self.folder.name + ".partial")
        self.key = key
        self.resume = resume
        self.force = force
        self.kept = 0
        self.rendered = 0
        self._source: Path | None = None

    @staticmethod
    def _manifest_key(folder: Path) -> str | None:
        try:
            return json.loads((folder / MANIFEST).read_text())["key"]
        except (OSError, ValueError, KeyError, TypeError):
            return None

    def check(self) -> None:
        """Validate against what is on disk; raise :class:`InputError` before any work."""
        if not self.folder.parent.is_dir():
            raise InputError("output folder does not exist", self.folder.parent)
        for cand in (self.partial, self.folder):
            if cand.exists() and not cand.is_dir():
                raise InputError("exists and is not a folder", cand)
        if self.resume:
            found = [c for c in (self.partial, self.folder) if c.is_dir()]
            for cand in found:
                key = self._manifest_key(cand)
                if key is None:
                    raise InputError("cannot resume: no visemeface frame manifest here", cand)
                if key != self.key:
                    raise InputError("cannot resume: these frames were rendered from another transcript "
                                     "or other settings (remove the folder or drop --resume)", cand)
            self._source = found[0] if found else None
        else:
            check_new(self.folder, self.force)
            if self.partial.exists() and self._manifest_key(self.partial) is None:
                raise InputError("exists and was not made by visemeface; move it away", self.partial)

    def __enter__(self) -> FrameFolder:
        if self._source is None and self.partial.exists():
            shutil.rmtree(self.partial)  # a stale partial run of ours, not resumed: start afresh
        if self._source == self.folder:
            self.folder.rename(self.partial)  # resume from a finished run: work on it in place
        self.partial.mkdir(exist_ok=True)
        (self.partial / MANIFEST).write_text(json.dumps({"key": self.key, "version": __version__}))
        return self

    def has(self, index: int) -> bool:
        return self.resume and (self.partial / export.frame_name(index)).is_file()

    def read(self, index: int, shape: tuple[int, ...]) -> np.ndarray | None:
        """The kept frame ``index``, or None if it cannot be read or has another shape."""
        try:
            image = export.read_png(self.partial / export.frame_name(index))
        except InputError:
            return None
        if image.shape != shape:
            return None
        self.kept += 1
        return image

    def write(self, index: int, image: np.ndarray) -> None:
        export.write_png(self.partial / export.frame_name(index), image)
        self.rendered += 1

    def finish(self, n_frames: int) -> None:
        """Drop frames beyond ``n_frames`` and stray temporaries; rename into place."""
        for p in self.partial.iterdir():
            if p.name == MANIFEST:
                continue
            stem = p.name.removeprefix("frame_").removesuffix(".png")
            if not (p.name.startswith("frame_") and stem.isdigit() and int(stem) < n_frames):
                p.unlink()
        if self.folder.exists():
            shutil.rmtree(self.folder) if self.folder.is_dir() else self.folder.unlink()
        self.partial.rename(self.folder)

    def __exit__(self, exc_type, exc, tb):
        if exc_type is not None and self.partial.exists():
            n = sum(1 for p in self.partial.glob("frame_*.png"))
            warnings.warn(f"{n} finished frame(s) kept in {self.partial}; rerun with --resume to continue",
                          stacklevel=2)
        return False


# --------------------------------------------------------------------------- the job


@dataclass
class Outputs:
    """Where ``animate`` writes; ``None`` = not wanted."""

    video: Path | None = None
    frames: Path | None = None
    obj: Path | None = None
    pc2: Path | None = None
    gltf: Path | None = None
    track: Path | None = None
    force: bool = False
    resume: bool = False

    def paths(self) -> dict[str, Path]:
        return {k: Path(v) for k, v in [("video", self.video), ("frames", self.frames), ("obj", self.obj),
                                        ("pc2", self.pc2), ("gltf", self.gltf), ("track", self.track)]
                if v is not None}


def plan_outputs(out: Outputs) -> None:
    """Check every output before any work: distinct, parent folders exist, no overwrite."""
    paths = out.paths()
    if not paths:
        raise InputError("nothing to write: give a video output or an export "
                         "(--frames, --obj, --pc2, --gltf, --track)")
    seen: dict[Path, str] = {}
    for kind, p in paths.items():
        r = p.resolve()
        if r in seen:
            raise InputError(f"the {kind} and {seen[r]} outputs are the same path", p)
        seen[r] = kind
    if out.resume and out.frames is None:
        raise InputError("--resume needs --frames DIR (the finished frames are kept there)")
    suffixes = {"video": ".mp4", "pc2": ".pc2", "gltf": ".glb", "track": ".csv"}
    for kind, suffix in suffixes.items():
        if kind in paths and paths[kind].suffix.lower() != suffix:
            raise InputError(f"the {kind} output must end in {suffix}", paths[kind])
    for kind, p in paths.items():
        if kind != "frames" or not out.resume:  # --resume may reuse an existing frames folder
            check_new(p, out.force)
    if out.video is not None:
        check_new(video_sidecar(out.video), out.force)


def video_sidecar(video: Path) -> Path:
    """``out.mp4.json``: the mouth box and frame rate, so ``visemeface analyze out.mp4`` needs no --box."""
    return Path(video).parent / (Path(video).name + ".json")


@dataclass
class RenderSettings:
    size: int = 512
    view: str = "face"
    msaa: int = 4
    fps: float = 30.0
    audio: Path | None = None
    show_progress: bool = True
    stats: dict = field(default_factory=dict)


def animate(track: pd.DataFrame, rig, out: Outputs, settings: RenderSettings,
            end_time: float | None = None, poses=None, poses_key: str = "") -> dict:
    """Pose, render and export every frame of ``track``, streaming.

    Parameters
    ----------
    track : ActivationTrack
        One row per frame (index = time in s), columns including ``rig.names``.
    rig : MuscleRig
        Poses the face (``rig.pose``); ``rig.face`` is rendered.
    out : Outputs
        Files to write (checked again here, before rendering).
    settings : RenderSettings
        Frame size, view, frame rate, audio to mux.
    end_time : float, optional
        End of the utterance (s), where the glTF animation ends.
    poses : iterator of (N, 3) arrays, optional
        The vertices of each frame, in order, instead of ``rig.pose`` of each
        row: e.g. :func:`visemeface.physics.drive.simulate_track` for
        ``--physics sticky|elastic``. It is advanced once per frame, also for
        frames kept by ``--resume`` (a simulation has to pass through them).
    poses_key : str
        What ``poses`` depends on beyond the track (physics settings), part of
        the frames' render key.

    Returns
    -------
    dict
        ``frames``, ``rendered``, ``kept`` (frames reused by ``--resume``).
    """
    plan_outputs(out)
    if settings.size % 16 or settings.size < 16:
        raise InputError(f"--size must be a positive multiple of 16, got {settings.size}")
    if settings.audio is not None:
        check_audio(settings.audio)
    a = track_matrix(track, rig)
    n = len(a)
    if n == 0:
        raise InputError("the activation track has no frames")
    need_image = out.video is not None or out.frames is not None
    frames = None
    if out.frames is not None:
        frames = FrameFolder(out.frames, render_key(rig, a, settings.size,
                                              f"{settings.view}/msaa{settings.msaa}{poses_key}"),
                             resume=out.resume, force=out.force)
        frames.check()

    face = rig.face
    with contextlib.ExitStack() as stack:
        renderer = None
        if need_image:
            from visemeface.render.renderer import Renderer

            renderer = stack.enter_context(
                Renderer(face, size=(settings.size, settings.size), view=settings.view,
                         samples=settings.msaa))
            mouth_box = renderer.mouth_box()
        video = obj = pc2 = None
        if out.video is not None:
            video = stack.enter_context(export.VideoWriter(
                out.video, (settings.size, settings.size), settings.fps, audio=settings.audio,
                n_frames=n, force=out.force))
        if out.obj is not None:
            obj = stack.enter_context(export.ObjSequenceWriter(out.obj, face.triangles, force=out.force))
        if out.pc2 is not None:
            pc2 = stack.enter_context(export.Pc2Writer(out.pc2, len(face.vertices), force=out.force))
        if frames is not None:
            stack.enter_context(frames)
        desc = "rendering" if poses is None else "simulating"
        bar = progress(range(n), total=n, desc=desc) if settings.show_progress else range(n)
        for i in bar:
            kept = frames is not None and frames.has(i)
            verts = None
            if poses is not None:
                verts = np.asarray(next(poses))
            elif obj is not None or pc2 is not None or (renderer is not None and not kept):
                verts = np.asarray(rig.pose(a[i]))
            if need_image:
                image = frames.read(i, (settings.size, settings.size, 3)) if kept else None
                if image is None:
                    if verts is None:
                        verts = np.asarray(rig.pose(a[i]))
                    image = renderer.render(verts)
                    if frames is not None:
                        frames.write(i, image)
                if video is not None:
                    video.write(image)
            if obj is not None:
                obj.write(i, verts)
            if pc2 is not None:
                pc2.write(verts)
        if frames is not None:
            frames.finish(n)
        if out.gltf is not None:
            write_gltf(out.gltf, rig, track, force=out.force, end_time=end_time)
        if out.track is not None:
            from visemeface.speech.timeline import save_track

            save_track(track, out.track, force=out.force)
    if out.video is not None:
        from visemeface.analysis.video import MouthBox, write_sidecar

        try:
            MouthBox.of(mouth_box)
        except InputError:
            pass  # thumbnails too small to measure a mouth in: no sidecar
        else:
            write_sidecar(video_sidecar(out.video), mouth_box, fps=settings.fps,
                          size=(settings.size, settings.size), force=out.force)
    return {"frames": n, "kept": frames.kept if frames else 0,
            "rendered": (n - frames.kept) if (frames and need_image) else (n if need_image else 0)}
