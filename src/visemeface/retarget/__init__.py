"""Retargeting: our face's motion in other tools' vocabularies.

:mod:`.recipes` defines the target shapes (ARKit's 52 blendshapes, VRM expressions, Oculus/Meta's 15
visemes) on our rig as data (``data/retarget/``); :mod:`.fit` solves each frame's bounded least-squares
weights; :mod:`.classes` turns an utterance's phones into Rhubarb Lip Sync mouth cues. The writers and
sinks live in :mod:`visemeface.export.retarget` and :mod:`visemeface.export.rhubarb`.
"""

from visemeface.retarget.fit import ShapeFit, moving_vertices
from visemeface.retarget.recipes import OCULUS, VOCABULARIES, Vocabulary, live_link_name, vocabulary

__all__ = ["OCULUS", "VOCABULARIES", "ShapeFit", "Vocabulary", "live_link_name", "moving_vertices", "vocabulary"]
