"""Exports: PC2, OBJ and PNG sequences, MP4 (+ audio sync), glTF morph animation."""

import json
import struct

import numpy as np
import pytest
import soundfile as sf
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from visemeface.errors import InputError
from visemeface.render import export


def grid_mesh(nx=6, ny=5, size=0.05):
    """A flat quad grid in the z=0 plane, CCW seen from +z, split into triangles."""
    xs, ys = np.meshgrid(np.linspace(-size / 2, size / 2, nx), np.linspace(-size / 3, size / 3, ny))
    v = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)])
    quads = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a = j * nx + i
            quads.append([a, a + 1, a + nx + 1, a + nx])
    quads = np.array(quads)
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return v, quads, tris


def test_frame_names_sort_and_pad():
    names = [export.frame_name(i) for i in (0, 9, 10, 123456)]
    assert names == ["frame_000000.png", "frame_000009.png", "frame_000010.png", "frame_123456.png"]
    assert sorted(names) == names
    with pytest.raises(ValueError):
        export.frame_name(10**6)


# ----------------------------------------------------------------------------- PC2

def test_pc2_round_trip_streamed(tmp_path):
    rng = np.random.default_rng(0)
    frames = rng.normal(size=(7, 11, 3)).astype(np.float32)
    path = tmp_path / "a.pc2"
    with export.Pc2Writer(path, 11, start_frame=1.0, sample_rate=1.0) as pc2:
        for f in frames:
            pc2.write(f)
    raw = path.read_bytes()
    assert raw[:12] == b"POINTCACHE2\0"
    assert struct.unpack("<iiffi", raw[12:32]) == (1, 11, 1.0, 1.0, 7)
    assert len(raw) == 32 + 7 * 11 * 12
    pts, head = export.read_pc2(path)
    assert head == {"version": 1, "num_points": 11, "start_frame": 1.0, "sample_rate": 1.0,
                    "num_samples": 7}
    np.testing.assert_array_equal(pts, frames)


def test_pc2_float64_input_is_stored_as_float32(tmp_path):
    frames = np.linspace(0, 1, 2 * 4 * 3).reshape(2, 4, 3)
    export.write_pc2(tmp_path / "b.pc2", frames)
    pts, _ = export.read_pc2(tmp_path / "b.pc2")
    np.testing.assert_allclose(pts, frames, rtol=1e-7)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(arrays(np.float32, st.tuples(st.integers(1, 4), st.integers(1, 6), st.just(3)),
              elements=st.floats(-1e6, 1e6, width=32)),
       st.floats(-100, 100, width=32), st.floats(0.125, 10, width=32))
def test_pc2_round_trip_property(tmp_path, frames, start, rate):
    path = tmp_path / "p.pc2"
    export.write_pc2(path, frames, start_frame=start, sample_rate=rate, force=True)
    pts, head = export.read_pc2(path)
    np.testing.assert_array_equal(pts, frames)
    assert (head["start_frame"], head["sample_rate"]) == (start, rate)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.binary(max_size=80), st.booleans())
def test_read_pc2_never_crashes(tmp_path, data, magic):
    path = tmp_path / "r.pc2"
    path.write_bytes((export.PC2_MAGIC if magic else b"") + data)
    try:
        pts, head = export.read_pc2(path)
    except InputError:
        return
    assert pts.shape == (head["num_samples"], head["num_points"], 3)


def test_pc2_rejects_bad_files(tmp_path):
    bad = tmp_path / "bad.pc2"
    bad.write_bytes(b"NOTACACHE123" + bytes(20))
    with pytest.raises(InputError, match="POINTCACHE2"):
        export.read_pc2(bad)
    export.write_pc2(tmp_path / "t.pc2", np.zeros((3, 5, 3)))
    data = (tmp_path / "t.pc2").read_bytes()
    (tmp_path / "t.pc2").write_bytes(data[:-4])  # truncated
    with pytest.raises(InputError, match="does not match header"):
        export.read_pc2(tmp_path / "t.pc2")


def test_pc2_error_midway_leaves_nothing(tmp_path):
    with pytest.raises(ValueError):
        with export.Pc2Writer(tmp_path / "c.pc2", 4) as pc2:
            pc2.write(np.zeros((4, 3)))
            pc2.write(np.zeros((5, 3)))  # wrong vertex count
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- OBJ / PNG

