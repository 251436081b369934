"""visemeface: expressive visual-speech synthesis.

Waters-style muscle functions move a face mesh; visemes and emotions are
muscle-activation vectors that are blended and interpolated along a timed
phoneme transcription; the same activation track can drive a TLED
finite-element face with sticky lips.
"""

__version__ = "0.1.0"
