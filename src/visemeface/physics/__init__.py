"""Finite-element soft tissue: hex8 meshes and the TLED solver (Leach & Maddock 2018; Miller et al. 2007).

Its modules:

hexmesh
    :class:`~visemeface.physics.hexmesh.HexMesh`, ``box_mesh``, ``extrude_quads``
    (a FaceMesh's quads pushed inward into hexahedra), quality checks.
materials
    :class:`~visemeface.physics.materials.NeoHookean` (μ, K, ρ), ``SOFT_TISSUE``,
    ``SALIVA``, the analytic stress, energy and uniaxial force–stretch laws.
tled
    :class:`~visemeface.physics.tled.TLEDSolver`: total Lagrangian explicit
    dynamics, one-point hex8 with hourglass control, lumped mass, central
    difference with mass-proportional damping, fixed / prescribed / force
    boundary conditions, an element-force hook; numba kernels and a numpy
    reference.

The FEM face is built from explicit parts: ``face_model`` (the
extruded face and its saliva hexahedra), ``drive`` (the muscle field and the
jaw from an activation track; ``scenarios`` for Leach & Maddock's (2018) tracks), ``film``
(the saliva film on >= 48 slabs, one compiled breaking rule; constitutive law
in ``saliva``, glue profiles in ``glue``), ``terms`` (force terms), ``state``
(the one exactly-restorable state), ``integrator`` (model + central
differences) and ``simulation`` (``StickySimulation`` putting them together).
The physics knows nothing of phonemes: the speech stages drive it through
activation tracks.

Example
-------
>>> import numpy as np
>>> from visemeface.physics.hexmesh import box_mesh
>>> from visemeface.physics.materials import SOFT_TISSUE
>>> from visemeface.physics.tled import TLEDSolver
>>> bar = box_mesh((8, 1, 1), (0.04, 0.005, 0.005))
>>> solver = TLEDSolver(bar, SOFT_TISSUE, dt=1e-5, damping=80.0, fixed=bar.node_sets["xmin"],
...                     forces=[(bar.node_sets["xmax"], lambda t: [1e-3, 0.0, 0.0])])
>>> last = list(solver.run(n_steps=2000, output_every=1000))[-1]
>>> bool(last.displacement[bar.node_sets["xmax"], 0].mean() > 0)
True

The numba modules are imported on first use of ``tled`` (``import visemeface``
stays fast).
"""

#: The physics kinds of ``--physics`` (besides none): the sticky lips (saliva film) and the tissue alone. Here,
#: not in :mod:`.simulation`, so that a command line lists them without importing the solver (numba, scipy).
PHYSICS = ("sticky", "elastic")


__all__ = ["hexmesh", "materials", "tled"]