def test_obj_sequence_shares_topology_and_round_trips(tmp_path):
    import trimesh

    v, quads, tris = grid_mesh()
    folder = tmp_path / "obj"
    moved = [v + [0, 0, 0.001 * i] for i in range(3)]
    with export.ObjSequenceWriter(folder, tris) as seq:
        for i, m in enumerate(moved):
            seq.write(i, m)
    files = sorted(folder.iterdir())
    assert [f.name for f in files] == [export.frame_name(i, "obj") for i in range(3)]
    face_lines = [[ln for ln in f.read_text().splitlines() if ln.startswith("f ")] for f in files]
    assert face_lines[0] == face_lines[1] == face_lines[2] and len(face_lines[0]) == len(tris)
    for f, m in zip(files, moved):
        mesh = trimesh.load(f, process=False)
        np.testing.assert_allclose(mesh.vertices, m, atol=1e-6)
        np.testing.assert_array_equal(mesh.faces, tris)


def test_obj_quads_are_one_based():
    text = export.obj_faces_text(np.array([[0, 1, 2, 3]]))
    assert text == "f 1 2 3 4\n"


def test_png_sequence_names_pixels_and_determinism(tmp_path):
    rng = np.random.default_rng(1)
    imgs = [rng.integers(0, 256, size=(16, 32, 3), dtype=np.uint8) for _ in range(3)]
    with export.PngSequenceWriter(tmp_path / "frames") as seq:
        for i, im in enumerate(imgs):
            seq.write(i, im)
    names = sorted(p.name for p in (tmp_path / "frames").iterdir())
    assert names == ["frame_000000.png", "frame_000001.png", "frame_000002.png"]
    for i, im in enumerate(imgs):
        np.testing.assert_array_equal(export.read_png(tmp_path / "frames" / names[i]), im)
    assert export.encode_png(imgs[0]) == export.encode_png(imgs[0].copy())
    # nothing is left of a failed sequence
    with pytest.raises(RuntimeError):
        with export.PngSequenceWriter(tmp_path / "frames2") as seq:
            seq.write(0, imgs[0])
            raise RuntimeError("interrupted")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frames"]


def test_read_png_unreadable(tmp_path):
    (tmp_path / "x.png").write_bytes(b"garbage")
    with pytest.raises(InputError, match="x.png"):
        export.read_png(tmp_path / "x.png")


# ----------------------------------------------------------------------------- MP4

def _grey_frames(n, w=64, h=48):
    for i in range(n):
        yield np.full((h, w, 3), (i * 8) % 256, np.uint8)


def test_mp4_frame_count_duration_and_order(tmp_path):
    import imageio_ffmpeg

    path = tmp_path / "v.mp4"
    with export.VideoWriter(path, (64, 48), fps=25) as video:
        for f in _grey_frames(20):
            video.write(f)
    info = export.read_video_info(path)
    assert info["n_frames"] == 20 and info["size"] == (64, 48)
    assert info["fps"] == pytest.approx(25)
    assert info["duration"] == pytest.approx(20 / 25, abs=1e-3)
    assert info["audio_samples"] == 0
    gen = imageio_ffmpeg.read_frames(str(path))
    next(gen)
    means = [np.frombuffer(b, np.uint8).mean() for b in gen]
    np.testing.assert_allclose(means, [(i * 8) % 256 for i in range(20)], atol=3)


@pytest.mark.parametrize("audio_s", [1.3, 0.6])  # longer and shorter than the video
def test_mp4_audio_in_sync(tmp_path, audio_s):
    sr = 16000
    sound = np.zeros(int(audio_s * sr), np.float32)
    onset = 0.4
    sound[int(onset * sr):int((onset + 0.1) * sr)] = 0.5 * np.sin(
        2 * np.pi * 440 * np.arange(int(0.1 * sr)) / sr)
    sf.write(tmp_path / "a.wav", sound, sr)
    path = tmp_path / "v.mp4"
    with export.VideoWriter(path, (64, 48), fps=30, audio=tmp_path / "a.wav", n_frames=30) as video:
        for f in _grey_frames(30):
            video.write(f)
    info = export.read_video_info(path)
    assert info["n_frames"] == 30
    assert info["audio_rate"] > 0
    assert info["audio_samples"] / info["audio_rate"] == pytest.approx(1.0, abs=2e-3)
    audio, rate = export.read_video_audio(path)
    start = np.argmax(np.abs(audio) > 0.05) / rate
    assert start == pytest.approx(onset, abs=3e-3)  # audio starts at t = 0, no priming offset


