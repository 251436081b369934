"""The physics configuration file (TOML): the physical face's parameters beyond the command line's few.

``--physics-config FILE.toml`` (``speak``, ``say``, ``simulate``) reads this file over the lips ``--lips``
chose, and options given on the command line win over it. Every key is optional; a key the file does not
know, a value of the wrong type or outside its range is refused in one line naming the file, the line and
the key. The keys and their ranges are :data:`KEYS` (:func:`keys_summary` lists them); ``docs/formats/physics-config.md`` shows a file holding
the speech lips' defaults (a test reads it back to :meth:`PhysicsSettings.speech`).

Top-level keys are :class:`~visemeface.physics.simulation.PhysicsSettings` fields, those of the
``[saliva]`` table :class:`~visemeface.physics.saliva.SalivaParams` fields (Leach & Maddock 2018, Table 1).
The experiments a research run may switch on in Python (a posture spring, dead muscle loads, a free lip
bone, field smoothing, a flowing or stranded film) are no keys here: they are not the model the commands
run.
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

from visemeface.errors import InputError, close_matches
from visemeface.textfile import parse_toml, read_text

#: ``dt``'s range in s. Below 1e-6 a second of motion is over a million steps (about 5 minutes here), and far
#: below it the step is no time at all (1e-308 was reported as a divergence); above 0.01 it is longer than a
#: frame at 100 fps, and beyond the film's stable step, which a run refuses anyway.
MIN_DT, MAX_DT = 1e-6, 0.01
#: Largest damping (1/s): the motion then relaxes in 0.1 ms, far past critical damping of any of the
#: face's modes; 1e308 overflowed the integrator.
MAX_DAMPING = 1e4
#: Most tissue elements along the lip seam (the default face at 96: 6,848 hexahedra against 4,176 at 48,
#: and a run 2.1x as long; far more is a mistyped number more often than a wish).
MAX_SEAM_ELEMENTS = 192
#: Largest moisture a file may give (the seed's 100, with room): a bigger number is a typo, and 1e308
#: overflows the film's arithmetic.
MAX_MOISTURE = 1e6


def _keys() -> dict:
    from visemeface.physics.glue import MAX_GLUE

    inf = math.inf
    # key: (table or None, type, low, high, low open?, what)
    return {
        "dt": (None, float, MIN_DT, MAX_DT, False, "one time step in s for every node (absent: multi-rate, "
               "the tissue's stable step with the film's nodes in substeps)"),
        "damping": (None, float, 0.0, MAX_DAMPING, False, "mass damping alpha, 1/s"),
        "hourglass_kappa": (None, float, 0.0, 1.0, False, "hourglass control of the one-point hexahedra "
                            "(Joldes et al. 2008)"),
        "glue": (None, float, 0.0, MAX_GLUE, False, "glue strength K_glue"),
        "glue_profile": (None, str, None, None, False, "glue across the mouth over glue, e.g. 'centre=0.18'"),
        "glue_file": (None, str, None, None, False, "a CSV of glue per film element or a profile (s,glue), "
                      "relative to this file"),
        "film_corners": (None, bool, None, None, False, "the saliva film runs on into the mouth corners"),
        "seam_elements": (None, int, 0, MAX_SEAM_ELEMENTS, False, "tissue elements along the lip seam at "
                          "least (0: the face's own)"),
        "tissue_limit": (None, float, 1.0, inf, True, "the tissue's limiting stretch (Gent; inf: neo-Hookean)"),
        "initial_moisture": ("saliva", float, 0.0, MAX_MOISTURE, False, "initial moisture M0"),
        "critical_moisture": ("saliva", float, 0.0, MAX_MOISTURE, True, "moisture under which saliva glues, Mc"),
        "evaporation": ("saliva", float, 0.0, MAX_MOISTURE, False, "moisture lost per second"),
        "decay": ("saliva", float, 0.0, 1.0, False, "per-step force factor of a broken brittle element, < 1"),
        "rupture_time": ("saliva", float, 0.0, 1.0, False, "s a saliva strand thins over before it snaps "
                         "(0: the brittle film)"),
    }


KEYS = _keys()
TABLES = ("saliva",)


def keys_summary() -> str:
    """The keys a physics configuration file may hold, as the help lists them: ``a, b; [table] c, d``."""
    groups = [", ".join(k for k, spec in KEYS.items() if spec[0] is None)]
    groups += [f"[{t}] " + ", ".join(k for k, spec in KEYS.items() if spec[0] == t) for t in TABLES]
    return "; ".join(groups)


def _line_of(text: str, key: str, table: bool = False) -> int | None:
    pattern = r"^\s*\[\s*" + re.escape(key) + r"\s*\]" if table else r"^\s*" + re.escape(key) + r"\s*="
    m = re.search(pattern, text, re.M)
    return text.count("\n", 0, m.start()) + 1 if m else None


def read_physics_config(path: str | Path) -> dict:
    """The checked values of a physics configuration file: ``{key: value}`` over :data:`KEYS`.

    ``glue_file`` is resolved against the file's folder; ``seam_elements`` 0 is None (the face's own).
    Every refusal is an :class:`InputError` naming the file, the line and the key.
    """
    path = Path(path)
    text = read_text(path, "physics configuration")
    data = parse_toml(text, path)
    flat = {}
    for key, value in data.items():
        if isinstance(value, dict):
            if key not in TABLES:
                raise InputError(f"unknown table [{key}]" + close_matches(key, TABLES) + f"; known: [{', '.join(TABLES)}]",
                                 path, _line_of(text, key, table=True))
            for sub, v in value.items():
                flat[(key, sub)] = v
        else:
            flat[(None, key)] = value
    out = {}
    for (table, key), value in flat.items():
        where = f"[{table}] {key}" if table else key
        known = [k for k, spec in KEYS.items() if spec[0] == table]
        if key not in known:
            raise InputError(f"unknown key {where!r}" + close_matches(key, known) + f"; known here: {', '.join(known)}",
                             path, _line_of(text, key))
        out[key] = _checked(KEYS[key], value, where, path, _line_of(text, key))
    if "glue_file" in out:
        out["glue_file"] = str((path.parent / out["glue_file"]).resolve())
    _check_glue(out, text, path)
    if out.get("seam_elements") == 0:
        out["seam_elements"] = None
    return out


def _check_glue(values: dict, text: str, path: Path) -> None:
    """The file's glue profile and glue file read as the options' are, before any face is built: a bad one
    is refused naming this file and the key's line (a glue file's own faults name the glue file)."""
    from visemeface.physics.glue import check_glue_sources

    if values.get("glue_profile"):
        try:
            check_glue_sources(values["glue_profile"])
        except InputError as exc:
            raise InputError(f"glue_profile: {exc.reason}", path, _line_of(text, "glue_profile")) from None
    if values.get("glue_file"):
        check_glue_sources(None, values["glue_file"])


def _checked(spec, value, where: str, path: Path, line: int | None):
    _, kind, low, high, low_open, _what = spec

    def refuse(expected):
        return InputError(f"{where} must be {expected}, got {value!r}", path, line)

    if kind is bool:
        if not isinstance(value, bool):
            raise refuse("true or false")
        return value
    if kind is str:
        if not isinstance(value, str):
            raise refuse("text")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)) or math.isnan(value):
        raise refuse("a number")
    if kind is int and not (isinstance(value, int) or float(value).is_integer()):
        raise refuse("a whole number")
    bad_low = value <= low if low_open else value < low
    if bad_low or value > high or (math.isinf(value) and not math.isinf(high)):
        span = f"{'over' if low_open else 'from'} {low:g}" + (" (inf: none)" if math.isinf(high) else f" to {high:g}")
        raise refuse(span)
    return int(value) if kind is int else float(value)


def apply_physics_config(settings, values: dict):
    """``settings`` (a :class:`~visemeface.physics.simulation.PhysicsSettings`) with a file's checked values."""
    saliva = {k: v for k, v in values.items() if KEYS[k][0] == "saliva"}
    top = {k: v for k, v in values.items() if KEYS[k][0] is None}
    return dataclasses.replace(settings, saliva=dataclasses.replace(settings.saliva, **saliva), **top)


def physics_config_text(settings) -> str:
    """A configuration file holding ``settings``' values of every key (the inverse of the reader)."""
    lines, saliva = [], ["", "[saliva]"]
    for key, (table, kind, *_rest, what) in KEYS.items():
        value = getattr(settings.saliva if table else settings, key)
        if value is None:
            if key == "seam_elements":
                value = 0
            else:
                lines.append(f"# {key} = ...  # {what}")
                continue
        if kind is bool:
            text = "true" if value else "false"
        elif kind is str:
            text = '"' + str(value).replace("\\", "\\\\").replace('"', '\\"') + '"'
        elif isinstance(value, float) and math.isinf(value):
            text = "inf"
        else:
            text = repr(int(value) if kind is int else float(value))
        (saliva if table else lines).append(f"{key} = {text}  # {what}")
    return "\n".join(lines + saliva) + "\n"
