"""Eight-node hexahedral meshes for the TLED solver.

A :class:`HexMesh` is plain arrays: ``nodes`` (n, 3) float64 rest positions in
metres, ``hexes`` (e, 8) int64 node ids, ``material`` (e,) int64 ids into a
material table (:mod:`visemeface.physics.materials`) and ``node_sets`` (name ->
sorted int64 node ids).

Node order inside a hexahedron (NiftySim's): with local
coordinates (ξ, η, ζ) ∈ [−1, 1]³ the eight nodes sit at

=====  ====  ====  ====
node    ξ     η     ζ
=====  ====  ====  ====
0      −1    −1    −1
1      +1    −1    −1
2      +1    +1    −1
3      −1    +1    −1
4      −1    −1    +1
5      +1    −1    +1
6      +1    +1    +1
7      −1    +1    +1
=====  ====  ====  ====

so the ζ− face (0, 1, 2, 3) is counter-clockwise seen from the ζ+ side and the
Jacobian ∂x/∂ξ has a positive determinant for a well-formed element.

Two ways to make a mesh: :func:`box_mesh` (structured block, for tests and
benchmarks) and :func:`extrude_quads` (any quad surface, e.g. a ``FaceMesh``'s
``quads``, pushed inward along its vertex normals into layers of hexahedra, as
Leach & Maddock (2018) §3.1 built its face model). :func:`check_quality` refuses inverted
or degenerate elements with the element id in the message.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from visemeface.errors import InputError

#: Local coordinates (ξ, η, ζ) of the eight nodes, shape (8, 3).
NODE_SIGNS = np.array(
    [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
     [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=np.float64)

#: The six faces as local node ids, each counter-clockwise seen from outside.
HEX_FACES = np.array(
    [[0, 3, 2, 1],   # ζ−
     [4, 5, 6, 7],   # ζ+
     [0, 1, 5, 4],   # η−
     [2, 3, 7, 6],   # η+
     [0, 4, 7, 3],   # ξ−
     [1, 2, 6, 5]],  # ξ+
    dtype=np.int64)

#: The twelve edges as pairs of local node ids.
HEX_EDGES = np.array(
    [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4],
     [0, 4], [1, 5], [2, 6], [3, 7]], dtype=np.int64)


@dataclass
class HexMesh:
    """A mesh of eight-node hexahedra.

    Attributes
    ----------
    nodes : ndarray, float64 (n, 3)
        Rest positions (metres).
    hexes : ndarray, int64 (e, 8)
        Node ids in the order of the module docstring.
    material : ndarray, int64 (e,)
        Material id of each element (index into a material table).
    node_sets : dict[str, ndarray]
        Named sorted int64 node ids, e.g. ``"surface"`` and ``"inner"`` for an
        extruded mesh, ``"xmin"`` … ``"zmax"`` for a box.
    surface_vertices : ndarray or None
        For an extruded mesh: the source surface vertex of nodes 0 … S−1, the
        surface nodes (see :func:`extrude_quads`).
    """

    nodes: np.ndarray
    hexes: np.ndarray
    material: np.ndarray | None = None
    node_sets: dict = field(default_factory=dict)
    surface_vertices: np.ndarray | None = None

    def __post_init__(self):
        self.nodes = np.ascontiguousarray(self.nodes, dtype=np.float64)
        self.hexes = np.ascontiguousarray(self.hexes, dtype=np.int64)
        if self.nodes.ndim != 2 or self.nodes.shape[1] != 3:
            raise InputError(f"hex mesh nodes must have shape (n, 3), got {self.nodes.shape}")
        if self.hexes.ndim != 2 or self.hexes.shape[1] != 8:
            raise InputError(f"hex mesh elements must have shape (e, 8), got {self.hexes.shape}")
        if self.hexes.size and (self.hexes.min() < 0 or self.hexes.max() >= len(self.nodes)):
            bad = int(np.flatnonzero((self.hexes < 0).any(1) | (self.hexes >= len(self.nodes)).any(1))[0])
            raise InputError(f"element {bad} refers to node ids {self.hexes[bad].tolist()} "
                             f"outside 0..{len(self.nodes) - 1}")
        if not np.isfinite(self.nodes).all():
            bad = int(np.flatnonzero(~np.isfinite(self.nodes).all(1))[0])
            raise InputError(f"node {bad} has a non-finite position {self.nodes[bad].tolist()}")
        if self.material is None:
            self.material = np.zeros(len(self.hexes), dtype=np.int64)
        self.material = np.ascontiguousarray(self.material, dtype=np.int64)
        if self.material.shape != (len(self.hexes),):
            raise InputError(f"material ids must have shape ({len(self.hexes)},), "
                             f"got {self.material.shape}")
        self.node_sets = {k: np.unique(np.asarray(v, dtype=np.int64)) for k, v in self.node_sets.items()}

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @property
    def n_elements(self) -> int:
        return len(self.hexes)

    def boundary_quads(self) -> np.ndarray:
        """Element faces that belong to one element only: the mesh's skin.

        Returns
        -------
        ndarray, int64 (q, 4)
            Node ids of each boundary face, counter-clockwise seen from outside.
        """
        return boundary_quads(self.hexes)

    def element_centres(self) -> np.ndarray:
        """Mean of each element's eight nodes, (e, 3)."""
        return self.nodes[self.hexes].mean(axis=1)


