"""Target vocabularies (ARKit, VRM, Oculus visemes) defined on our face as data.

Every target shape is a *recipe*: activations of the rig, written in
``data/retarget/*.csv`` as space-separated ``KEY=W`` terms, where ``KEY`` is

- a rig function (``zygomatic_major_left``, ``jaw``),
- a FACS action unit of ``data/retarget/action_units.csv`` (``AU12L``), itself a recipe of rig functions,
- ``viseme:SYM``, a DECtalk viseme of the posture tables (``viseme:aa``),
- ``emotion:NAME``, an expression of the posture tables (``emotion:happiness``),

and ``W`` a number (default 1; negative allowed, e.g. ``jaw=-0.1`` raises the jaw past rest). The terms add
up and are clamped to the rig's ranges. The shape's displacement is the rig's displacement at those
activations; a ``side`` of ``left``/``right`` keeps that half of it (a smooth split across the mouth's
centre line, so the two halves add up to the whole: the sided ARKit shapes of a function the rig does not
side, like the sphincter). An empty recipe is a shape the rig cannot make (eyelids, tongue): its weight is
always 0 and its morph target is zero.

The Oculus/Meta visemes are the means of the DECtalk visemes of each class of
``data/retarget/phoneme_classes.csv`` (the same table gives the Rhubarb mouth shapes).
"""

from __future__ import annotations

import csv
import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from visemeface.errors import InputError, close_matches
from visemeface.numeric import smoothstep
from visemeface.resources import data_path

#: The vocabularies :func:`vocabulary` builds (and the ``--gltf-shapes`` choices besides ``muscles``).
VOCABULARIES = ("arkit", "vrm", "oculus")
#: Oculus/Meta's 15 visemes, in the SDK's order.
OCULUS = ("sil", "PP", "FF", "TH", "DD", "kk", "CH", "SS", "nn", "RR", "aa", "E", "ih", "oh", "ou")
#: Half-width of the left/right split of a sided shape, in half mouth widths about the centre line.
SIDE_BLEND = 0.5


#: The columns each recipe table must have (``side`` is optional).
_COLUMNS = {"action_units.csv": ("au", "recipe"), "phoneme_classes.csv": ("dectalk", "oculus", "rhubarb")}


def _rows(name: str) -> tuple[Path, list[dict]]:
    """A recipe table's rows (every cell a stripped string), or :class:`InputError` naming the file."""
    path = data_path("retarget", name)
    need = _COLUMNS.get(name, ("name", "recipe", "note"))
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            missing = [c for c in need if c not in (reader.fieldnames or ())]
            if missing:
                raise InputError(f"the header row lacks the column {missing[0]!r}", path, 1)
            rows = [{k: (v or "").strip() for k, v in r.items() if isinstance(k, str) and not isinstance(v, list)}
                    for r in reader]
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"not a UTF-8 CSV table ({type(exc).__name__})", path) from None
    return path, rows


def parse_recipe(text: str, path: Path | None = None, line: int | None = None) -> list[tuple[str, float]]:
    """``"AU12L=1 jaw=-0.1 viseme:aa"`` -> ``[("AU12L", 1.0), ("jaw", -0.1), ("viseme:aa", 1.0)]``."""
    terms = []
    for term in (text or "").split():
        key, sep, value = term.partition("=")
        try:
            w = float(value) if sep else 1.0
        except ValueError:
            w = float("nan")
        if not key or not np.isfinite(w):
            raise InputError(f"bad recipe term {term!r}: expected KEY or KEY=NUMBER", path, line)
        terms.append((key, w))
    return terms


@functools.lru_cache(maxsize=1)
def action_units() -> dict[str, list[tuple[str, float]]]:
    """The action units of ``data/retarget/action_units.csv``: name -> terms of rig functions."""
    path, rows = _rows("action_units.csv")
    return {r["au"]: parse_recipe(r["recipe"], path, i + 2) for i, r in enumerate(rows)}


@functools.lru_cache(maxsize=1)
def phoneme_classes() -> dict[str, tuple[str, str]]:
    """DECtalk symbol -> (Oculus viseme, Rhubarb mouth shape), from ``phoneme_classes.csv``."""
    from visemeface.postures.phonemes import DECTALK

    path, rows = _rows("phoneme_classes.csv")
    table = {r["dectalk"]: (r["oculus"], r["rhubarb"]) for r in rows}
    missing = [s for s in DECTALK if s not in table]
    if missing or any(o not in OCULUS for o, _ in table.values()):
        raise InputError(f"phoneme classes must map every DECtalk symbol to an Oculus viseme (missing {missing})",
                         path)
    return table


