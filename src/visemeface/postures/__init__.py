"""Speech and expression postures.

- :mod:`visemeface.postures.phonemes`: the DECtalk inventory, Edge & Maddock (2001) Table 2's
  eight classes, ARPAbet/TIMIT/IPA maps.
- :mod:`visemeface.postures.library`: the 56 visemes and 7 emotions as muscle
  activations (``data/visemes``, ``data/expressions``), validated loading, and
  weighted blending ``blend(viseme, emotions)`` / ``posed_vertices(rig, ...)``.
"""
