"""Reading a rig file (TOML): validation with file, entry and field in every error, and the muscles it places.

See :mod:`visemeface.muscles.rig` for the format. The reader resolves points
(landmarks, mixes and offsets in mouth widths along the mouth frame) and region
names; :func:`muscles_from` builds the :class:`~visemeface.muscles.muscle.Muscle` list.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from visemeface.errors import InputError, close_matches
from visemeface.numeric import sphere_fit
from visemeface.textfile import parse_toml, read_text

#: Region names of docs/conventions.md (a rig file may name them even if a mesh lacks some).
CONVENTION_REGIONS = ("upper_lip", "lower_lip", "lip_seam_upper", "lip_seam_lower", "jaw", "fixed", "brow",
                      "cheek", "mouth_cavity", "eyes", "cavity_wall", "upper_teeth", "lower_teeth", "upper_gum",
                      "lower_gum", "tongue", "upper_lids", "lower_lids", "eyeballs")
LIP_SIDES = ("upper", "lower", "both")


class _RigFileReader:
    """Parses and validates a rig TOML; every error names file, entry and field."""

    def __init__(self, path: Path, face, frame: MouthFrame):
        self.path = path
        self.face = face
        self.frame = frame
        self.text = read_text(path, "rig file")
        self.data = parse_toml(self.text, path)

    def line_of(self, name: str) -> int | None:
        m = re.search(r'^\s*name\s*=\s*"' + re.escape(name) + '"', self.text, re.M)
        return self.text.count("\n", 0, m.start()) + 1 if m else None

    def error(self, entry: str, fld: str, message: str):
        return InputError(f"entry {entry!r}, field {fld!r}: {message}", self.path, self.line_of(entry))

    def get(self, table: Mapping, entry: str, fld: str, kind=float, default=...):
        if fld not in table:
            if default is ...:
                raise self.error(entry, fld, "missing")
            return default
        value = table[fld]
        if kind is float:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
                raise self.error(entry, fld, f"expected a finite number, got {value!r}")
            return float(value)
        if kind is str:
            if not isinstance(value, str):
                raise self.error(entry, fld, f"expected text, got {value!r}")
            return value
        if kind == "range":
            if (not isinstance(value, list) or len(value) != 2
                    or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in value)
                    or not value[0] < value[1]):
                raise self.error(entry, fld, f"expected [low, high] with low < high, got {value!r}")
            return (float(value[0]), float(value[1]))
        if kind == "regions":
            if not isinstance(value, list) or not all(isinstance(x, str) for x in value):
                raise self.error(entry, fld, f"expected a list of region names, got {value!r}")
            return tuple(value)
        raise AssertionError(kind)

    def table(self, name: str) -> dict:
        """The rig file's table ``name`` over the face's own values for it
        (:attr:`~visemeface.face.mesh.FaceMesh.rig_defaults`: the file's win); {} without either."""
        t = self.data.get(name)
        if t is not None and not isinstance(t, Mapping):
            raise self.error(name, name, "expected a table")
        return {**getattr(self.face, "rig_defaults", {}).get(name, {}), **(t or {})}

    def gaze_rigid(self) -> bool:
        """The optional ``[gaze]`` table's ``rigid`` (default false): the "turn" functions turn their whole
        regions exactly, each about the centre of the sphere through its vertices (spherical eyeballs)."""
        rigid = self.table("gaze").get("rigid", False)
        if not isinstance(rigid, bool):
            raise self.error("gaze", "rigid", f"expected true or false, got {rigid!r}")
        return rigid

    def modiolus(self) -> dict | None:
        """The optional ``[modiolus]`` table (``radius`` in W, ``core``, ``exclude``) over the face's own;
        None without either (the corners are not blended)."""
        t = self.table("modiolus")
        if not t:
            return None
        out = {"radius": self.get(t, "modiolus", "radius", float), "core": self.get(t, "modiolus", "core", float),
               "exclude": self.regions(self.get(t, "modiolus", "exclude", "regions", ()), "modiolus", "exclude")}
        if out["radius"] <= 0:
            raise self.error("modiolus", "radius", f"must be positive, got {out['radius']}")
        if not 0 < out["core"] < 1:
            raise self.error("modiolus", "core", f"must be in (0, 1), got {out['core']}")
        return out

    def regions(self, names, entry: str, fld: str) -> tuple:
        """The region names the face has; a name neither on the face nor in the
        conventions' list is an error (a typo), a conventional one the face lacks
        (a user's mesh without ``eyes``) is skipped."""
        kept = []
        for region in names:
            if region in self.face.regions:
                kept.append(region)
            elif region not in CONVENTION_REGIONS:
                raise self.error(entry, fld, f"unknown region {region!r}"
                                 + close_matches(region, set(self.face.regions) | set(CONVENTION_REGIONS)))
        return tuple(kept)

    def landmark(self, entry: str, fld: str, name: str) -> np.ndarray:
        if name not in self.face.landmarks:
            raise self.error(entry, fld, f"unknown landmark {name!r}" + close_matches(name, self.face.landmarks))
        return self.face.landmark_position(name)

    def point(self, table: Mapping, entry: str, fld: str, side: str) -> np.ndarray:
        spec = table.get(fld)
        if not isinstance(spec, Mapping):
            raise self.error(entry, fld, "missing" if spec is None else
                             f"expected {{at = \"landmark\", offset = [x, y, z]}}, got {spec!r}")
        sub = side if side in ("left", "right") else ""

        def name_of(n):
            if "{side}" in n and not sub:
                raise self.error(entry, fld, f"landmark {n!r} uses {{side}} but the muscle has no sides")
            return n.replace("{side}", sub)

        if "at" in spec and "mix" not in spec:
            if not isinstance(spec["at"], str):
                raise self.error(entry, fld, f"'at' must be a landmark name, got {spec['at']!r}")
            base = self.landmark(entry, fld, name_of(spec["at"]))
        elif "mix" in spec and "at" not in spec:
            mix = spec["mix"]
            if not isinstance(mix, Mapping) or not mix:
                raise self.error(entry, fld, f"'mix' must map landmarks to weights, got {mix!r}")
            total, base = 0.0, np.zeros(3)
            for n, w in mix.items():
                if isinstance(w, bool) or not isinstance(w, (int, float)) or not np.isfinite(w):
                    raise self.error(entry, fld, f"weight of {n!r} must be a number, got {w!r}")
                base = base + float(w) * self.landmark(entry, fld, name_of(n))
                total += float(w)
            if abs(total) < 1e-12:
                raise self.error(entry, fld, "mix weights sum to zero")
            base = base / total
        else:
            raise self.error(entry, fld, "give exactly one of 'at' or 'mix'")
        offset = spec.get("offset", [0.0, 0.0, 0.0])
        if (not isinstance(offset, list) or len(offset) != 3
                or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x)
                           for x in offset)):
            raise self.error(entry, fld, f"offset must be [x, y, z] in mouth widths, got {offset!r}")
        offset = np.array(offset, dtype=float)
        if side == "right":
            offset[0] = -offset[0]
        return base + self.frame.to_world(offset)