def test_mp4_error_leaves_no_file_and_refuses_overwrite(tmp_path):
    path = tmp_path / "v.mp4"
    with pytest.raises(ValueError):
        with export.VideoWriter(path, (64, 48), fps=30) as video:
            video.write(np.zeros((48, 64, 3), np.uint8))
            video.write(np.zeros((10, 10, 3), np.uint8))
    assert list(tmp_path.iterdir()) == []
    path.write_bytes(b"user")
    with pytest.raises(InputError, match="exists"):
        with export.VideoWriter(path, (64, 48), fps=30):
            pass
    assert path.read_bytes() == b"user"
    with pytest.raises(InputError, match="even"):
        export.VideoWriter(tmp_path / "w.mp4", (63, 48), fps=30)


# ----------------------------------------------------------------------------- glTF

def test_vertex_normals_plane_and_sphere():
    import trimesh

    from visemeface.face.normals import vertex_normals

    v, _, tris = grid_mesh()
    np.testing.assert_allclose(vertex_normals(v, tris), np.tile([0, 0, 1.0], (len(v), 1)))
    # glTF needs unit normals everywhere: a vertex in no triangle gets +z
    isolated = np.vstack([v, [[5.0, 5.0, 5.0]]])
    np.testing.assert_allclose(export.unit_normals(vertex_normals(isolated, tris))[-1], [0, 0, 1.0])
    s = trimesh.creation.icosphere(subdivisions=3, radius=2.0)
    n = vertex_normals(s.vertices, s.faces)
    radial = s.vertices / np.linalg.norm(s.vertices, axis=1, keepdims=True)
    assert np.min(np.sum(n * radial, axis=1)) > 0.99


def test_jaw_sample_weights_exact_at_samples_and_bounded_by_chord():
    samples = np.linspace(0.125, 1.0, 8)
    w = export.jaw_sample_weights(samples, samples)
    np.testing.assert_allclose(w, np.eye(8), atol=1e-12)
    np.testing.assert_allclose(export.jaw_sample_weights([0.0], samples), 0.0)
    # a rotation by a * theta_max about the origin of a point at radius r
    r, theta_max = 0.1, 0.35
    a = np.linspace(0, 1, 401)

    def motion(a):
        th = np.asarray(a) * theta_max
        return np.column_stack([r * np.sin(th), r * np.cos(th) - r])

    wa = export.jaw_sample_weights(a, samples)
    approx = wa @ motion(samples)
    err = np.linalg.norm(approx - motion(a), axis=1)
    sag = r * (1 - np.cos(theta_max * 0.125 / 2))  # chord sag of one sample interval
    assert err.max() <= sag * 1.0001
    assert err.max() > 0.5 * sag  # it is a chord, not exact: the bound is tight
    # a motion linear in a is reproduced exactly
    np.testing.assert_allclose(wa @ (samples[:, None] * [1.0, 2.0]), a[:, None] * [1.0, 2.0],
                               atol=1e-12)


def test_jaw_sample_weights_negative_side():
    samples = np.array([-0.1, -0.05, 0.5, 1.0])
    w = export.jaw_sample_weights([-0.1, -0.075, 0.0, 0.25, 1.0], samples)
    np.testing.assert_allclose(w, [[1, 0, 0, 0], [0.5, 0.5, 0, 0], [0, 0, 0, 0],
                                   [0, 0, 0.5, 0], [0, 0, 0, 1]], atol=1e-12)
    with pytest.raises(ValueError):
        export.jaw_sample_weights([0.1], [0.0, 0.5])


def _accessor_array(gl, blob, idx):
    acc = gl.accessors[idx]
    view = gl.bufferViews[acc.bufferView]
    dtype = {5126: "<f4", 5123: "<u2", 5125: "<u4"}[acc.componentType]
    ncomp = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[acc.type]
    start = view.byteOffset + (acc.byteOffset or 0)
    arr = np.frombuffer(blob, dtype=dtype, count=acc.count * ncomp, offset=start)
    return arr.reshape(acc.count, ncomp) if ncomp > 1 else arr


