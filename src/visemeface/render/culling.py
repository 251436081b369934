"""Triangles a renderer may leave out: back faces of closed surfaces, and the still triangles no pixel shows at rest.

**One-sided surfaces.** Along a ray from a camera outside a closed, consistently oriented surface whose
normals point out (a tooth, an eyeball, a scanned head's skin with its mouth socket), the first crossing
enters the surface, so the nearest of its fragments faces the camera: its back faces can be left out
(``GL_CULL_FACE``) without changing a pixel, except where the depth test's rounding let a back face win at
a crease or a silhouette (one-pixel dark specks, which culling removes). A surface with a hole (a head cut
off at the neck) is closed by a cap over the hole; a ray that never meets the cap sees it as closed, and
no ray in the view meets a cap whose corners all lie beyond one plane of the view's frustum (the cap is
the hull of the hole's rim, which then lies outside too). Such a surface is drawn one-sided in a frame
whose hole rim is out of view (:func:`outside_frustum`, checked each frame), two-sided otherwise. Every
other triangle (open sheets, inward-facing surfaces) is drawn two-sided, as the shading expects.

**Still triangles.**
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
uniform uint u_base;
out uint f_id;
void main() {
    f_id = uint(gl_PrimitiveID) + u_base + 1u;
}
"""


def draw_sides(ctx, vao, cut: int, total: int, base=None, front=None) -> None:
    """Draw ``vao``'s first ``cut`` triangles one-sided (back faces culled; through ``front``, a vertex array of
    the same index buffer, if given), the rest up to ``total`` two-sided; ``base``, a uniform, is given the
    second draw's first triangle (``gl_PrimitiveID`` restarts each draw)."""
    import moderngl
    if cut:
        ctx.enable(moderngl.CULL_FACE)
        (front or vao).render(moderngl.TRIANGLES, vertices=3 * cut)
    ctx.disable(moderngl.CULL_FACE)
    if total > cut:
        if base is not None:
            base.value = cut
        vao.render(moderngl.TRIANGLES, vertices=3 * (total - cut), first=3 * cut)


def shown_triangles(ctx, mvp: np.ndarray, positions: np.ndarray, triangles: np.ndarray,
                    still: np.ndarray, size: tuple[int, int], one_sided: int = 0,
                    caps=()) -> tuple[np.ndarray, np.ndarray]:
    """The triangles to draw, in a one-sample framebuffer of ``size`` with clip matrix ``mvp``.

    Returns ((T,) bool, (len(caps),) bool): every triangle with a corner off ``still`` ((N,) bool) and each
    still triangle that shows at a pixel when the still triangles alone are drawn at ``positions`` ((N, 3)
    float32, the rest positions as the renderer writes them), the first ``one_sided`` of ``triangles``
    one-sided as the renderer draws them; and for each cap (the (k, 2) edges of a surface's hole rims,
    closed by a fan about their centre) whether no pixel of it shows among them.
    """
    import moderngl

    still_tri = still[triangles].all(axis=1)
    keep = ~still_tri
    idx = np.flatnonzero(still_tri)
    if not len(idx):
        return keep, np.zeros(len(caps), bool)
    n = len(positions)
    fans = [np.column_stack([rim, np.full(len(rim), n + i)]) for i, rim in enumerate(caps)]
    centres = [np.asarray(positions, np.float64)[np.unique(rim)].mean(0) for rim in caps]
    objects = [ctx.program(vertex_shader=_ID_VERTEX_SHADER, fragment_shader=_ID_FRAGMENT_SHADER)]
    program = objects[0]
    program["u_mvp"].write(np.asarray(mvp).T.astype("f4").tobytes())
    objects += [ctx.buffer(np.concatenate([positions, np.reshape(centres, (-1, 3))]).astype("f4").tobytes()),
                ctx.buffer(np.concatenate([triangles[idx], *fans]).astype(np.int32).tobytes())]
    objects.append(ctx.vertex_array(program, [(objects[1], "3f", "in_pos")], index_buffer=objects[2],
                                    index_element_size=4))
    objects += [ctx.renderbuffer(size, 1, dtype="u4"), ctx.depth_renderbuffer(size)]
    objects.append(ctx.framebuffer(color_attachments=[objects[4]], depth_attachment=objects[5]))
    try:
        objects[6].use()
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.front_face = "cw"       # the renderer's clip matrix flips y, and so the winding
        objects[6].clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        program["u_base"].value = 0
        draw_sides(ctx, objects[3], int((idx < one_sided).sum()), len(idx) + sum(map(len, fans)),
                   base=program["u_base"])
        ids = np.frombuffer(objects[6].read(components=1, dtype="u4"), dtype=np.uint32)
    finally:
        for o in reversed(objects):
            o.release()
    shown = np.unique(ids[ids > 0]) - 1
    keep[idx[shown[shown < len(idx)]]] = True
    fan_of = np.repeat(np.arange(len(fans)), [len(f) for f in fans])
    hidden = np.ones(len(caps), bool)
    hidden[fan_of[shown[shown >= len(idx)] - len(idx)]] = False
    return keep, hidden


