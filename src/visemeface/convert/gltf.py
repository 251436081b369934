"""This project's own ``--gltf`` glb read back as a take: its morph-weight animation and target names.

A glb of ``--gltf-shapes arkit`` (``vrm``, ``oculus``) holds the vocabulary's shapes: a weights take. The
default (``muscles``) holds one target per muscle and sampled jaw openings ``jaw@<a>``: the muscles' weights
are their activations and the jaw's is :math:`\\sum_k w_k a_k` (the inverse of
:func:`visemeface.muscles.morphs.jaw_sample_weights`' hat weights). The held last key
(``extras.heldLastKey``) gives the end and is not a frame.
"""

from __future__ import annotations

import json
import struct

import numpy as np

from visemeface.errors import InputError

_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def read_glb(path):
    """(JSON document, accessor(i) -> float array) of a binary glTF; :class:`InputError` if it is none."""
    data = path.read_bytes()
    if len(data) < 20 or data[:4] != b"glTF":
        raise InputError("not a binary glTF (.glb)", path)
    (n_json,) = struct.unpack_from("<I", data, 12)
    try:
        doc = json.loads(data[20:20 + n_json])
        n_bin = struct.unpack_from("<I", data, 20 + n_json)[0]
    except (ValueError, struct.error):
        raise InputError("a damaged glb (its JSON or binary chunk)", path) from None
    blob = data[28 + n_json:28 + n_json + n_bin]

    def accessor(i):
        a = doc["accessors"][i]
        view = doc["bufferViews"][a["bufferView"]]
        if a.get("componentType") != 5126:
            raise InputError("an animation accessor that is not float", path)
        start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        n = a["count"] * _COMPONENTS[a["type"]]
        return np.frombuffer(blob, dtype="<f4", count=n, offset=start).astype(np.float64)

    return doc, accessor


def glb_take(path):
    from visemeface.convert.take import Take, weights_take
    from visemeface.track import make_track

    doc, accessor = read_glb(path)
    try:
        extras = doc["asset"].get("extras", {})
        names = list(doc["meshes"][0]["extras"]["targetNames"])
        sampler = doc["animations"][0]["samplers"][0]
        times, w = accessor(sampler["input"]), accessor(sampler["output"]).reshape(-1, len(names))
        fps = float(extras["fps"])
    except (KeyError, IndexError, TypeError, ValueError):
        raise InputError("not a visemeface glb: it needs a morph-weight animation, targetNames and asset.extras.fps",
                         path) from None
    end = float(times[-1])
    if extras.get("heldLastKey") and len(times) > 1:
        times, w = times[:-1], w[:-1]
    if extras.get("shapes", "muscles") != "muscles":
        take = weights_take(path, names, np.round(times * fps) / fps, w, "glb", fps=fps, end=end)
        take.shapes = "recipes"            # the glb's targets are our face's recipe shapes, its weights fit them
        return take
    jaw = [(k, float(n.split("@", 1)[1])) for k, n in enumerate(names) if n.startswith("jaw@")]
    muscles = [(k, n) for k, n in enumerate(names) if not n.startswith("jaw@")]
    columns = {n: w[:, k] for k, n in muscles}
    columns["jaw"] = sum(w[:, k] * a for k, a in jaw) if jaw else np.zeros(len(times))
    track = make_track(np.round(times * fps) / fps, columns, list(columns), fps)
    return Take("track", end, str(path), "glb", fps=fps, track=track)