def muscles_from(reader: _RigFileReader) -> list:
    """The :class:`~visemeface.muscles.muscle.Muscle` entries of a rig file, placed on the reader's face."""
    from visemeface.muscles.muscle import Muscle

    data = reader.data
    entries = data.get("muscle")
    if not isinstance(entries, list) or not entries:
        raise InputError("no [[muscle]] entries", reader.path)
    default_exclude = reader.get(data.get("defaults", {}), "defaults", "exclude", "regions", ())
    W = reader.frame.width
    muscles: list[Muscle] = []
    for i, table in enumerate(entries):
        base = table.get("name") if isinstance(table.get("name"), str) else f"muscle #{i + 1}"
        if not isinstance(table.get("name"), str):
            raise reader.error(base, "name", "missing")
        kind = reader.get(table, base, "kind", str)
        if kind not in ("linear", "sphincter", "local", "turn"):
            raise reader.error(base, "kind", f"expected 'linear', 'sphincter', 'local' or 'turn', got {kind!r}")
        lip = reader.get(table, base, "lip", str)
        if lip not in LIP_SIDES:
            raise reader.error(base, "lip", f"expected one of {', '.join(LIP_SIDES)}, got {lip!r}")
        rng = reader.get(table, base, "range", "range")
        sides = table.get("sides", [])
        if sides not in ([], ["left", "right"]):
            raise reader.error(base, "sides", f'expected ["left", "right"] or nothing, got {sides!r}')
        exclude = reader.regions(default_exclude + reader.get(table, base, "exclude", "regions", ()),
                                 base, "exclude")
        for side in sides or ["centre"]:
            name = f"{base}_{side}" if sides else base
            m = Muscle(name=name, kind=kind, side=side, lip=lip, range=rng, exclude=exclude,
                       description=str(table.get("description", "")), params=dict(table))
            if kind == "local":
                _local_muscle(reader, table, base, side, m)
            elif kind == "turn":
                _turn_muscle(reader, table, base, side, m)
            elif kind == "linear":
                m.k = reader.get(table, base, "k", float) * W
                m.attachment = reader.point(table, base, "attachment", side)
                m.insertion = reader.point(table, base, "insertion", side)
                length = float(np.linalg.norm(m.insertion - m.attachment))
                if length <= 0:
                    raise reader.error(base, "insertion", "insertion coincides with the attachment")
                omega = reader.get(table, base, "zone_angle_deg", float)
                if not 0 < omega < 180:
                    raise reader.error(base, "zone_angle_deg", f"must be in (0, 180), got {omega}")
                m.zone_angle = np.radians(omega)
                rs = reader.get(table, base, "falloff_start", float)
                rf = reader.get(table, base, "falloff_end", float)
                if not 0 < rs < rf:
                    raise reader.error(base, "falloff_end", f"need 0 < falloff_start < falloff_end, got {rs}, {rf}")
                m.falloff_start, m.falloff_end = rs * length, rf * length
                fibres = reader.get(table, base, "fibres", str, "fan")
                if fibres not in ("fan", "parallel"):
                    raise reader.error(base, "fibres", f"expected 'fan' or 'parallel', got {fibres!r}")
                if fibres == "parallel" and not (omega < 90 and rf > 1):
                    raise reader.error(base, "fibres", "a sheet of parallel fibres needs zone_angle_deg under 90 "
                                       "and falloff_end past the insertion (over 1)")
            else:
                m.centre = reader.point(table, base, "centre", side)
                sx = reader.get(table, base, "semi_x", float)
                sy = reader.get(table, base, "semi_y", float)
                if not 0 < sy <= sx:
                    raise reader.error(base, "semi_y", f"need 0 < semi_y <= semi_x, got {sx}, {sy}")
                m.semi_x, m.semi_y = sx * W, sy * W
                m.k = reader.get(table, base, "k", float)
                if not 0 <= m.k < 1:
                    raise reader.error(base, "k", f"a sphincter's contraction fraction must be in [0, 1), got {m.k}")
                shield = reader.get(table, base, "shield", float, None)
                m.shield = None if shield is None else shield * W
                m.protrusion = reader.get(table, base, "protrusion", float, 0.0) * W
                depth = reader.get(table, base, "depth", float, None)
                m.depth = None if depth is None else depth * W
            muscles.append(m)
    names = [m.name for m in muscles]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise reader.error(dup[0], "name", "defined twice")
    if "jaw" in names:
        raise reader.error("jaw", "name", "'jaw' is reserved for the [jaw] table")
    return muscles