def one_sided(triangles: np.ndarray, vertices: np.ndarray) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """Which triangles may be drawn one-sided (their back faces culled).

    Returns ``(closed, holed)``: (T,) bool for the triangles of closed, consistently oriented,
    outward-facing connected surfaces, and for each such surface with holes (each edge on a hole used
    once, every other edge once in each direction) a pair ((T,) bool of its triangles, its holes' rim edges
    (k, 2), as its triangles run). A surface faces out when its signed volume about its own centroid is positive
    (the triangles counter-clockwise seen from outside, as the renderer's front faces are).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    tris = np.asarray(triangles, dtype=np.int64)
    v = np.asarray(vertices, dtype=np.float64)
    n = len(v)
    edges = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    _, label = connected_components(coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])),
                                               shape=(n, n)), directed=False)
    part = label[tris[:, 0]]
    m = label.max() + 1
    directed, dcount = np.unique(edges[:, 0] * n + edges[:, 1], return_counts=True)
    reverse = np.isin(edges[:, 1] * n + edges[:, 0], directed)
    twice = np.isin(edges[:, 0] * n + edges[:, 1], directed[dcount > 1])
    # each edge of each triangle: paired with its reverse (0), on a hole (1), or used twice (2: no surface)
    kind = np.where(twice, 2, np.where(reverse, 0, 1))
    edge_part = np.tile(part, 3)
    broken = np.bincount(edge_part, weights=kind == 2, minlength=m) > 0
    holes = np.bincount(edge_part, weights=kind == 1, minlength=m) > 0
    corner = v[tris]
    centre = np.zeros((m, 3))
    np.add.at(centre, part, corner.mean(1))
    centre /= np.maximum(np.bincount(part, minlength=m), 1)[:, None]
    c = corner - centre[part][:, None, :]
    volume = np.bincount(part, weights=np.einsum("ij,ij->i", c[:, 0], np.cross(c[:, 1], c[:, 2])), minlength=m)
    good = (volume > 0) & ~broken
    closed = good[part] & ~holes[part]
    holed = [(part == p, edges[(kind == 1) & (edge_part == p)]) for p in np.flatnonzero(good & holes)]
    return closed, holed


def outside_frustum(clip: np.ndarray, points: np.ndarray) -> bool:
    """Whether ``points`` (n, 3) all lie beyond one plane of the view frustum of clip matrix ``clip``."""
    p = np.asarray(points, dtype=np.float64)
    if not len(p):
        return True
    c = np.concatenate([p, np.ones((len(p), 1))], 1) @ np.asarray(clip, dtype=np.float64).T
    w = c[:, 3]
    return bool(any((c[:, i] > w).all() or (c[:, i] < -w).all() for i in range(3)))
