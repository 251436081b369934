"""Glue strength per saliva element: uniform, a profile across the mouth, or a CSV file.

Positions across the mouth are s = −1 at the subject's right corner, 0 at the
centre, +1 at the left corner (:attr:`visemeface.physics.face_model.FEMFace.saliva_s`).
"""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np

from visemeface.errors import InputError

#: Leach & Maddock (2018, 2019) Table 1: the uniform glue and Leach & Maddock's (2019) central element's glue.
GLUE = 0.08
CENTRAL_GLUE = 0.18
#: Half-width in s of the ``centre`` a glue profile names: the mouth's central twelfth (|s| ≤ 1/12).
#: Leach & Maddock (2019) glue "one of the central elements" of their face; the seed-scale face (the default face,
#: 12 saliva elements across) has elements 1/12 of the mouth wide. Named by width, not by element, so
#: the stuck patch is the same size on a refined face or a film finer than the face (48 slabs: the
#: two slabs nearest the centre are 1/24 of the mouth, a patch half the seed's).
CENTRAL_HALF_WIDTH = 1.0 / 12.0
#: Strongest glue taken (option, profile item or file value): 125 times Leach & Maddock's (2018) 0.08. The film's stable
#: time step shrinks as 1/sqrt(glue), so at 10 it is 11 times the default's; 1e308 made it 0 and the run
#: failed with "time step must be a positive number, got 0.0", naming no option.
MAX_GLUE = 10.0

_ITEM = re.compile(r"^\s*([A-Za-z_]+|[-+]?\d*\.?\d+\s*\.\.\s*[-+]?\d*\.?\d+)\s*=\s*([^=]+?)\s*$")
_NAMED = ("centre", "center", "left", "right", "corners", "all")