def _vector(reader: _RigFileReader, table: Mapping, base: str, fld: str) -> np.ndarray:
    value = table.get(fld)
    if (not isinstance(value, list) or len(value) != 3
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x) for x in value)):
        raise reader.error(base, fld, f"expected [x, y, z] in mouth widths, got {value!r}")
    return np.array(value, dtype=float)


def _local_muscle(reader: _RigFileReader, table: Mapping, base: str, side: str, m) -> None:
    """Fill a "local" function (tongue, lip rounding, lip tuck).

    It moves the vertices of its ``regions`` (all when none are named) except its
    own ``exclude`` regions (the rig's default exclusions do not apply: the tongue's
    functions move the tongue). ``symmetric = true`` adds the mirror image about
    the mouth's mid-plane; ``direction_lower`` moves the lower lip (lip-trimmed)
    differently from the upper; ``inner`` (W) makes the lateral falloff a band
    (:func:`~visemeface.muscles.functions.local_displacement`); ``close_to`` (regions) and ``overlap`` (W)
    size the push so that its margin meets theirs (:func:`~visemeface.muscles.functions.closing_scale`).
    """
    W = reader.frame.width
    names = reader.get(table, base, "regions", "regions", ())
    regions = reader.regions(names, base, "regions")
    m.exclude = reader.regions(reader.get(table, base, "exclude", "regions", ()), base, "exclude")
    mask = np.zeros(len(reader.face.vertices), bool)
    if not names:
        mask[:] = True
    for region in regions:
        mask[reader.face.regions[region]] = True
    m.mask = mask
    radius = _vector(reader, table, base, "radius")
    if not np.all(radius > 0):
        raise reader.error(base, "radius", f"radii must be positive, got {table['radius']!r}")
    m.radii = radius * W
    flip = np.array([-1.0 if side == "right" else 1.0, 1.0, 1.0])
    m.direction = (_vector(reader, table, base, "direction") * flip) @ reader.frame.axes * W
    if "direction_lower" in table:
        m.direction_lower = (_vector(reader, table, base, "direction_lower") * flip) @ reader.frame.axes * W
    sym = table.get("symmetric", False)
    if not isinstance(sym, bool):
        raise reader.error(base, "symmetric", f"expected true or false, got {sym!r}")
    m.symmetric = sym
    if "inner" in table:
        m.inner = reader.get(table, base, "inner", float) * W
        if m.inner < 0:
            raise reader.error(base, "inner", f"must be >= 0, got {table['inner']!r}")
    if "close_to" in table:
        # the lid this one closes onto: the push sized, column by column, by the eye's own opening
        target = reader.regions(reader.get(table, base, "close_to", "regions"), base, "close_to")
        m.close_to = np.unique(np.concatenate([reader.face.regions[r] for r in target] or [np.zeros(0, int)]))
        m.overlap = reader.get(table, base, "overlap", float, 0.0) * W
    # a face without the regions (a user's mesh without a tongue) gets a zero field: no landmark needed
    m.centre = reader.point(table, base, "centre", side) if mask.any() else np.zeros(3)


