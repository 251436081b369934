"""Hex8 meshing: structured boxes, quad-surface extrusion, quality checks."""

import numpy as np
import pytest

from visemeface.errors import InputError
from visemeface.physics.hexmesh import (HEX_FACES, HexMesh, box_mesh, boundary_quads, check_quality,
                                        element_quality, extrude_quads, nodal_areas, vertex_normals)


def _grid(nu=6, nv=4, radius=0.08, width=0.05, height=0.03):
    """A cylindrical patch of quads (like a cheek), counter-clockwise seen from outside (+r)."""
    ang = np.linspace(-0.4, 0.4, nu + 1)
    y = np.linspace(-height / 2, height / 2, nv + 1)
    A, Y = np.meshgrid(ang, y, indexing="xy")
    verts = np.stack([radius * np.sin(A).ravel(), Y.ravel(), radius * np.cos(A).ravel()], axis=1)
    quads = []
    for j in range(nv):
        for i in range(nu):
            a = j * (nu + 1) + i
            quads.append([a, a + 1, a + nu + 2, a + nu + 1])
    return verts, np.array(quads)


def test_box_mesh_counts_sets_and_volume():
    m = box_mesh((3, 2, 4), (0.03, 0.02, 0.04), origin=(1.0, 0.0, -0.02))
    assert (m.n_nodes, m.n_elements) == (4 * 3 * 5, 24)
    assert np.allclose(m.nodes[m.node_sets["xmin"], 0], 1.0)
    assert np.allclose(m.nodes[m.node_sets["zmax"], 2], 0.02)
    assert len(m.node_sets["surface"]) == m.n_nodes - 2 * 1 * 3  # interior nodes: 2 x 1 x 3
    q = check_quality(m)
    # Rectangular boxes: scaled Jacobian 1 and det(dx/dξ) = element volume / 8 everywhere.
    assert np.allclose(q["scaled_jacobian"], 1.0)
    assert np.isclose(8 * q["min_jacobian"].sum(), 0.03 * 0.02 * 0.04)


def test_boundary_quads_are_the_outward_skin():
    m = box_mesh((2, 2, 2), (1.0, 1.0, 1.0))
    quads = m.boundary_quads()
    assert len(quads) == 6 * 4
    p = m.nodes[quads]
    normal = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    outward = p.mean(1) - 0.5
    assert (np.einsum("qi,qi->q", normal, outward) > 0).all()
    assert np.isclose(nodal_areas(m.nodes, quads).sum(), 6.0)
    # A corner touches 3 skin quads of area 1/4, an edge node 4, a face centre 4: a quarter each.
    areas = nodal_areas(m.nodes, quads)
    face_centre = 1 + 3 * (1 + 3 * 0)                         # (1, 1, 0)
    assert np.allclose(areas[[0, 1, face_centre]], [3 / 16, 4 / 16, 4 / 16])
    assert areas[1 + 3 * (1 + 3 * 1)] == 0.0                  # the box's centre node


def test_hex_faces_are_outward_for_the_reference_cube():
    m = box_mesh()
    p = m.nodes[m.hexes[0][HEX_FACES]]
    normal = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    assert (np.einsum("qi,qi->q", normal, p.mean(1) - 0.5) > 0).all()


def test_extrusion_goes_inward_along_normals_with_positive_jacobians():
    verts, quads = _grid()
    t = 0.006
    m = extrude_quads(verts, quads, thickness=t, layers=3, material=2)
    S = len(verts)
    assert (m.n_nodes, m.n_elements) == (4 * S, 3 * len(quads))
    assert (m.material == 2).all()
    assert np.array_equal(m.node_sets["surface"], np.arange(S))
    assert np.array_equal(m.node_sets["inner"], np.arange(3 * S, 4 * S))
    assert np.array_equal(m.surface_vertices, np.arange(S))
    # Surface nodes are the vertices; inner nodes lie t deeper, toward the cylinder's axis.
    assert np.allclose(m.nodes[:S], verts)
    r = np.linalg.norm(m.nodes[:, [0, 2]], axis=1)
    assert np.allclose(r[3 * S:], 0.08 - t, atol=2e-5)
    assert (element_quality(m)["min_jacobian"] > 0).all()
    # The ζ+ face (local nodes 4..7) of the outer layer is the surface quad.
    assert np.array_equal(m.hexes[: len(quads), 4:], quads)


def test_extrusion_compacts_unused_vertices_and_takes_per_vertex_thickness():
    verts, quads = _grid(2, 1)
    extra = np.vstack([verts, [[9.0, 9.0, 9.0]]])            # a vertex on no quad
    thickness = np.linspace(0.002, 0.004, len(extra))
    m = extrude_quads(extra, quads, thickness=thickness)
    assert m.n_nodes == 2 * len(verts)
    assert np.array_equal(m.surface_vertices, np.arange(len(verts)))
    depth = np.linalg.norm(m.nodes[len(verts):] - m.nodes[: len(verts)], axis=1)
    assert np.allclose(depth, thickness[: len(verts)])


def test_extrusion_along_flipped_normals_is_refused_naming_the_element():
    verts, quads = _grid(2, 2)
    normals = -vertex_normals(verts, quads)
    with pytest.raises(InputError, match=r"element 0 \(nodes .*\) has scaled Jacobian"):
        extrude_quads(verts, quads, thickness=0.004, normals=normals)


def test_quality_check_names_inverted_and_elongated_elements():
    m = box_mesh((2, 1, 1), (0.02, 0.01, 0.01))
    bad = m.hexes.copy()
    bad[1] = bad[1][[4, 5, 6, 7, 0, 1, 2, 3]]                 # ζ swapped: inside out
    with pytest.raises(InputError, match="element 1"):
        check_quality(HexMesh(m.nodes, bad))
    flat = box_mesh((1, 1, 1), (0.03, 0.01, 0.001))
    with pytest.raises(InputError, match=r"aspect ratio 30 > 20"):
        check_quality(flat)
    assert check_quality(flat, max_aspect=None)["aspect_ratio"][0] == pytest.approx(30.0)


def test_bad_mesh_input_is_an_input_error():
    with pytest.raises(InputError, match="outside 0..7"):
        HexMesh(np.zeros((8, 3)), [[0, 1, 2, 3, 4, 5, 6, 8]])
    verts, quads = _grid(1, 1)
    with pytest.raises(InputError, match="thickness must be positive"):
        extrude_quads(verts, quads, thickness=0.0)
    with pytest.raises(InputError, match="quad vertex ids"):
        extrude_quads(verts, quads + 10, thickness=0.01)
