"""The viseme and expression tables, and expressive blending of the two.

A *posture* is a vector of muscle activations, one per rig function
(``rig.names``: 25 muscles then ``jaw``). Edge & Maddock (2001, §2.2) store 56 speech
postures (visemes, one per DECtalk phoneme, silence included) and a handful of
emotions, and makes an expressive speech posture by weighted parameter
blending, muscle by muscle:

.. math::

    a_m = \\operatorname{clip}\\Big(w_v\\, V_m + \\sum_e w_e\\, E_{e,m},\\;
          \\ell_m,\\; u_m\\Big)

where :math:`V` is the viseme, :math:`E_e` the emotions with weights
:math:`w_e \\ge 0`, and :math:`[\\ell_m, u_m]` the muscle's range in the rig
(Edge & Maddock 2001, §2.1.3: each contraction is restricted so summed influences do not
disfigure the mask).

The tables are read and validated by :mod:`visemeface.postures.tables` (its
loaders are re-exported here).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Mapping

import numpy as np
import pandas as pd

from visemeface.errors import InputError, table_name
from visemeface.muscles.measure import TARGET_DIMENSIONS  # noqa: F401  (lip-shape target columns, re-exported)
from visemeface.muscles.rig import SPEECH_FUNCTIONS  # noqa: F401  (Edge & Maddock 2001, Table 1, re-exported)
from visemeface.postures.tables import (EMOTIONS, _default_rig, _rig_spec, expression_info,  # noqa: F401
                                        expressions_file, load_expressions, load_targets, load_visemes,
                                        targets_file, viseme_info, visemes_file)

__all__ = [
    "EMOTIONS", "PostureLibrary", "default_library", "SPEECH_FUNCTIONS", "TARGET_DIMENSIONS", "blend", "expression_info", "keep_lip_contact", "expressions_file",
    "load_expressions", "load_targets", "load_visemes", "parse_weights", "posed_vertices", "targets_file",
    "viseme_info", "visemes_file",
]

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
    weight 1. A mapping (a dict or a pandas Series, name -> weight) gives its
    weights as they are. Weights must be finite and non-negative.
    """
    if specs is None:
        return {}
    if isinstance(specs, str):
        specs = [specs]
    elif hasattr(specs, "items"):                   # {name: weight}: not its names alone at weight 1
        return {str(name).strip(): _weight(str(name), value) for name, value in specs.items()}
    out: dict[str, float] = {}
    for spec in specs:
        parts = [p.strip() for p in str(spec).split(",")]
        if not any(parts):
            raise InputError(f"empty weight {spec!r}: expected NAME or NAME=WEIGHT")
        for part in filter(None, parts):
            name, sep, value = part.partition("=")
            name = name.strip()
            if not name:
                raise InputError(f"bad weight {part!r}: expected NAME=WEIGHT")
            if sep and not value.strip():
                raise InputError(f"bad weight {part!r}: a number must follow '='")
            out[name] = out.get(name, 0.0) + _weight(name, value.strip() if sep else 1.0)
    return out


def blend(viseme: str, emotions: Mapping[str, float] | None = None, w_viseme: float = 1.0, rig=None,
          *, visemes: pd.DataFrame | None = None, expressions: pd.DataFrame | None = None,
          keep_contact: bool = False, library: PostureLibrary | None = None) -> pd.Series:
    """Expressive speech posture by weighted parameter blending (Edge & Maddock 2001, §2.2.1).

    .. math::

        a_m = \\operatorname{clip}(w_v V_m + \\textstyle\\sum_e w_e E_{e,m},\\ \\ell_m, u_m)

    Parameters
    ----------
    viseme : str
        DECtalk symbol (``"ah"``); ``"_"`` (silence) gives the pure expression.
    emotions : mapping of str to float, or str, optional
        Emotion name -> weight :math:`w_e \\ge 0`; several emotions mix (a string is read as the
        command line's ``"happiness=0.6, anger"``; names in any case). Above 1 exaggerates (the
        notebook's sliders go to 1.5); the command line and a text's emotion tags keep to 0..1.
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
        still closes. Off by default (Leach & Maddock's (2018) plain arithmetic).

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
    >>> a = blend("ah", {"happiness": 0.6})
    >>> round(float(a["zygomatic_major_left"]), 2)
    0.6
    """
    if library is None:
        library = _library(rig)
    rig = library.rig
    names, ranges = _rig_spec(rig)
    visemes = library.visemes if visemes is None else visemes
    expressions = library.expressions if expressions is None else expressions
    viseme = table_name(viseme, visemes.index, "viseme")
    w_v = _weight("viseme", w_viseme)
    total = w_v * visemes.loc[viseme].reindex(list(names), fill_value=0.0).to_numpy(dtype=float)
    # "happiness=0.6, anger" as on the command line, a list of such, a dict or a pandas Series
    emotions = parse_weights(emotions)              # trimmed names, weights checked
    for name, w in emotions.items():
        name = table_name(name, expressions.index, "emotion")
        total = total + w * expressions.loc[name].reindex(list(names), fill_value=0.0).to_numpy(dtype=float)
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