def _turn_muscle(reader: _RigFileReader, table: Mapping, base: str, side: str, m) -> None:
    """Fill a "turn" function (the eyeballs' gaze): its ``regions`` turn about ``axis`` (mouth frame)
    through ``centre`` by ``angle_deg`` at activation 1 (linearised), within ``radius`` (W) of the
    forward line through ``centre`` when given; a face without the regions gets a zero field. ``lids``
    (regions), ``lid_follow`` (share of the angle, default 1; one number, or one per ``lids`` region) and
    ``lid_radius`` (W) make lid vertices turn with it, fading out toward the eye's corners."""
    names = reader.get(table, base, "regions", "regions")
    regions = reader.regions(names, base, "regions")
    m.exclude = ()
    mask = np.zeros(len(reader.face.vertices), bool)
    for region in regions:
        mask[reader.face.regions[region]] = True
    # only the side's own part of the regions (one eyeball of "eyeballs")
    m.mask = mask
    m.axis = _vector(reader, table, base, "axis") @ reader.frame.axes
    if not np.linalg.norm(m.axis) > 0:
        raise reader.error(base, "axis", "must not be zero")
    m.k = np.radians(reader.get(table, base, "angle_deg", float))
    radius = reader.get(table, base, "radius", float, None)
    m.inner = None if radius is None else radius * reader.frame.width
    m.centre = reader.point(table, base, "centre", side) if mask.any() else np.zeros(3)
    if "lids" in table:
        names = reader.regions(reader.get(table, base, "lids", "regions"), base, "lids")
        follow = table.get("lid_follow", 1.0)
        follow = follow if isinstance(follow, list) else [follow] * len(names)
        if len(follow) != len(names) or not all(isinstance(f, (int, float)) and not isinstance(f, bool)
                                                and 0.0 <= f <= 2.0 for f in follow):
            raise reader.error(base, "lid_follow", f"expected a share in [0, 2] or one per lids region, got "
                                                   f"{table.get('lid_follow')!r}")
        lids = np.zeros(len(reader.face.vertices))
        for region, share in zip(names, follow):
            lids[reader.face.regions[region]] = share
        m.lids = lids if mask.any() else np.zeros_like(lids)
        m.lid_radius = reader.get(table, base, "lid_radius", float) * reader.frame.width
        if not m.lid_radius > 0:
            raise reader.error(base, "lid_radius", "must be positive")
    if mask.any() and side in ("left", "right"):
        x = reader.frame.to_local(reader.face.vertices)[:, 0]
        mine = (x > 0) if side == "left" else (x < 0)
        m.mask = mask & mine
        if m.lids is not None:
            m.lids = m.lids * mine
    if reader.gaze_rigid() and m.mask.any():
        # a spherical eyeball turns whole and exactly about its own centre (the sphere through its vertices;
        # parts inside it, such as ICT's iris shells, left out of the fit); the lids' fade keeps the file's
        # centre, on the forward line through the pupil
        fit = m.mask.copy()
        if "enclosed" in reader.face.regions:
            fit[reader.face.regions["enclosed"]] = False
        m.line = m.centre
        m.centre, _ = sphere_fit(reader.face.vertices[fit if fit.any() else m.mask])
        m.inner, m.rigid = None, True