class RecipeResolver:
    """Turns recipes into activation vectors (rig ``names`` order) on one rig."""

    def __init__(self, rig, library=None):
        self.rig = rig
        self._library = library

    @property
    def library(self):
        if self._library is None:
            from visemeface.postures.library import PostureLibrary

            self._library = PostureLibrary(self.rig)
        return self._library

    def _term(self, key: str, path, line) -> np.ndarray:
        rig = self.rig
        if key in rig.index:
            a = np.zeros(len(rig.names))
            a[rig.index[key]] = 1.0
            return a
        kind, _, name = key.partition(":")
        if kind == "viseme" and name in self.library.visemes.index:
            return self.library.visemes.loc[name].reindex(rig.names, fill_value=0.0).to_numpy(float)
        if kind == "emotion" and name in self.library.expressions.index:
            return self.library.expressions.loc[name].reindex(rig.names, fill_value=0.0).to_numpy(float)
        aus = action_units()
        if key in aus:
            return self.sum(aus[key], path, line)
        raise InputError(f"unknown recipe term {key!r}" + close_matches(key, list(aus) + list(rig.names)),
                         path, line)

    def sum(self, terms, path=None, line=None) -> np.ndarray:
        """Unclamped sum of the terms' activation vectors."""
        a = np.zeros(len(self.rig.names))
        for key, w in terms:
            a += w * self._term(key, path, line)
        return a

    def activations(self, terms, path=None, line=None) -> np.ndarray:
        """The recipe's activations, clamped to the rig's ranges (silently: recipes are data, checked by tests)."""
        lo, hi = self.rig.ranges[:, 0], self.rig.ranges[:, 1]
        return np.clip(self.sum(terms, path, line), lo, hi)


def side_weights(rig, side: str) -> np.ndarray:
    r"""Per-vertex weight (N,) of one side of the face: :math:`s_L(u) = \mathrm{smoothstep}((u + h) / 2h)`,
    ``u`` the mouth-frame x in half mouth widths (+ = the subject's left), ``h`` = :data:`SIDE_BLEND`;
    :math:`s_R = 1 - s_L`, so the halves of a shape add up to the shape."""
    frame = rig.frame
    u = frame.to_local(rig.face.vertices)[:, 0] / (frame.width / 2)
    left = smoothstep((u + SIDE_BLEND) / (2 * SIDE_BLEND))
    if side == "left":
        return left
    if side == "right":
        return 1.0 - left
    raise ValueError(f"side must be left or right, got {side!r}")


@dataclass
class Vocabulary:
    """A target vocabulary on one rig.

    Attributes
    ----------
    name : str
    names : list of str
        Shape names in the vocabulary's own order.
    shapes : (K, N, 3) float
        Each shape's displacement from rest (zero for a shape the rig cannot make).
    activations : (K, M+1) float
        The recipes' activations (rig ``names`` order; a sided shape: the whole recipe's).
    made : (K,) bool
        The shapes the rig can make (non-empty recipe); the others are never fitted.
    simplex : bool
        The weights are a partition of one (viseme vocabularies: exactly one viseme at rest is ``sil``).
    notes : list of str
    """

    name: str
    names: list
    shapes: np.ndarray
    activations: np.ndarray
    made: np.ndarray
    simplex: bool
    notes: list


def _displacement(rig, a: np.ndarray, side: str) -> np.ndarray:
    d = np.asarray(rig.displacement(a), dtype=np.float64)
    return d * side_weights(rig, side)[:, None] if side else d


def _table_vocabulary(name: str, rig, resolver: RecipeResolver) -> Vocabulary:
    path, rows = _rows(f"{name}.csv")
    k, m = len(rows), len(rig.names)
    shapes, acts = np.zeros((k, rig.face.n_vertices, 3)), np.zeros((k, m))
    made = np.zeros(k, bool)
    for i, r in enumerate(rows):
        terms = parse_recipe(r["recipe"], path, i + 2)
        if terms:
            acts[i] = resolver.activations(terms, path, i + 2)
            shapes[i] = _displacement(rig, acts[i], (r.get("side") or "").strip())
            made[i] = True
    return Vocabulary(name, [r["name"] for r in rows], shapes, acts, made, False, [r["note"] for r in rows])


def _oculus_vocabulary(rig, resolver: RecipeResolver) -> Vocabulary:
    classes = phoneme_classes()
    k = len(OCULUS)
    shapes, acts = np.zeros((k, rig.face.n_vertices, 3)), np.zeros((k, len(rig.names)))
    notes = []
    for i, vis in enumerate(OCULUS):
        members = [s for s, (o, _) in classes.items() if o == vis]
        acts[i] = np.mean([resolver.activations([(f"viseme:{s}", 1.0)]) for s in members], axis=0)
        shapes[i] = _displacement(rig, acts[i], "")
        notes.append("mean of DECtalk " + " ".join(members))
    return Vocabulary("oculus", list(OCULUS), shapes, acts, np.ones(k, bool), True, notes)


def vocabulary(name: str, rig, library=None) -> Vocabulary:
    """The vocabulary ``name`` (one of :data:`VOCABULARIES`) on ``rig``."""
    resolver = RecipeResolver(rig, library)
    if name == "oculus":
        return _oculus_vocabulary(rig, resolver)
    if name in ("arkit", "vrm"):
        return _table_vocabulary(name, rig, resolver)
    raise InputError(f"unknown vocabulary {name!r}{close_matches(name, VOCABULARIES)}")


def live_link_name(name: str) -> str:
    """ARKit's camelCase name -> Live Link Face's PascalCase column (``jawOpen`` -> ``JawOpen``)."""
    return name[:1].upper() + name[1:]
