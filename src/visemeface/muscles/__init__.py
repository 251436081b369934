"""Waters muscle rig (Edge & Maddock 2001, §2.1): 25 muscles and the jaw on any face mesh.

- :mod:`~visemeface.muscles.functions`: linear and sphincter muscle fields, lip
  trimming, jaw rotation (pure numpy, formulas in the docstrings);
- :mod:`~visemeface.muscles.rig`: :class:`~visemeface.muscles.rig.MuscleRig`
  placed from ``data/rig/default.toml`` relative to landmarks, ``pose(activations)``;
- :mod:`~visemeface.muscles.measure`: lip dimensions of a posed mesh;
- :mod:`~visemeface.muscles.fitting`: activations that produce target lip dimensions;
- :mod:`~visemeface.muscles.overlay`: pictures of the rig.
"""
