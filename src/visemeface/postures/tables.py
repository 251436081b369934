"""The viseme and expression tables: where they are, how they are read and validated.

``data/visemes/visemes.csv`` (regenerated from the lip-shape targets in
``data/visemes/targets.csv`` by ``scripts/fit_visemes.py``) and
``data/expressions/emotions.csv`` (FACS action units mapped to muscles). Both are
validated when loaded: every activation column must be a function of the rig,
every value a finite number inside its range; errors name the file, line and column.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from visemeface.errors import InputError, close_matches
from visemeface.muscles.measure import TARGET_DIMENSIONS
from visemeface.resources import data_path

#: The seven emotions every expression table must provide (Edge & Maddock's (2001) six + disgust).
EMOTIONS: tuple[str, ...] = ("happiness", "sadness", "surprise", "fear", "anger", "contempt", "disgust")

_TARGET_RANGE = (-1.0, 1.0)  # a lip moving by more than a mouth width is a typo


def _dectalk() -> tuple[str, ...]:
    from visemeface.postures.phonemes import DECTALK

    return tuple(DECTALK)


def _default_rig():
    from visemeface.muscles.rig import default_rig

    return default_rig()


def visemes_file() -> Path:
    """Path of the shipped viseme table (``data/visemes/visemes.csv``)."""
    return data_path("visemes", "visemes.csv")


def targets_file() -> Path:
    """Path of the shipped lip-shape targets (``data/visemes/targets.csv``)."""
    return data_path("visemes", "targets.csv")


def expressions_file() -> Path:
    """Path of the shipped emotion table (``data/expressions/emotions.csv``)."""
    return data_path("expressions", "emotions.csv")


# --------------------------------------------------------------------------- reading

def _read_csv(path: Path) -> pd.DataFrame:
    if not path.is_file():
        raise InputError("file not found", path)
    try:
        df = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise InputError(f"not a readable CSV table ({str(exc).splitlines()[0]})", path) from None
    if df.empty:
        raise InputError("table has no rows", path)
    df.columns = [c.strip() for c in df.columns]
    dupes = df.columns[df.columns.duplicated()].tolist()
    if dupes:
        raise InputError(f"column {dupes[0]!r} appears twice", path, 1)
    return df


def _numeric_block(df: pd.DataFrame, columns: Iterable[str], path: Path,
                   ranges: Mapping[str, tuple[float, float]]) -> pd.DataFrame:
    """Parse ``columns`` of the string table as floats inside their ``ranges``.

    Row ``i`` of the table is line ``i + 2`` of the file (line 1 is the header).
    """
    out = {}
    for col in columns:
        lo, hi = ranges[col]
        values = np.empty(len(df))
        for i, text in enumerate(df[col].tolist()):
            try:
                v = float(text)
            except ValueError:
                raise InputError(f"column {col!r}: {text!r} is not a number", path, i + 2) from None
            if not math.isfinite(v):
                raise InputError(f"column {col!r}: {text!r} is not a finite number", path, i + 2)
            if v < lo - 1e-9 or v > hi + 1e-9:
                raise InputError(f"column {col!r}: {v:g} is outside the range [{lo:g}, {hi:g}]", path, i + 2)
            values[i] = v
        out[col] = values
    return pd.DataFrame(out, index=df.index)


def _rig_spec(rig) -> tuple[tuple[str, ...], np.ndarray]:
    if rig is None:
        rig = _default_rig()
    names = tuple(rig.names)
    ranges = np.asarray(rig.ranges, dtype=float).reshape(len(names), 2)
    return names, ranges


def _activation_table(path: Path, key: str, notes: str, rig, extra: tuple[str, ...] = ()) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Read a posture table: ``key`` column, activation columns, ``notes`` column.

    Returns ``(activations, info)``: activations indexed by ``key`` with one column
    per rig function (functions absent from the file are 0), and the remaining
    descriptive columns.
    """
    names, ranges = _rig_spec(rig)
    df = _read_csv(path)
    for required in (key, notes):
        if required not in df.columns:
            raise InputError(f"missing column {required!r}", path, 1)
    descriptive = {key, notes, *extra}
    muscles = [c for c in df.columns if c not in descriptive]
    for col in muscles:
        if col not in names:
            raise InputError(f"column {col!r} is not a function of the rig{close_matches(col, names)}", path, 1)
    keys = [k.strip() for k in df[key].tolist()]
    seen: dict[str, int] = {}
    for i, k in enumerate(keys):
        if not k:
            raise InputError(f"empty {key!r}", path, i + 2)
        if k in seen:
            raise InputError(f"{key} {k!r} appears twice (first on line {seen[k]})", path, i + 2)
        seen[k] = i + 2
    rng = {n: (float(ranges[j, 0]), float(ranges[j, 1])) for j, n in enumerate(names)}
    values = _numeric_block(df, muscles, path, rng)
    acts = values.reindex(columns=list(names), fill_value=0.0)
    acts.index = pd.Index(keys, name=key)
    info = df[[c for c in df.columns if c in descriptive and c != key]].copy()
    info.index = acts.index
    return acts, info


