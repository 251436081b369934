"""Fuzz every reader of user files: it reads the file or refuses it with an InputError.

Each reader gets hypothesis-generated files (fixed seed, bounded count): valid
samples mutated at random places with the tokens that broke readers before
(``nan``, ``1e309``, negative and huge numbers, NUL and non-UTF-8 bytes,
truncation, duplicated lines), and plain random bytes. Anything other than a
result or an :class:`~visemeface.errors.InputError` is an untyped crash (a
traceback and exit 1 for the user) and fails the test. The number of cases
per reader is printed at the end of the run (``conftest.pytest_terminal_summary``).
"""

from __future__ import annotations

import io
import json
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from visemeface.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
_COUNTS: dict = {}


@pytest.fixture(autouse=True)
def _counts(fuzz_counts):
    """Count into the session's table (printed by conftest's terminal summary)."""
    global _COUNTS
    _COUNTS = fuzz_counts


def record_fuzz(reader: str, outcome: str) -> None:
    """Count one case of ``reader``: "read", "refused" (one-line InputError) or "crashed"."""
    counts = _COUNTS.setdefault(reader, {"read": 0, "refused": 0, "crashed": 0})
    counts[outcome] += 1

TOKENS = [b"nan", b"NaN", b"inf", b"-inf", b"1e309", b"-1", b"0", b"-0.0", b"1e-320", b"99999999999999999999",
          b"", b"\x00", b"\xff\xfe", b"\xe9", b"\n", b"\r\n", b",", b";", b"\t", b" ", b'"', b"[", b"]", b"{",
          b"}", b"=", b"#", b"<", b">", b"v", b"f", b"xmin", b"intervals", b"jaw", b"\xef\xbb\xbf"]

MUTATION = st.tuples(st.floats(0, 1), st.sampled_from(["insert", "replace", "delete", "truncate", "repeat"]),
                     st.sampled_from(TOKENS), st.integers(1, 12))
