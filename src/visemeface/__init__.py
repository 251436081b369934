"""visemeface: expressive visual-speech synthesis.

Waters-style muscle functions move a face mesh; visemes and emotions are
muscle-activation vectors that are blended and interpolated along a timed
phoneme transcription; the same activation track can drive a TLED
finite-element face with sticky lips.

One call per job (:mod:`visemeface.api`, imported on first use so that
``import visemeface`` stays light): :func:`speak`, :func:`say`,
:func:`simulate`, :func:`lipsync` and :func:`analyze`, each the command of the
same name with its defaults, returning a :class:`Result`.
"""

__version__ = "0.1.0"

__all__ = ["__version__", "speak", "say", "simulate", "lipsync", "analyze", "Result"]

_API = {"speak", "say", "simulate", "lipsync", "analyze", "Result"}


def __getattr__(name):
    if name in _API:
        from visemeface import api

        return getattr(api, name)
    raise AttributeError(f"module 'visemeface' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | _API)
