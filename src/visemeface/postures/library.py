"""The viseme and expression tables, and expressive blending of the two.

A *posture* is a vector of muscle activations, one per rig function
(``rig.names``: 25 muscles then ``jaw``). Seed 002 (§2.2) stores 56 speech
postures (visemes, one per DECtalk phoneme, silence included) and a handful of
emotions, and makes an expressive speech posture by weighted parameter
blending, muscle by muscle:

.. math::

    a_m = \\operatorname{clip}\\Big(w_v\\, V_m + \\sum_e w_e\\, E_{e,m},\\;
          \\ell_m,\\; u_m\\Big)

where :math:`V` is the viseme, :math:`E_e` the emotions with weights
:math:`w_e \\ge 0`, and :math:`[\\ell_m, u_m]` the muscle's range in the rig
(seed 002 §2.1.3: each contraction is restricted so summed influences do not
disfigure the mask).

The tables live in ``data/visemes/visemes.csv`` (regenerated from the
lip-shape targets in ``data/visemes/targets.csv`` by ``scripts/fit_visemes.py``)
and ``data/expressions/emotions.csv`` (FACS action units mapped to muscles).
Both are validated when loaded: every activation column must be a function of
the rig, every value a finite number inside its range; errors name the file,
line and column.
"""

from __future__ import annotations

import functools

import math
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from visemeface.errors import InputError, close_matches
from visemeface.muscles.measure import TARGET_DIMENSIONS  # lip-shape target columns, re-exported
from visemeface.muscles.rig import SPEECH_FUNCTIONS  # seed 002 Table 1, re-exported
from visemeface.resources import data_path

__all__ = [
    "EMOTIONS", "PostureLibrary", "default_library", "SPEECH_FUNCTIONS", "TARGET_DIMENSIONS", "blend", "expression_info", "keep_lip_contact", "expressions_file",
    "load_expressions", "load_targets", "load_visemes", "parse_weights", "posed_vertices", "targets_file",
    "viseme_info", "visemes_file",
]

#: The seven emotions every expression table must provide (seed 002's six + disgust).
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


class PostureLibrary:
    """The viseme and emotion tables validated against one rig, with a lip gauge on its face.

    Made once and passed around (loading and validating the tables costs milliseconds;
    blending a posture microseconds). :func:`blend` and :func:`posed_vertices` use the
    default rig's library when given no library.

    Parameters
    ----------
    rig : MuscleRig, optional
        Default: the shared default rig.
    visemes, expressions : DataFrame, optional
        Tables to use instead of the shipped ones (as the loaders return them).
    """

    def __init__(self, rig=None, visemes: pd.DataFrame | None = None, expressions: pd.DataFrame | None = None):
        from visemeface.muscles.measure import LipGauge

        self.rig = _default_rig() if rig is None else rig
        self.visemes = load_visemes(rig=self.rig) if visemes is None else visemes
        self.expressions = load_expressions(rig=self.rig) if expressions is None else expressions
        self.gauge = LipGauge(self.rig.face)

    def blend(self, viseme: str, emotions: Mapping[str, float] | None = None, w_viseme: float = 1.0,
              keep_contact: bool = False) -> pd.Series:
        """:func:`blend` with this library's rig and tables."""
        return blend(viseme, emotions, w_viseme, library=self, keep_contact=keep_contact)

    def posed_vertices(self, viseme: str, emotions: Mapping[str, float] | None = None, w_viseme: float = 1.0,
                       keep_contact: bool = False) -> np.ndarray:
        """The rig's face posed at :meth:`blend`: (N, 3) vertices."""
        return np.asarray(self.rig.pose(self.blend(viseme, emotions, w_viseme, keep_contact).to_numpy()))

    def opening(self, a) -> float:
        """Lip opening (change from rest, in rest mouth widths) of activations ``a``."""
        return float(self.gauge.changes(self.rig.pose(np.asarray(a, dtype=float)))["opening_height"])


@functools.lru_cache(maxsize=1)
def default_library() -> PostureLibrary:
    """The shipped tables on the shared default rig (built once)."""
    return PostureLibrary()


def _library(rig) -> PostureLibrary:
    from visemeface.muscles.rig import default_rig

    return default_library() if rig is None or rig is default_rig() else PostureLibrary(rig)


# --------------------------------------------------------------------------- blending

def _weight(name: str, value) -> float:
    try:
        w = float(value)
    except (TypeError, ValueError):
        raise InputError(f"weight of {name!r} must be a number, got {value!r}") from None
    if not math.isfinite(w):
        raise InputError(f"weight of {name!r} must be finite, got {value!r}")
    if w < 0:
        raise InputError(f"weight of {name!r} must not be negative, got {w:g}")
    return w


def parse_weights(specs: Iterable[str] | str | None) -> dict[str, float]:
    """Parse ``NAME[=WEIGHT]`` strings (``"happiness=0.6"``) into a dict.

    Several may be given as a list or comma-separated; a bare name means
    weight 1. Weights must be finite and non-negative.
    """
    if specs is None:
        return {}
    if isinstance(specs, str):
        specs = [specs]
    out: dict[str, float] = {}
    for spec in specs:
        for part in str(spec).split(","):
            part = part.strip()
            if not part:
                continue
            name, _, value = part.partition("=")
            name = name.strip()
            if not name:
                raise InputError(f"bad weight {part!r}: expected NAME=WEIGHT")
            out[name] = out.get(name, 0.0) + _weight(name, value.strip() if value else 1.0)
    return out


