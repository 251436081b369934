"""visemeface.render: headless OpenGL rendering (:mod:`~visemeface.render.renderer`) and file
export of animations (:mod:`~visemeface.render.export`).

The renderer is imported on demand (``from visemeface.render.renderer import Renderer``) so that
importing the package does not load OpenGL.
"""

#: Camera presets of :class:`~visemeface.render.renderer.Renderer` (here so that option lists need no OpenGL).
VIEWS = ("face", "mouth", "three-quarter")
#: Projections of the renderer.
PROJECTIONS = ("perspective", "orthographic")