def boundary_quads(hexes: np.ndarray) -> np.ndarray:
    """Faces of ``hexes`` (e, 8) used by exactly one element, outward oriented."""
    faces = np.asarray(hexes)[:, HEX_FACES].reshape(-1, 4)
    key = np.sort(faces, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return faces[counts[inverse.ravel()] == 1]


def nodal_areas(nodes: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """Lumped area of each node over a quad surface.

    Each (bilinear) quad gives a quarter of its area to each of its corners,
    which is exact for a uniform traction on flat quads: a total force
    ``t · area`` spread as ``t · nodal_areas``.

    Parameters
    ----------
    nodes : ndarray (n, 3)
    quads : ndarray (q, 4)

    Returns
    -------
    ndarray (n,)
        Zero for nodes on no quad.
    """
    p = np.asarray(nodes, dtype=np.float64)[np.asarray(quads)]
    # Area of a planar quad = |(p2 − p0) × (p3 − p1)| / 2.
    area = 0.5 * np.linalg.norm(np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1]), axis=1)
    out = np.zeros(len(nodes))
    np.add.at(out, np.asarray(quads).ravel(), np.repeat(area / 4.0, 4))
    return out


def box_mesh(shape=(1, 1, 1), size=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0)) -> HexMesh:
    """A structured block of ``nx × ny × nz`` equal hexahedra.

    Parameters
    ----------
    shape : (int, int, int)
        Elements along x, y, z.
    size : (float, float, float)
        Edge lengths of the block (metres).
    origin : (float, float, float)
        Position of the (xmin, ymin, zmin) corner.

    Returns
    -------
    HexMesh
        Node sets ``xmin``, ``xmax``, ``ymin``, ``ymax``, ``zmin``, ``zmax`` and
        ``surface`` (all boundary nodes). Node id = i + (nx+1)(j + (ny+1)k).

    Examples
    --------
    >>> m = box_mesh((2, 1, 1), (0.02, 0.01, 0.01))
    >>> m.n_nodes, m.n_elements
    (12, 2)
    """
    nx, ny, nz = (int(s) for s in shape)
    if min(nx, ny, nz) < 1:
        raise InputError(f"box mesh needs at least one element along each axis, got shape {shape}")
    if min(size) <= 0:
        raise InputError(f"box mesh size must be positive, got {size}")
    xs = [np.linspace(o, o + s, n + 1) for o, s, n in zip(origin, size, (nx, ny, nz))]
    X, Y, Z = np.meshgrid(*xs, indexing="ij")
    nodes = np.stack([X.ravel(order="F"), Y.ravel(order="F"), Z.ravel(order="F")], axis=1)

    def nid(i, j, k):
        return i + (nx + 1) * (j + (ny + 1) * k)

    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    i, j, k = i.ravel(order="F"), j.ravel(order="F"), k.ravel(order="F")
    di, dj, dk = ((NODE_SIGNS + 1) // 2).astype(np.int64).T
    hexes = nid(i[:, None] + di, j[:, None] + dj, k[:, None] + dk)
    ii, jj, kk = np.meshgrid(np.arange(nx + 1), np.arange(ny + 1), np.arange(nz + 1), indexing="ij")
    ii, jj, kk = ii.ravel(order="F"), jj.ravel(order="F"), kk.ravel(order="F")
    sets = {"xmin": ii == 0, "xmax": ii == nx, "ymin": jj == 0, "ymax": jj == ny,
            "zmin": kk == 0, "zmax": kk == nz}
    sets = {name: np.flatnonzero(mask) for name, mask in sets.items()}
    sets["surface"] = np.unique(np.concatenate(list(sets.values())))
    return HexMesh(nodes, hexes, node_sets=sets)


def vertex_normals(vertices: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """Area-weighted unit normals of a quad surface.

    The normal of quad (p0, p1, p2, p3) is n = (p2 − p0) × (p3 − p1) (twice its
    vector area, pointing outward for counter-clockwise quads); each vertex
    normal is the normalised sum over the quads around it.

    Returns
    -------
    ndarray (N, 3)
        Unit normals; zero rows for vertices on no quad.
    """
    v = np.asarray(vertices, dtype=np.float64)
    q = np.asarray(quads, dtype=np.int64)
    n = np.cross(v[q[:, 2]] - v[q[:, 0]], v[q[:, 3]] - v[q[:, 1]])
    acc = np.zeros_like(v)
    for c in range(4):
        np.add.at(acc, q[:, c], n)
    length = np.linalg.norm(acc, axis=1)
    out = np.zeros_like(v)
    ok = length > 0
    out[ok] = acc[ok] / length[ok, None]
    return out


def smoothed_normals(vertices, quads, iterations: int = 50) -> np.ndarray:
    """Outward unit normals averaged over the quad graph, for extrusion.

    Each pass replaces a normal by ½ (itself + the mean of its edge
    neighbours'), a diffusion that widens the curvature radius the extrusion
    sees: raw normals cross inside the lips and chin (radius < tissue depth)
    and invert elements; 50 passes keep every default-face element's scaled
    Jacobian above 0.3 at 12 mm.
    """
    import scipy.sparse as sp
    v = np.asarray(vertices, dtype=np.float64)
    q = np.asarray(quads, dtype=np.int64)
    n = vertex_normals(v, q)
    a = np.concatenate([q[:, i] for i in range(4)])
    b = np.concatenate([q[:, (i + 1) % 4] for i in range(4)])
    adj = sp.coo_matrix((np.ones(2 * len(a)), (np.r_[a, b], np.r_[b, a])), shape=(len(v), len(v))).tocsr()
    adj.data[:] = 1.0
    deg = np.maximum(np.asarray(adj.sum(axis=1)).ravel(), 1.0)
    for _ in range(int(iterations)):
        n = 0.5 * n + 0.5 * (adj @ n) / deg[:, None]
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, norm, out=np.zeros_like(n), where=norm > 0)


def smooth_on_quads(values, quads, passes: int) -> np.ndarray:
    """Average a per-vertex value with its quad-edge neighbours ``passes`` times."""
    v = np.asarray(values, dtype=np.float64).copy()
    q = np.asarray(quads)
    a = np.concatenate([q[:, i] for i in range(4)])
    b = np.concatenate([q[:, (i + 1) % 4] for i in range(4)])
    for _ in range(passes):
        acc = np.zeros_like(v)
        cnt = np.zeros_like(v)
        np.add.at(acc, a, v[b])
        np.add.at(cnt, a, 1.0)
        used = cnt > 0
        v[used] = 0.5 * v[used] + 0.5 * acc[used] / cnt[used]
    return v


def extrude_quads(vertices, quads, thickness, layers: int = 1, material=0, normals=None,
                  check: bool = True) -> HexMesh:
    """Extrude a quad surface inward along its vertex normals into hexahedra.

    Layer ``L = 0 … layers`` of node positions is ``p − (L / layers) · t · n``
    with ``n`` the outward vertex normal and ``t`` the thickness; between
    layers ``L + 1`` (ζ−, inner) and ``L`` (ζ+, outer) each quad (q0, q1, q2, q3)
    becomes the hexahedron ``[inner q0..q3, outer q0..q3]``. Because the quads
    are counter-clockwise seen from outside, the ζ− face is counter-clockwise
    seen from the ζ+ side and the element has a positive Jacobian.

    Parameters
    ----------
    vertices : array (N, 3)
        Surface positions (metres).
    quads : int array (Q, 4)
        Counter-clockwise seen from outside (``FaceMesh.quads``).
    thickness : float or array (N,)
        Total extrusion depth (metres), per vertex if an array.
    layers : int
        Number of element layers through the thickness.
    material : int or int array (Q,)
        Material id of the elements of each quad (same through all layers).
    normals : array (N, 3), optional
        Outward unit normals; default :func:`vertex_normals`.
    check : bool
        Run :func:`check_quality` (positive Jacobians) on the result.

    Returns
    -------
    HexMesh
        ``layers · Q`` elements, the elements of layer L (outermost L = 0)
        at ids ``L·Q … (L+1)·Q − 1``, element ``L·Q + i`` from quad ``i``.
        Only vertices used by a quad are extruded. Node sets: ``surface``
        (layer 0) and ``inner`` (the bone side, last layer).
        ``surface_vertices`` gives the source vertex of nodes 0 … S−1, which
        are the surface nodes (node ``L·S + s`` lies under node ``s``).
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    quads = np.asarray(quads, dtype=np.int64)
    layers = int(layers)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise InputError(f"surface vertices must have shape (N, 3), got {vertices.shape}")
    if quads.ndim != 2 or quads.shape[1] != 4 or len(quads) == 0:
        raise InputError(f"surface quads must have shape (Q, 4) with Q > 0, got {quads.shape}")
    if quads.min() < 0 or quads.max() >= len(vertices):
        raise InputError(f"quad vertex ids must lie in 0..{len(vertices) - 1}, "
                         f"got {quads.min()}..{quads.max()}")
    if layers < 1:
        raise InputError(f"extrusion needs at least one layer, got {layers}")
    t = np.broadcast_to(np.asarray(thickness, dtype=np.float64), (len(vertices),))
    used = np.unique(quads)
    if not (t[used] > 0).all():
        bad = int(used[np.flatnonzero(~(t[used] > 0))[0]])
        raise InputError(f"extrusion thickness must be positive; vertex {bad} has {t[bad]}")
    if normals is None:
        normals = vertex_normals(vertices, quads)
    normals = np.asarray(normals, dtype=np.float64)
    remap = np.full(len(vertices), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    surf = vertices[used]
    depth = (t[used, None] * normals[used])
    S = len(used)
    nodes = np.concatenate([surf - (L / layers) * depth for L in range(layers + 1)])
    q = remap[quads]
    hexes = np.concatenate([np.concatenate([q + (L + 1) * S, q + L * S], axis=1)
                            for L in range(layers)])
    mat = np.broadcast_to(np.asarray(material, dtype=np.int64), (len(quads),))
    mesh = HexMesh(nodes, hexes, material=np.tile(mat, layers),
                   node_sets={"surface": np.arange(S), "inner": np.arange(layers * S, (layers + 1) * S)},
                   surface_vertices=used)
    if check:
        check_quality(mesh, max_aspect=None)
    return mesh


def _jacobians(nodes: np.ndarray, hexes: np.ndarray, points: np.ndarray) -> np.ndarray:
    """∂x/∂ξ at local ``points`` (p, 3) for every element: (e, p, 3, 3)."""
    x = nodes[hexes]                                           # (e, 8, 3)
    s = NODE_SIGNS
    # ∂N_a/∂ξ_k at each point: (p, 8, 3); N_a = Π_k (1 + s_ak ξ_k) / 8.
    fac = 1.0 + s[None, :, :] * points[:, None, :]              # (p, 8, 3)
    dN = np.empty((len(points), 8, 3))
    for k in range(3):
        others = [m for m in range(3) if m != k]
        dN[:, :, k] = s[None, :, k] * fac[:, :, others[0]] * fac[:, :, others[1]] / 8.0
    return np.einsum("eai,pak->epik", x, dN)


def element_quality(mesh: HexMesh) -> dict:
    """Per-element quality measures.

    Returns
    -------
    dict of ndarray (e,)
        ``min_jacobian``: smallest det(∂x/∂ξ) over the eight corners and the
        centre; ``scaled_jacobian``: that value divided by the product of the
        three edge lengths at the worst corner (1 for a rectangular box, ≤ 0
        for an inverted element); ``aspect_ratio``: longest / shortest edge.
    """
    pts = np.vstack([NODE_SIGNS, np.zeros((1, 3))])
    Jm = _jacobians(mesh.nodes, mesh.hexes, pts)
    det = np.linalg.det(Jm)                                    # (e, 9)
    cols = np.linalg.norm(Jm, axis=2)                           # (e, 9, 3) column norms
    scaled = det / np.maximum(np.prod(cols, axis=2), np.finfo(float).tiny)
    x = mesh.nodes[mesh.hexes]
    edges = np.linalg.norm(x[:, HEX_EDGES[:, 1]] - x[:, HEX_EDGES[:, 0]], axis=2)
    with np.errstate(divide="ignore"):
        aspect = edges.max(1) / edges.min(1)
    return {"min_jacobian": det.min(1), "scaled_jacobian": scaled.min(1), "aspect_ratio": aspect}


def check_quality(mesh: HexMesh, max_aspect: float | None = 20.0, min_scaled_jacobian: float = 0.0) -> dict:
    """Refuse inverted, degenerate or (optionally) too elongated elements.

    Parameters
    ----------
    mesh : HexMesh
    max_aspect : float or None
        Largest allowed ratio of longest to shortest edge; None skips the test
        (thin saliva layers are meant to be flat).
    min_scaled_jacobian : float
        Every element's scaled Jacobian (see :func:`element_quality`) must
        exceed this at all corners and the centre.

    Returns
    -------
    dict
        :func:`element_quality`'s arrays, when the mesh passes.

    Raises
    ------
    InputError
        Naming the first bad element, its node ids and the offending value.
    """
    q = element_quality(mesh)
    bad = np.flatnonzero(~(q["scaled_jacobian"] > min_scaled_jacobian))
    if len(bad):
        e = int(bad[0])
        raise InputError(
            f"{len(bad)} hex element(s) inverted or degenerate; first: element {e} "
            f"(nodes {mesh.hexes[e].tolist()}) has scaled Jacobian {q['scaled_jacobian'][e]:.3g} "
            f"<= {min_scaled_jacobian:g} (node order must be NiftySim's: nodes 0-3 one face, counter-clockwise seen from the opposite face, "
            f"nodes 4-7 that opposite face in the same order)")
    if max_aspect is not None:
        bad = np.flatnonzero(~(q["aspect_ratio"] <= max_aspect))
        if len(bad):
            e = int(bad[np.argmax(q["aspect_ratio"][bad])])
            raise InputError(
                f"{len(bad)} hex element(s) too elongated; worst: element {e} "
                f"(nodes {mesh.hexes[e].tolist()}) has aspect ratio {q['aspect_ratio'][e]:.3g} "
                f"> {max_aspect:g}")
    return q


def first_touch_order(hexes, n_nodes: int) -> np.ndarray:
    """Nodes in the order the elements first touch them (then any node no element uses): new → old ids.

    Numbered so, the nodes a contiguous run of elements uses are themselves nearly contiguous, so a
    thread that computes a block of elements also gathers and steps the nodes they load (the TLED
    solver's threaded step: on an extruded sheet numbered layer by layer every thread otherwise reads
    forces the other wrote, 2 threads ran 1.66x faster than one; numbered so, 1.98x).
    """
    flat = np.asarray(hexes, dtype=np.int64).ravel()
    _, first = np.unique(flat, return_index=True)          # first slot that touches each used node
    used = flat[np.sort(first)]
    rest = np.setdiff1d(np.arange(n_nodes), used)
    return np.concatenate([used, rest]).astype(np.int64)