def _check_symbols(symbols: list[str], path: Path, what: str) -> None:
    known = _dectalk()
    for i, s in enumerate(symbols):
        if s not in known:
            raise InputError(f"{what} {s!r} is not a DECtalk symbol{close_matches(s, known)}", path, i + 2)
    missing = [s for s in known if s not in symbols]
    if missing:
        raise InputError(f"{len(missing)} DECtalk postures missing: {', '.join(missing)} "
                         f"(expected {len(known)} rows)", path)


def load_visemes(path: str | Path | None = None, rig=None) -> pd.DataFrame:
    """Load and validate the viseme table.

    Parameters
    ----------
    path : str or Path, optional
        CSV with columns ``index``, ``symbol``, ``class``, activation columns
        (rig function names) and ``notes``; default the shipped table.
    rig : MuscleRig, optional
        Rig whose ``names`` and ``ranges`` validate the columns (default rig if None).

    Returns
    -------
    DataFrame
        Index ``symbol`` (the 56 DECtalk postures in DECtalk order), one column
        per rig function in ``rig.names`` order; functions absent from the file are 0.

    Raises
    ------
    InputError
        Unknown column, non-numeric or out-of-range value, unknown, missing or
        repeated symbol; the message names the file, line and column.
    """
    path = Path(path) if path is not None else visemes_file()
    acts, _ = _activation_table(path, "symbol", "notes", rig, extra=("index", "class"))
    _check_symbols(acts.index.tolist(), path, "symbol")
    return acts.loc[list(_dectalk())]


def viseme_info(path: str | Path | None = None) -> pd.DataFrame:
    """The descriptive columns of the viseme table: index ``symbol``; ``index``, ``class``, ``notes``."""
    path = Path(path) if path is not None else visemes_file()
    df = _read_csv(path)
    for col in ("index", "symbol", "class", "notes"):
        if col not in df.columns:
            raise InputError(f"missing column {col!r}", path, 1)
    out = df[["symbol", "index", "class", "notes"]].copy()
    out["index"] = pd.to_numeric(out["index"], errors="coerce")
    return out.set_index("symbol")


def load_targets(path: str | Path | None = None) -> pd.DataFrame:
    """Load and validate the lip-shape targets of the visemes.

    Each row gives, for one DECtalk posture, the change of each lip dimension
    (:data:`TARGET_DIMENSIONS`) from rest, in fractions of the rest mouth width
    :math:`W_0`: e.g. ``mouth_width = 0.1`` means the corners are
    :math:`1.1\\,W_0` apart.

    Returns
    -------
    DataFrame
        Index ``symbol`` in DECtalk order; columns :data:`TARGET_DIMENSIONS`
        (floats) then ``index``, ``class``, ``notes``.
    """
    path = Path(path) if path is not None else targets_file()
    df = _read_csv(path)
    extra = [c for c in df.columns if c not in ("index", "symbol", "class", "notes", *TARGET_DIMENSIONS)]
    if extra:
        raise InputError(f"column {extra[0]!r} is not a lip dimension"
                         f"{close_matches(extra[0], TARGET_DIMENSIONS)}", path, 1)
    for col in ("index", "symbol", "class", "notes", *TARGET_DIMENSIONS):
        if col not in df.columns:
            raise InputError(f"missing column {col!r}", path, 1)
    values = _numeric_block(df, TARGET_DIMENSIONS, path, dict.fromkeys(TARGET_DIMENSIONS, _TARGET_RANGE))
    symbols = [s.strip() for s in df["symbol"].tolist()]
    if len(set(symbols)) != len(symbols):
        dup = next(s for s in symbols if symbols.count(s) > 1)
        raise InputError(f"symbol {dup!r} appears twice", path)
    _check_symbols(symbols, path, "symbol")
    values.index = pd.Index(symbols, name="symbol")
    for col in ("index", "class", "notes"):
        values[col] = df[col].to_numpy()
    values["index"] = values["index"].astype(int)
    return values.loc[list(_dectalk())]


def load_expressions(path: str | Path | None = None, rig=None) -> pd.DataFrame:
    """Load and validate the emotion table.

    Parameters
    ----------
    path : str or Path, optional
        CSV with columns ``emotion``, activation columns and ``action_units``;
        default the shipped table (the seven of :data:`EMOTIONS`).
    rig : MuscleRig, optional
        Rig whose names and ranges validate the columns.

    Returns
    -------
    DataFrame
        Index ``emotion``, one column per rig function.

    Raises
    ------
    InputError
        As :func:`load_visemes`; also when one of :data:`EMOTIONS` is missing.
    """
    path = Path(path) if path is not None else expressions_file()
    acts, _ = _activation_table(path, "emotion", "action_units", rig)
    missing = [e for e in EMOTIONS if e not in acts.index]
    if missing:
        raise InputError(f"emotions missing: {', '.join(missing)}", path)
    return acts


def expression_info(path: str | Path | None = None) -> pd.DataFrame:
    """Index ``emotion``; column ``action_units`` (the FACS notes)."""
    path = Path(path) if path is not None else expressions_file()
    df = _read_csv(path)
    for col in ("emotion", "action_units"):
        if col not in df.columns:
            raise InputError(f"missing column {col!r}", path, 1)
    return df[["emotion", "action_units"]].set_index("emotion")