FUZZ = settings(max_examples=60, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def mutate(data: bytes, mutations) -> bytes:
    """Apply (where, what, token, length) edits to ``data``."""
    for where, what, token, n in mutations:
        i = int(where * len(data))
        if what == "insert":
            data = data[:i] + token + data[i:]
        elif what == "replace":
            data = data[:i] + token + data[i + n:]
        elif what == "delete":
            data = data[:i] + data[i + n:]
        elif what == "truncate":
            data = data[:i]
        else:                                   # repeat a stretch (duplicated lines, double headers)
            data = data[:i + n] + data[i:]
    return data


def shuffle_lines(data: bytes, picks) -> bytes:
    """Drop, duplicate or swap whole lines (mostly still well-formed files)."""
    lines = data.split(b"\n")
    for where, what in picks:
        i = int(where * (len(lines) - 1))
        if what == "drop":
            del lines[i]
        elif what == "duplicate":
            lines.insert(i, lines[i])
        else:
            lines[i], lines[-1 - i] = lines[-1 - i], lines[i]
        if not lines:
            break
    return b"\n".join(lines)


def fuzz_files(seed: bytes):
    """Files to try: the seed mutated 1-6 times, its lines shuffled, or random bytes."""
    lines = st.lists(st.tuples(st.floats(0, 1), st.sampled_from(["drop", "duplicate", "swap"])), min_size=1,
                     max_size=3)
    return st.one_of(st.lists(MUTATION, min_size=1, max_size=6).map(lambda m: mutate(seed, m)),
                     lines.map(lambda picks: shuffle_lines(seed, picks)), st.binary(max_size=300))


def check_reader(name, read, data: bytes, suffix: str):
    """``read(path)`` on a file holding ``data``: a result or an InputError, nothing else."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"input{suffix}"
        path.write_bytes(data)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")     # "not in the CMU dictionary", clamped values
                read(path)
        except InputError as exc:
            assert str(exc).strip() and "\n" not in str(exc), "an InputError is one line"
            record_fuzz(name, "refused")
            return
        except Exception:
            record_fuzz(name, "crashed")
            raise
    record_fuzz(name, "read")


# ---------------------------------------------------------------------------------------------- transcripts
TRANSCRIPTS = {     # format name (PARSERS, or None: detected) -> shipped sample
    "lab": "bob_moves_five_boats.lab", "phn": "bob_moves_five_boats.PHN", "timed": "bob_moves_five_boats.txt",
    "textgrid": "bob_moves_five_boats_short.TextGrid", "mfa-json": "bob_moves_five_boats.json",
    "mfa-csv": "bob_moves_five_boats.csv", "text": "bob_moves_five_boats_angry.txt",
    "dectalk": "bob_moves_five_boats_dectalk.txt",
}


@pytest.mark.parametrize("fmt", sorted(TRANSCRIPTS))
def test_transcript_readers(fmt):
    from visemeface.speech.transcripts import read_utterance

    sample = ROOT / "transcripts" / TRANSCRIPTS[fmt]
    fuzz(f"transcript ({fmt})", lambda p: read_utterance(p, fmt=fmt), sample.read_bytes(), sample.suffix)


# ---------------------------------------------------------------------------------------------- face files
@pytest.fixture(scope="module")
def small_face_files(tmp_path_factory):
    from visemeface.face.procedural import default_face

    folder = tmp_path_factory.mktemp("face")
    face = default_face(resolution=800)
    face.save(folder / "face.obj")
    return folder


def test_mesh_and_landmark_readers(small_face_files):
    from visemeface.face.mesh import load_face

    obj = (small_face_files / "face.obj").read_bytes()
    marks_path = next(small_face_files.glob("*.json"))
    marks = marks_path.read_bytes()

    fuzz("mesh (OBJ)", lambda p: load_face(p, marks_path), obj, ".obj")
    fuzz("landmarks (JSON)", lambda p: load_face(small_face_files / "face.obj", p), marks, ".json")


def test_rig_reader(default_face):
    from visemeface.muscles.rig import MuscleRig

    seed = (ROOT / "data" / "rig" / "default.toml").read_bytes()

    fuzz("rig (TOML)", lambda p: MuscleRig.from_file(default_face, p), seed, ".toml", 40)


@pytest.mark.parametrize("table", ["visemes", "expressions"])
def test_posture_table_readers(table, rig):
    from visemeface.postures import tables

    seed = (ROOT / "data" / ("visemes/visemes.csv" if table == "visemes" else "expressions/emotions.csv")).read_bytes()
    load = tables.load_visemes if table == "visemes" else tables.load_expressions

    fuzz(f"{table} table (CSV)", lambda p: load(p, rig=rig), seed, ".csv", 40)


# ---------------------------------------------------------------------------------------------- run files
def fuzz(name, read, seed: bytes, suffix: str, examples: int = 60):
    """Run ``read`` on ``examples`` generated files made from ``seed``."""
    @settings(FUZZ, max_examples=examples)
    @given(fuzz_files(seed))
    def run(data):
        check_reader(name, read, data, suffix)
    run()


TRACK = b"time,jaw,orbicularis_oris\n0,0,0\n0.0333333,0.2,0.1\n0.0666667,0.5,0.3\n"
PROFILE = b"time,count,area,width,height\n0,0,0,0,0\n0.04,1,0.01,0.2,0.05\n0.08,1,0.02,0.3,0.08\n"
SIDECAR = json.dumps({"mouth_box": [10, 20, 50, 30], "fps": 30, "size": [128, 128]}).encode()
GLUE = b"s,glue\n-1,0.08\n0,0.2\n1,0.08\n"


def test_track_profile_sidecar_and_glue_readers():
    from visemeface.analysis.profiles import read_profile
    from visemeface.physics.saliva import read_glue_file
    from visemeface.sidecars import read_video_sidecar
    from visemeface.track import load_track

    fuzz("activation track (CSV)", load_track, TRACK, ".csv")
    fuzz("opening profile (CSV)", read_profile, PROFILE, ".csv")
    fuzz("video sidecar (JSON)", read_video_sidecar, SIDECAR, ".json")
    fuzz("glue file (CSV)", lambda p: read_glue_file(p, np.linspace(-0.95, 0.95, 12)), GLUE, ".csv")


def test_checkpoint_reader():
    from visemeface.checkpoint import STATE, VERTICES, RunCheckpoint

    buf = io.BytesIO()
    np.savez(buf, _frames_done=np.array(2), _key=np.array("k"), u=np.zeros((4, 3)), t=np.array(0.1))
    seed = buf.getvalue()

    @settings(FUZZ, max_examples=40)
    @given(fuzz_files(seed))
    def run(data):
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp) / "out.mp4.checkpoint"
            folder.mkdir()
            (folder / VERTICES).write_bytes(np.zeros((2, 4, 3), "<f4").tobytes())
            (folder / STATE).write_bytes(data)      # the reader looks at folder/state.npz
            check_reader("checkpoint (state.npz)", lambda p: RunCheckpoint(folder, "k", 4, 30).load(), data, "")
    run()


def test_audio_reader():
    from visemeface.pipeline import check_audio
    import soundfile as sf

    buf = io.BytesIO()
    sf.write(buf, (0.1 * np.sin(np.linspace(0, 200, 1600))).astype(np.float32), 16000, format="WAV")
    fuzz("audio (WAV)", check_audio, buf.getvalue(), ".wav", 40)


VALUES = st.one_of(st.integers(-2**70, 2**70), st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=5),
                   st.lists(st.floats(-1e3, 1e3), max_size=4), st.booleans())


def test_checkpoint_reader_well_formed_npz():
    """Readable archives with wrong contents: missing keys, wrong types, NaN, huge counts."""
    from visemeface.checkpoint import STATE, VERTICES, RunCheckpoint

    @settings(FUZZ, max_examples=60)
    @given(st.dictionaries(st.sampled_from(["_frames_done", "_key", "u", "t", "saliva"]), VALUES, max_size=5),
           st.booleans())
    def run(entries, over_valid):
        if over_valid:                               # a valid archive with some entries replaced
            entries = {"_frames_done": 2, "_key": "k", **entries}
        buf = io.BytesIO()
        np.savez(buf, **{k: np.asarray(v) for k, v in entries.items()})
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp) / "out.mp4.checkpoint"
            folder.mkdir()
            (folder / VERTICES).write_bytes(np.zeros((2, 4, 3), "<f4").tobytes())
            (folder / STATE).write_bytes(buf.getvalue())
            check_reader("checkpoint (well-formed npz)", lambda p: RunCheckpoint(folder, "k", 4, 30).load(),
                         b"", "")
    run()


# ---------------------------------------------------------------------------------------------- batch files
MANIFEST = (b"clip,transcript,text,audio,emotion,physics,fps,size,view,msaa,interp,rate,outputs\n"
            b"c1,t.txt,,,happiness=0.6; surprise=0.2,none,30,64,mouth,0,coarticulation,,video gltf\n"
            b"c2,,one five,,,,25,,,,,150,track\n"
            b"c3,,bob moves,a.wav,anger,,,,face,,,,obj\n")


def test_batch_manifest_reader(tmp_path, vowels_wav):
    import shutil

    from visemeface.batch.manifest import read_manifest

    (tmp_path / "t.txt").write_text("0.00 0.05 _\n0.05 0.25 aa\n0.25 0.30 _\n")
    shutil.copy(vowels_wav, tmp_path / "a.wav")

    def read(p):
        moved = tmp_path / p.name
        shutil.copy(p, moved)                   # beside the files its rows name
        try:
            rows = read_manifest(moved, {"size": 64})
        finally:
            moved.unlink()
        for row in rows:                        # a bad row's reason is one line too
            assert "\n" not in getattr(row, "error", ""), row
    fuzz("batch manifest (CSV)", read, MANIFEST, ".csv", 80)


def test_batch_clip_record_reader(tmp_path):
    from visemeface.batch.clip import CLIP_RECORD, clip_state
    from visemeface.batch.manifest import Job

    job = Job(clip="c1", text="one")
    seed = json.dumps({"settings": job.settings(), "seconds": 1.5}).encode()

    def read(p):                                # clip_state on --resume: "done", "other" or "missing", no crash
        (tmp_path / "c1").mkdir(exist_ok=True)
        (tmp_path / "c1" / CLIP_RECORD).write_bytes(p.read_bytes())
        assert clip_state(job, tmp_path) in ("done", "other")
    fuzz("batch clip record (JSON)", read, seed, ".json", 40)


# ---------------------------------------------------------------------------------------------- recordings
def _mp3_bytes(wav: Path) -> bytes:
    import subprocess

    import imageio_ffmpeg

    return subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(wav), "-t", "0.4",
                           "-f", "mp3", "-"], capture_output=True, check=True).stdout


@pytest.mark.parametrize("kind", ["wav", "mp3"])
def test_recording_reader(kind, vowels_wav):
    import soundfile as sf

    from visemeface.speech.audio import read_audio

    if kind == "wav":
        buf = io.BytesIO()
        x, rate = sf.read(str(vowels_wav), frames=4000)
        sf.write(buf, x, rate, format="WAV", subtype="PCM_16")
        seed = buf.getvalue()
    else:
        seed = _mp3_bytes(vowels_wav)

    def read(p):
        samples, rate = read_audio(p)
        assert samples.size and rate > 0 and np.all(np.isfinite(samples))
    fuzz(f"recording ({kind.upper()})", read, seed, f".{kind}", 40)


# ---------------------------------------------------------------------------------------------- preview, retarget
def test_preview_glb_reader(tmp_path):
    from visemeface.export.gltf import write_morph_animation_glb
    from visemeface.export.preview import glb_duration

    tri = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    write_morph_animation_glb(tmp_path / "a.glb", tri, [[0, 1, 2]], tri[None] * 0.1, ["m"], [0.0, 1.0],
                              [[0.0], [1.0]])
    seed = (tmp_path / "a.glb").read_bytes()

    def read(p):
        d = glb_duration(p.read_bytes())
        assert np.isfinite(d) and d >= 0
    fuzz("preview glb (glTF)", read, seed, ".glb", 60)


@pytest.mark.parametrize("table", ["arkit.csv", "vrm.csv", "action_units.csv", "phoneme_classes.csv"])
def test_retarget_data_readers(table, rig, monkeypatch, tmp_path):
    """The recipe tables of data/retarget/ (edited by hand to add a shape): read, or refused with the line."""
    from visemeface.resources import data_path
    from visemeface.retarget import recipes

    seed = data_path("retarget", table).read_bytes()
    real = recipes.data_path

    def read(p):
        monkeypatch.setattr(recipes, "data_path", lambda *parts: p if parts[-1] == table else real(*parts))
        recipes.action_units.cache_clear()
        recipes.phoneme_classes.cache_clear()
        try:
            name = {"arkit.csv": "arkit", "vrm.csv": "vrm", "phoneme_classes.csv": "oculus"}.get(table, "arkit")
            recipes.vocabulary(name, rig)
            if table == "phoneme_classes.csv":
                recipes.phoneme_classes()
        finally:
            recipes.action_units.cache_clear()
            recipes.phoneme_classes.cache_clear()
    fuzz(f"retarget {table}", read, seed, ".csv", 25)


# ---------------------------------------------------------------------------------------------- well-formed, hostile
JSON_VALUES = st.recursive(st.none() | st.booleans() | st.integers(-2**70, 2**70) | st.floats() | st.text(max_size=6),
                           lambda inner: st.lists(inner, max_size=3) | st.dictionaries(
                               st.sampled_from(["settings", "accessors", "animations", "samplers", "input", "max",
                                                "clip", "x"]), inner, max_size=4), max_leaves=12)


def test_well_formed_json_with_any_contents(tmp_path):
    """Readable JSON of any shape where the readers expect an object: a clip record, a glb's JSON chunk."""
    import struct

    from visemeface.batch.clip import CLIP_RECORD, clip_state
    from visemeface.batch.manifest import Job
    from visemeface.export.preview import glb_duration

    job = Job(clip="c1", text="one")
    (tmp_path / "c1").mkdir()

    def record(p):
        (tmp_path / "c1" / CLIP_RECORD).write_bytes(p.read_bytes())
        assert clip_state(job, tmp_path) == "other"

    def glb(p):
        doc = p.read_bytes()
        glb_duration(b"glTF" + struct.pack("<II", 2, 20 + len(doc)) + struct.pack("<I4s", len(doc), b"JSON") + doc)

    @settings(FUZZ, max_examples=60)
    @given(JSON_VALUES)
    def run(value):
        data = json.dumps(value).encode()
        check_reader("batch clip record (any JSON)", record, data, ".json")
        check_reader("preview glb (any JSON chunk)", glb, data, ".json")
    run()


CELLS = st.sampled_from(["", "nan", "inf", "-1", "0", "1e309", "99999999999999999999", "t.txt", "../t.txt", "/",
                         "happiness=nan", "happiness=2", "happiness", "zz=0.5", "video", "video gltf", "obj;pc2",
                         "none", "sticky", "face", "mouth", "linear", "a b", "\x00", "é", '"', "c1"])


def test_batch_manifest_rows_with_hostile_cells(tmp_path):
    """A well-formed manifest whose cells are the values that break readers: each row is a Job or a one-line
    BadRow, and the manifest is never refused whole for a bad cell."""
    import csv

    from visemeface.batch.manifest import COLUMNS, BadRow, Job, read_manifest

    (tmp_path / "t.txt").write_text("0.00 0.05 _\n0.05 0.25 aa\n0.25 0.30 _\n")

    @settings(FUZZ, max_examples=80)
    @given(st.lists(st.fixed_dictionaries({c: CELLS for c in COLUMNS}), min_size=1, max_size=4))
    def run(rows):
        path = tmp_path / "m.csv"
        with open(path, "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=COLUMNS)
            w.writeheader()
            w.writerows(rows)

        def read(p):
            out = read_manifest(path, {"size": 64})
            assert len(out) == sum(any(r.values()) for r in rows)
            assert all(isinstance(r, Job) or (isinstance(r, BadRow) and "\n" not in r.error) for r in out)
        check_reader("batch manifest (hostile cells)", read, b"", ".csv")
    run()


HOSTILE_VALUES = st.one_of(
    st.integers(-10**30, 10**30), st.sampled_from([1e308, -1e308, 99999999999999999999, -1, 2**63, 0.5]),
    st.floats(), st.lists(st.integers(-10**25, 10**25), max_size=5), st.lists(st.floats(), max_size=4),
    st.lists(st.lists(st.integers(-10**22, 10**22), max_size=5), max_size=3), JSON_VALUES)


def test_landmark_files_with_hostile_values(small_face_files):
    """Well-formed landmarks files whose entries (a landmark, a region, a quad, the vertex count) hold hostile
    values: 20-digit indices (OverflowError before), coordinates at 1e308, NaN, nested lists, any JSON."""
    import copy

    from visemeface.face.mesh import load_face

    marks_path = next(small_face_files.glob("*.json"))
    base = json.loads(marks_path.read_text())

    @settings(FUZZ, max_examples=150)
    @given(st.sampled_from(["landmarks", "regions", "quads", "n_vertices"]), st.integers(0, 200), HOSTILE_VALUES)
    def run(section, k, value):
        data = copy.deepcopy(base)
        if section in ("landmarks", "regions"):
            names = sorted(data[section])
            data[section][names[k % len(names)]] = value
        elif section == "quads":
            data["quads"][k % len(data["quads"])] = value
        else:
            data[section] = value
        check_reader("landmarks (hostile values)", lambda p: load_face(small_face_files / "face.obj", p),
                     json.dumps(data).encode(), ".json")
    run()


def test_every_number_option_refuses_hostile_text():
    """Every option parsed by the number helper: any text is a value in its range or one InputError line
    naming the option (never a traceback, never a 309-digit echo)."""
    from visemeface.cli import build_parser
    from visemeface.commands._options import check_number

    options = []
    for name, parser in build_parser()._subparsers._group_actions[0].choices.items():
        for action in parser._actions:
            t = action.type
            if getattr(t, "__name__", None) in ("number", "integer"):
                options.append((f"{name} {action.option_strings[-1]}", t))
    assert len(options) >= 15, options
    texts = st.one_of(st.text(max_size=12), st.floats().map(repr), st.integers(-10**400, 10**400).map(str),
                      st.sampled_from(["1e308", "-1e308", "1e-308", "nan", "inf", "-inf", "0x10", "1_000", " 5 "]))

    @settings(FUZZ, max_examples=120)
    @given(st.sampled_from(options), texts)
    def run(option, text):
        name, t = option
        kw = dict(integer=t.__name__ == "integer", infinite=t.infinite)
        try:
            value = check_number(text, name.split()[-1], t.low, t.high, **kw)
        except InputError as exc:
            msg = str(exc)
            assert msg.startswith(name.split()[-1] + " must be ") and "\n" not in msg and len(msg) < 140, msg
            record_fuzz("number options", "refused")
            return
        assert value == value and (t.low is None or value >= t.low) and (t.high is None or value <= t.high
                                                                           or value == float("inf"))
        record_fuzz("number options", "read")
    run()