def test_glb_structure_and_animation_round_trip(tmp_path):
    import pygltflib
    import trimesh

    v, _, tris = grid_mesh()
    rng = np.random.default_rng(2)
    k, f = 5, 9
    targets = rng.normal(scale=1e-3, size=(k, len(v), 3))
    names = [f"m{i}" for i in range(k)]
    times = np.arange(f) / 30.0
    weights = rng.uniform(0, 1, size=(f, k))
    colors = rng.uniform(0, 1, size=(len(v), 3))
    path = tmp_path / "face.glb"
    export.write_morph_animation_glb(path, v, tris, targets, names, times, weights, colors=colors)

    raw = path.read_bytes()
    magic, version, length = struct.unpack("<4sII", raw[:12])
    assert (magic, version, length) == (b"glTF", 2, len(raw)) and length % 4 == 0

    gl = pygltflib.GLTF2().load(str(path))
    blob = gl.binary_blob()
    assert gl.buffers[0].byteLength <= len(blob)
    assert all(bv.byteOffset % 4 == 0 for bv in gl.bufferViews)
    assert all(bv.byteOffset + bv.byteLength <= gl.buffers[0].byteLength for bv in gl.bufferViews)
    assert all(a.min is not None and a.max is not None for a in gl.accessors)
    prim = gl.meshes[0].primitives[0]
    assert len(prim.targets) == k
    assert gl.meshes[0].extras["targetNames"] == names
    sampler = gl.animations[0].samplers[0]
    assert sampler.interpolation == "LINEAR"
    assert gl.accessors[sampler.input].max[0] == pytest.approx(times[-1])
    assert gl.accessors[sampler.output].count == f * k
    assert gl.animations[0].channels[0].target.path == "weights"

    # decode and rebuild the pose at keyframe 4: X + sum_k w_k T_k
    pos = _accessor_array(gl, blob, prim.attributes.POSITION)
    tgt = np.stack([_accessor_array(gl, blob, t["POSITION"] if isinstance(t, dict) else t.POSITION)
                    for t in prim.targets])
    w_out = _accessor_array(gl, blob, sampler.output).reshape(f, k)
    posed = pos + np.tensordot(w_out[4], tgt, axes=1)
    np.testing.assert_allclose(posed, v + np.tensordot(weights[4], targets, axes=1), atol=1e-6)
    idx = _accessor_array(gl, blob, prim.indices).reshape(-1, 3)
    np.testing.assert_array_equal(idx, tris)
    normals = _accessor_array(gl, blob, prim.attributes.NORMAL)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-6)

    mesh = trimesh.load(path, force="mesh", process=False)
    np.testing.assert_allclose(mesh.vertices, v, atol=1e-7)
    assert len(mesh.faces) == len(tris)
    assert json.loads(raw[20:20 + struct.unpack("<I", raw[12:16])[0]])["asset"]["version"] == "2.0"


def test_glb_validation_errors(tmp_path):
    v, _, tris = grid_mesh()
    with pytest.raises(ValueError, match="increasing"):
        export.write_morph_animation_glb(tmp_path / "a.glb", v, tris, np.zeros((1, len(v), 3)), ["a"],
                                         [0.0, 0.0], np.zeros((2, 1)))
    with pytest.raises(ValueError, match="weights"):
        export.write_morph_animation_glb(tmp_path / "a.glb", v, tris, np.zeros((1, len(v), 3)), ["a"],
                                         [0.0, 0.1], np.zeros((3, 1)))
    assert list(tmp_path.iterdir()) == []


def test_a_video_stopped_before_its_first_frame_says_nothing_and_leaves_nothing(tmp_path):
    """Ctrl-C as a run opened its video: imageio-ffmpeg logged "No frames have been written; the written video
    is invalid." on stderr beside our one line (in a process of its own: pytest captures logging)."""
    import subprocess
    import sys

    code = ("from visemeface.export.video import VideoWriter\ntry:\n"
            "    with VideoWriter('v.mp4', (32, 32), fps=30):\n        raise KeyboardInterrupt\n"
            "except KeyboardInterrupt:\n    print('stopped')\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, check=True)
    assert out.stdout == "stopped\n" and out.stderr == "", out.stderr
    assert list(tmp_path.iterdir()) == []
