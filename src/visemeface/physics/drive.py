"""The physical face's public names in one place: the simulation, its settings and the tracks that drive it.

:class:`~visemeface.physics.loads.FaceDrive` turns an activation track into muscle loads and the prescribed
jaw; :mod:`visemeface.physics.simulation` runs the sticky-lip FEM face (Leach & Maddock 2018) under them;
:mod:`visemeface.physics.scenarios` makes the tracks of their experiments. Importing this module imports the
solver (numba); :data:`visemeface.physics.PHYSICS` names the kinds without it.
"""

from visemeface.physics.glue import GLUE
from visemeface.physics.loads import FaceDrive
from visemeface.physics.saliva import SalivaParams
from visemeface.physics.scenarios import (SCENARIOS, SIDES, activation_at, make_track, ramp_track, scenario_track,
                                          smoothstep_keyframes, track_values)
from visemeface.physics.simulation import (MIN_JACOBIAN, PHYSICS, TERMS, PhysicsSettings, SimFrame,
                                           StickySimulation, face_simulation, physics_face, simulate_track)

__all__ = ["GLUE", "MIN_JACOBIAN", "PHYSICS", "SCENARIOS", "SIDES", "TERMS", "FaceDrive", "PhysicsSettings",
           "SalivaParams", "SimFrame", "StickySimulation", "activation_at", "face_simulation", "make_track",
           "physics_face", "ramp_track", "scenario_track", "simulate_track", "smoothstep_keyframes", "track_values"]
