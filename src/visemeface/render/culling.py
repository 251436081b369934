"""Triangles a renderer may leave out: the still ones that no pixel shows at rest.

A caller whose frames leave some vertices at their rest positions (the kinematic rig: the scalp, neck and
back of a scanned head, the upper teeth) names them; a triangle with only such corners ("still") is drawn in
the same place in every frame. With the depth test, a pixel shows the nearest fragment (the first drawn
among equals) whatever else is drawn, and the moving triangles can only add fragments; so a still triangle
that shows at no pixel when the still triangles alone are drawn at rest shows at no pixel of any frame, and
leaving it out does not change the image. Which still triangles show is read back once from an image of
their indices (``gl_PrimitiveID``) drawn with the renderer's own camera and vertex positions.
"""

from __future__ import annotations

import numpy as np

_ID_VERTEX_SHADER = """
#version 330
uniform mat4 u_mvp;
in vec3 in_pos;
void main() {
    gl_Position = u_mvp * vec4(in_pos, 1.0);
}
"""

_ID_FRAGMENT_SHADER = """
#version 330
out uint f_id;
void main() {
    f_id = uint(gl_PrimitiveID) + 1u;
}
"""


def shown_triangles(ctx, mvp: np.ndarray, positions: np.ndarray, triangles: np.ndarray,
                    still: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """(T,) bool: the triangles to draw, in a one-sample framebuffer of ``size`` with clip matrix ``mvp``.

    Every triangle with a corner off ``still`` ((N,) bool), and each still triangle that shows at a pixel
    when the still triangles alone are drawn at ``positions`` ((N, 3) float32, the rest positions as the
    renderer writes them).
    """
    import moderngl

    still_tri = still[triangles].all(axis=1)
    keep = ~still_tri
    idx = np.flatnonzero(still_tri)
    if not len(idx):
        return keep
    objects = [ctx.program(vertex_shader=_ID_VERTEX_SHADER, fragment_shader=_ID_FRAGMENT_SHADER)]
    program = objects[0]
    program["u_mvp"].write(np.asarray(mvp).T.astype("f4").tobytes())
    objects += [ctx.buffer(np.ascontiguousarray(positions, dtype="f4").tobytes()),
                ctx.buffer(np.ascontiguousarray(triangles[idx], dtype=np.int32).tobytes())]
    objects.append(ctx.vertex_array(program, [(objects[1], "3f", "in_pos")], index_buffer=objects[2],
                                    index_element_size=4))
    objects += [ctx.renderbuffer(size, 1, dtype="u4"), ctx.depth_renderbuffer(size)]
    objects.append(ctx.framebuffer(color_attachments=[objects[4]], depth_attachment=objects[5]))
    try:
        objects[6].use()
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.CULL_FACE)
        objects[6].clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        objects[3].render(moderngl.TRIANGLES)
        ids = np.frombuffer(objects[6].read(components=1, dtype="u4"), dtype=np.uint32)
    finally:
        for o in reversed(objects):
            o.release()
    keep[idx[np.unique(ids[ids > 0]) - 1]] = True
    return keep