def blend(viseme: str, emotions: Mapping[str, float] | None = None, w_viseme: float = 1.0, rig=None,
          *, visemes: pd.DataFrame | None = None, expressions: pd.DataFrame | None = None,
          keep_contact: bool = False, library: PostureLibrary | None = None) -> pd.Series:
    """Expressive speech posture by weighted parameter blending (seed 002 §2.2.1).

    .. math::

        a_m = \\operatorname{clip}(w_v V_m + \\textstyle\\sum_e w_e E_{e,m},\\ \\ell_m, u_m)

    Parameters
    ----------
    viseme : str
        DECtalk symbol (``"ah"``); ``"_"`` (silence) gives the pure expression.
    emotions : mapping of str to float, optional
        Emotion name -> weight :math:`w_e \\ge 0`; several emotions mix.
    w_viseme : float
        Weight :math:`w_v \\ge 0` of the viseme.
    rig : MuscleRig, optional
        Gives the function names and ranges (default rig if None).
    visemes, expressions : DataFrame, optional
        Tables to use instead of the shipped ones (as returned by the loaders).
    library : PostureLibrary, optional
        Rig, tables and lip gauge loaded once (instead of ``rig``); pass one when
        blending many postures on your own rig.
    keep_contact : bool
        For postures whose articulation needs lip contact (bilabials p b m,
        labiodentals f v), close the jaw after blending until the lip opening is
        back to the viseme's own (:func:`keep_lip_contact`): a surprised /m/
        still closes. Off by default (the seed's plain arithmetic).

    Returns
    -------
    Series
        Activations indexed by ``rig.names``, each clamped to its range.

    Raises
    ------
    InputError
        Unknown viseme or emotion (with close matches), negative, NaN or
        non-numeric weight.

    Examples
    --------
    >>> a = blend("ah", {"happiness": 0.6})          # doctest: +SKIP
    >>> a["zygomatic_major_left"]                    # doctest: +SKIP
    0.54
    """
    if library is None:
        library = _library(rig)
    rig = library.rig
    names, ranges = _rig_spec(rig)
    visemes = library.visemes if visemes is None else visemes
    expressions = library.expressions if expressions is None else expressions
    viseme = str(viseme).strip()
    if viseme not in visemes.index and viseme.lower() in visemes.index:
        viseme = viseme.lower()           # DECtalk symbols are lower case; "AA" means /aa/
    if viseme not in visemes.index:
        raise InputError(f"unknown viseme {viseme!r}{close_matches(viseme.lower(), visemes.index)}")
    w_v = _weight("viseme", w_viseme)
    total = w_v * visemes.loc[viseme].reindex(list(names), fill_value=0.0).to_numpy(dtype=float)
    for name, w in (emotions or {}).items():
        name = str(name).strip()
        if name not in expressions.index:
            raise InputError(f"unknown emotion {name!r}{close_matches(name, expressions.index)}")
        total = total + _weight(name, w) * expressions.loc[name].reindex(list(names), fill_value=0.0).to_numpy(dtype=float)
    clamped = np.clip(total, ranges[:, 0], ranges[:, 1])
    out = pd.Series(clamped, index=pd.Index(names, name="function"), name=viseme)
    if keep_contact and viseme in _contact_postures() and emotions and w_v > 0:
        alone = np.clip(w_v * visemes.loc[viseme].reindex(list(names), fill_value=0.0).to_numpy(dtype=float),
                        ranges[:, 0], ranges[:, 1])
        out = keep_lip_contact(rig, out, library.opening(alone), library=library)
    return out


def _contact_postures() -> tuple[str, ...]:
    from visemeface.postures.phonemes import CLOSURE, LABIODENTAL

    return tuple(CLOSURE) + tuple(LABIODENTAL)


def keep_lip_contact(rig, activations: pd.Series, opening: float, tol: float = 1e-4,
                     library: PostureLibrary | None = None) -> pd.Series:
    r"""Close the jaw until the lip opening is at most ``opening``.

    The lip opening :math:`h(j)` (change from rest, in rest mouth widths) grows
    monotonically with the jaw activation :math:`j`, so bisection on
    :math:`j \in [j_{min}, j_0]` finds the largest jaw with :math:`h(j) \le`
    ``opening``; every other activation is kept. If even the closed jaw
    :math:`j_{min}` leaves the lips further apart (an emotion lifting the upper
    lip), the jaw stays at :math:`j_{min}`.

    Parameters
    ----------
    rig : MuscleRig
    activations : Series
        Activations indexed by ``rig.names``.
    opening : float
        Largest lip opening allowed (e.g. the bare viseme's).
    tol : float
        Bisection stops when the jaw interval is shorter than this.
    library : PostureLibrary, optional
        Its lip gauge measures the opening (default: one for ``rig``).

    Returns
    -------
    Series
        A copy of ``activations`` with the ``jaw`` entry lowered where needed.
    """
    library = library if library is not None and library.rig is rig else _library(rig)
    a = activations.astype(float).copy()
    j = rig.names.index("jaw")
    lo, hi = float(rig.ranges[j, 0]), float(a.iloc[j])

    def h(jaw):
        b = a.to_numpy().copy()
        b[j] = jaw
        return library.opening(b)

    if h(hi) <= opening + 1e-9:
        return a
    if h(lo) > opening:
        a.iloc[j] = lo
        return a
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if h(mid) <= opening else (lo, mid)
    a.iloc[j] = lo
    return a


def posed_vertices(rig, viseme: str, emotions: Mapping[str, float] | None = None,
                   w_viseme: float = 1.0, keep_contact: bool = False) -> np.ndarray:
    """The rig's face posed at ``blend(viseme, emotions, w_viseme, keep_contact=...)``: (N, 3) vertices."""
    return _library(rig).posed_vertices(viseme, emotions, w_viseme, keep_contact)