def _positive_glue(text: str, spec: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise InputError(f"glue profile {spec!r}: {text!r} is not a number") from None
    if not np.isfinite(v) or not 0 <= v <= MAX_GLUE:
        raise InputError(f"glue profile {spec!r}: glue must be from 0 to {MAX_GLUE:g}, got {text.strip()[:24]}")
    return v


def parse_glue_profile(spec: str, s, base: float = GLUE) -> np.ndarray:
    """Glue strength per saliva element from a profile across the mouth.

    Parameters
    ----------
    spec : str
        Comma-separated ``WHERE=VALUE`` items applied left to right over
        ``base``. WHERE is ``all``; ``centre`` (the elements in the mouth's
        central twelfth, |s| ≤ :data:`CENTRAL_HALF_WIDTH`: Leach & Maddock's (2019) "central
        element"; the one(s) nearest the centre, ties included, if none is);
        ``left`` / ``right`` (the subject's left, s > 0 / right, s < 0);
        ``corners`` (|s| ≥ 0.7); or a range ``a..b`` of s. A bare number sets
        ``all``. Example: ``"centre=0.18"``, ``"left=0.2,-0.1..0.1=0"``.
    s : (E,) array
        Element-centre positions across the mouth, −1 at the right corner,
        0 at the centre, +1 at the left corner.
    base : float
        Glue of elements no item names.

    Raises
    ------
    InputError
        Unparseable item, negative value, or an item naming no element.

    Examples
    --------
    >>> parse_glue_profile("centre=0.18", np.array([-0.5, -0.1, 0.2, 0.6]))
    array([0.08, 0.18, 0.08, 0.08])
    """
    s = np.asarray(s, dtype=np.float64)
    glue = np.full(len(s), float(base))
    spec = str(spec).strip()
    if not spec:
        raise InputError("empty glue profile")
    for item in spec.split(","):
        try:
            glue[:] = _positive_glue(item, spec)
            continue
        except InputError:
            pass
        m = _ITEM.match(item)
        if not m:
            raise InputError(f"glue profile {spec!r}: cannot read {item.strip()!r} "
                             "(expected WHERE=VALUE, WHERE one of centre, left, right, corners, all, a..b)")
        where, value = m.group(1).strip().lower(), _positive_glue(m.group(2), spec)
        if ".." in where:
            a, b = sorted(float(x) for x in where.split(".."))
            sel = (s >= a) & (s <= b)
        elif where in ("centre", "center"):
            d = np.abs(s)
            sel = d <= max(CENTRAL_HALF_WIDTH, d.min()) + 1e-9 if len(s) else np.zeros(0, bool)
        elif where == "left":
            sel = s > 0
        elif where == "right":
            sel = s < 0
        elif where == "corners":
            sel = np.abs(s) >= 0.7
        elif where == "all":
            sel = np.ones(len(s), bool)
        else:
            from visemeface.errors import close_matches
            raise InputError(f"glue profile {spec!r}: unknown place {where!r}" + close_matches(where, _NAMED))
        if not sel.any():
            raise InputError(f"glue profile {spec!r}: {item.strip()!r} names no saliva element "
                             f"(elements span s = {s.min():.2f}..{s.max():.2f})")
        glue[sel] = value
    return glue


def check_glue_sources(profile: str | None = None, path: str | Path | None = None) -> None:
    """Refuse a glue profile or file that cannot be read, or whose values are out of range, before any face
    is built (which places of the mouth the items name is checked on the face, by :func:`glue_per_element`)."""
    across = np.linspace(-1.0, 1.0, 2001)                 # every place an item can name, finely
    if profile:
        parse_glue_profile(profile, across)
    if path is not None:
        read_glue_file(path, across, check_elements=False)


def read_glue_file(path, s, check_elements: bool = True) -> np.ndarray:
    """Glue per saliva element from a CSV file.

    Two layouts (header line required):

    * ``element,glue``: one row per element index (0-based, in order across
      the mouth from the subject's right corner: element k is the one with the
      k-th smallest ``s``); every element must be given. With the film carried
      into the mouth corners (the speech lips) its wedges count too, first and
      last (50 elements on the default face).
    * ``s,glue``: a profile across the mouth (s from −1, right corner, to +1,
      left corner), linearly interpolated at the element centres ``s``.
    """
    path = Path(path)
    s = np.asarray(s, dtype=np.float64)
    try:
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
    except OSError as e:
        raise InputError(f"cannot read glue file: {e.strerror}", path) from None
    except (UnicodeDecodeError, csv.Error):
        raise InputError("not a glue CSV file (not text)", path) from None
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if not rows:
        raise InputError("empty glue file", path)
    header = [c.strip().lower() for c in rows[0]]
    if header not in (["element", "glue"], ["s", "glue"]):
        raise InputError(f"header must be 'element,glue' or 's,glue', got {','.join(rows[0])!r}", path, 1)
    keys, vals = [], []
    for i, row in enumerate(rows[1:], start=2):
        if len(row) != 2:
            raise InputError(f"expected 2 columns, got {len(row)}", path, i)
        try:
            k, v = float(row[0]), float(row[1])
        except ValueError:
            raise InputError(f"not a number in {','.join(row)!r}", path, i) from None
        if not np.isfinite(v) or not 0 <= v <= MAX_GLUE:
            raise InputError(f"glue must be from 0 to {MAX_GLUE:g}, got {row[1].strip()[:24]}", path, i)
        keys.append(k)
        vals.append(v)
    if not keys:
        raise InputError("no glue values", path)
    keys, vals = np.array(keys), np.array(vals)
    if header[0] == "element":
        if not check_elements:
            return np.full(len(s), np.nan)
        idx = keys.astype(np.int64)
        bad = (idx != keys) | (idx < 0) | (idx >= len(s))
        if bad.any():
            raise InputError(f"element {keys[bad][0]:g} names no saliva element (0..{len(s) - 1})", path)
        glue = np.full(len(s), np.nan)
        glue[idx] = vals
        if np.isnan(glue).any():
            raise InputError(f"missing elements {np.flatnonzero(np.isnan(glue))[:5].tolist()}", path)
        out = np.empty(len(s))
        out[np.argsort(s, kind="stable")] = glue             # element k: the k-th from the right corner
        return out
    order = np.argsort(keys)
    return np.interp(s, keys[order], vals[order])


def glue_per_element(s, glue: float = GLUE, profile: str | None = None,
                     path: str | Path | None = None) -> np.ndarray:
    """Combine the three ways of giving glue: uniform ``glue``, then a ``profile``, or a file."""
    s = np.asarray(s, dtype=np.float64)
    if not np.isfinite(glue) or not 0 <= glue <= MAX_GLUE:
        raise InputError(f"glue must be from 0 to {MAX_GLUE:g}, got {glue}")
    if path is not None:
        return read_glue_file(path, s)
    if profile:
        return parse_glue_profile(profile, s, base=glue)
    return np.full(len(s), float(glue))
