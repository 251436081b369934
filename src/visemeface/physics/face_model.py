"""The FEM face: the lower face extruded into hexahedra, with a saliva layer between the lips.

Leach & Maddock (2018) §3.1 built its model by extruding the quads of a face surface into
hex8 elements and marking a thin saliva layer between the lips. Here, from any
:class:`~visemeface.face.mesh.FaceMesh` with regions and landmarks:

* **Tissue.** The quads of the lower face (lips, cheeks, chin, up to below the
  eyes; not the mouth cavity, eyes or nose) are extruded inward along their
  (smoothed) vertex normals (:func:`visemeface.physics.hexmesh.extrude_quads`),
  default 12 mm in two layers: a 1.5 mm front layer and the rest. Material id
  0 (soft tissue).
* **Bone.** The inner (bone-side) nodes are the skull, held fixed, except
  those under the ``jaw`` region, which the jaw rotation moves (prescribed).
* **Saliva.** The lip seams (``lip_seam_upper``/``lip_seam_lower``) are
  paired by position across the mouth; between two neighbouring pairs one
  hexahedron per tissue layer bridges the rest gap from the lower to the
  upper lip: node order (ξ along the seam toward the subject's left, η from
  the lower lip up, ζ from the bone side out), so the element's local y axis
  runs across the lips. Material id 1 (saliva). The gap comes from the face
  (``default_face(rest_gap=...)``) and must be wide enough for the stable
  time step (the saliva's wave speed is ~14 m/s: 0.3 mm allows 1e-5 s).

The model also knows where the lips are, so it measures the opening from the
mesh (:func:`seam_openings`) and draws the rest gap (the saliva film) closed
(:meth:`FEMFace.display_vertices`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from visemeface.errors import InputError
from visemeface.face.mesh import FaceMesh
from visemeface.physics.hexmesh import HexMesh, check_quality, extrude_quads
from visemeface.physics.hexmesh import smooth_on_quads as _smooth_on_quads
from visemeface.physics.hexmesh import smoothed_normals
from visemeface.physics.bone import relax_bone_side
from visemeface.physics.openings import seam_openings  # noqa: F401  (re-exported)

TISSUE = 0
SALIVA = 1
#: Default tissue depth (m) and layers (seed: 10-15 mm of soft tissue).
TISSUE_THICKNESS = 0.012
LAYERS = 2
#: Depth (m) of the saliva layer: the front band where the lips touch. The
#: first tissue layer is this deep; the saliva bridges only it.
SALIVA_DEPTH = 0.001
#: Depth (m) of the tissue under the lips: their bone side is the teeth and
#: gums, closer than the cheeks' and chin's.
LIP_THICKNESS = 0.004
#: Smoothing passes of the lips' depth into the cheeks' (element shape at the mouth corners).
DEPTH_SMOOTHING = 2
#: Default rest gap between the lips that the saliva fills (m).
REST_GAP = 0.001
#: Regions the FEM needs: the bone side under ``jaw`` turns with the mandible; the saliva bridges the seams.
PHYSICS_REGIONS = ("jaw", "lip_seam_upper", "lip_seam_lower")
#: Regions never part of the FEM (they stay kinematic).
EXCLUDED_REGIONS = ("mouth_cavity", "eyes", "brow", "nose")
#: Normal-smoothing passes before extrusion (lips and chin curve tighter than 12 mm).
NORMAL_SMOOTHING = 50


@dataclass
class FEMFace:
    """A FaceMesh's lower face as a hex mesh with a saliva layer.

    Attributes
    ----------
    face : FaceMesh
    mesh : HexMesh
        Material 0 tissue, 1 saliva; node sets ``surface``, ``inner``,
        ``fixed``, ``jaw``.
    surface_vertices : (S,) int
        Face vertex of surface node ``s`` (node ``L·S + s`` lies ``L`` layers
        under it).
    layers : int
    saliva : (E,) int
        Element ids of the saliva elements.
    saliva_pairs : (E, 2) int
        The two seam pairs (indices into ``seam_pairs``) each saliva element bridges.
    saliva_s : (E,) float
        Element centre across the mouth: −1 right corner, 0 centre, +1 left corner.
    seam_pairs : (P, 2) int
        Face vertices (upper, lower) of the lip seams, ordered from the
        subject's right corner to the left.
    seam_s : (P,) float
        Each pair's position across the mouth (as ``saliva_s``).
    mouth_width : float
        Corner-to-corner distance at rest (m).
    depth_fraction : (layers + 1, S) float
        Depth of each node layer under each surface node, as a fraction of
        the tissue depth there (0 at the skin, 1 at the bone side).
    lip_weight : (S,) float
        1 under the lips, 0 away from them, blended over two rings: where the
        bone side is the lips' own muscle layer rather than skull or jaw.
    corner_hexes : (C, 8) int
        The saliva between the last seam pair and each mouth corner, where the lips
        meet: wedges (the corner's two nodes are one), for the film alone
        (:class:`~visemeface.physics.film.SalivaFilm`), not the mesh; ``corner_s`` (C, 2)
        their ξ− and ξ+ faces across the mouth.
    """

    face: FaceMesh
    mesh: HexMesh
    surface_vertices: np.ndarray
    layers: int
    saliva: np.ndarray
    saliva_pairs: np.ndarray
    saliva_s: np.ndarray
    seam_pairs: np.ndarray
    seam_s: np.ndarray
    mouth_width: float
    depth_fraction: np.ndarray | None = None
    lip_weight: np.ndarray | None = None
    corner_hexes: np.ndarray | None = None
    corner_s: np.ndarray | None = None

    @property
    def n_surface(self) -> int:
        return len(self.surface_vertices)

    @property
    def tissue(self) -> np.ndarray:
        return np.flatnonzero(self.mesh.material == TISSUE)

    def counts(self) -> dict:
        """Node and element counts (Leach & Maddock 2018: 6,982 nodes, 3,414 hexahedra)."""
        return {"nodes": int(self.mesh.n_nodes), "elements": int(self.mesh.n_elements),
                "tissue": int(len(self.tissue)), "saliva": int(len(self.saliva)),
                "fixed_nodes": int(len(self.mesh.node_sets["fixed"])),
                "jaw_nodes": int(len(self.mesh.node_sets["jaw"]))}

    def surface(self, u, base=None) -> np.ndarray:
        """Face vertex positions (N, 3): ``base`` (default rest) with the FEM surface moved by ``u``.

        ``u`` is the node displacement (n, 3); vertices outside the FEM keep
        ``base`` (the kinematic pose, for brows and eyes).
        """
        v = np.array(self.face.vertices if base is None else base, dtype=np.float64, copy=True)
        S = self.n_surface
        v[self.surface_vertices] = self.mesh.nodes[:S] + np.asarray(u)[:S]
        return v

    def seam_gaps(self, vertices) -> np.ndarray:
        """Distance (m) between each paired upper and lower seam vertex, (P,)."""
        v = np.asarray(vertices)
        return np.linalg.norm(v[self.seam_pairs[:, 0]] - v[self.seam_pairs[:, 1]], axis=1)

    def display_vertices(self, vertices, rest_gaps=None) -> np.ndarray:
        """Vertices to render: each lip-seam pair drawn ``rest gap`` closer together.

        The rest gap is the saliva film (and numerical room for the saliva
        elements), not an opening: drawn gap = max(gap − rest gap, 0) about the
        pair's midpoint, so lips at rest or held by saliva look closed and an
        opening shows exactly the separation beyond the film.
        """
        v = np.array(vertices, dtype=np.float64, copy=True)
        if rest_gaps is None:
            rest_gaps = self.rest_gaps
        up, lo = self.seam_pairs[:, 0], self.seam_pairs[:, 1]
        d = v[up] - v[lo]
        g = np.linalg.norm(d, axis=1)
        mid = 0.5 * (v[up] + v[lo])
        unit = d / np.maximum(g, 1e-12)[:, None]
        half = 0.5 * np.maximum(g - rest_gaps, 0.0)[:, None]
        v[up] = mid + half * unit
        v[lo] = mid - half * unit
        return v

    @property
    def rest_gaps(self) -> np.ndarray:
        return self.seam_gaps(self.face.vertices)


def seam_pairs(face: FaceMesh) -> np.ndarray:
    """Pair the upper and lower lip-seam vertices across the mouth.

    Each upper seam vertex is paired with the lower seam vertex nearest to it
    along the mouth axis (corner to corner); pairs are returned ordered from
    the subject's right corner to the left, shared corner vertices dropped.

    Returns
    -------
    (P, 2) int array of face vertex ids (upper, lower).
    """
    up, lo = face.region("lip_seam_upper"), face.region("lip_seam_lower")
    if len(up) < 2 or len(lo) < 2:
        raise InputError(f"the face's lip seams are too short to hold saliva "
                         f"({len(up)} upper, {len(lo)} lower vertices)")
    axis, origin = _mouth_axis(face)
    xu = (face.vertices[up] - origin) @ axis
    xl = (face.vertices[lo] - origin) @ axis
    order_u, order_l = np.argsort(xu), np.argsort(xl)
    up, xu, lo, xl = up[order_u], xu[order_u], lo[order_l], xl[order_l]
    if len(up) == len(lo):
        pairs = np.stack([up, lo], axis=1)
    else:
        nearest = np.abs(xl[None, :] - xu[:, None]).argmin(axis=1)
        pairs = np.stack([up, lo[nearest]], axis=1)
    return pairs[pairs[:, 0] != pairs[:, 1]]


def _mouth_axis(face: FaceMesh):
    left = face.landmark_position("mouth_corner_left")
    right = face.landmark_position("mouth_corner_right")
    axis = left - right
    width = float(np.linalg.norm(axis))
    if not width > 0:
        raise InputError("the mouth corners coincide; cannot place the saliva layer")
    return axis / width, 0.5 * (left + right)


def fem_quads(face: FaceMesh, top: float | None = None, nose_radius: float | None = None,
              back: float | None = None) -> np.ndarray:
    """Mask of the face quads that become tissue: the lower face below the eyes.

    Parameters
    ----------
    top : float, optional
        Height (y, m) every vertex of a quad must be under; default halfway
        between the nose tip and the eye centres.
    nose_radius : float, optional
        Quads with a vertex closer than this to the nose tip (in the x-y plane,
        above the upper lip's top) are left out: the nose is too thin to
        extrude 12 mm inward. Default 0.4 mouth widths; 0 when the face has a
        ``nose`` region (which is left out instead).
    back : float, optional
        Quads with a vertex further back than this (z, m) are left out (the
        sides of the head and under the chin). Default −1 mouth width.
    """
    v = face.vertices
    width = float(np.linalg.norm(face.landmark_position("mouth_corner_left")
                                 - face.landmark_position("mouth_corner_right")))
    if top is None:
        eye_y = 0.5 * (face.landmark_position("eye_centre_left")[1] + face.landmark_position("eye_centre_right")[1])
        top = 0.5 * (eye_y + face.landmark_position("nose_tip")[1])
    if nose_radius is None:
        nose_radius = 0.0 if "nose" in face.regions else 0.4 * width
    if back is None:
        back = -width
    excluded = np.zeros(face.n_vertices, dtype=bool)
    for name in EXCLUDED_REGIONS:
        if name in face.regions:
            excluded[face.regions[name]] = True
    nose = face.landmark_position("nose_tip")
    lip_top = face.landmark_position("upper_lip_top")[1]
    near_nose = (np.hypot(v[:, 0] - nose[0], v[:, 1] - nose[1]) < nose_radius) & (v[:, 1] > lip_top)
    bad = excluded | near_nose | (v[:, 1] > top) | (v[:, 2] < back)
    return ~bad[face.quads].any(axis=1)


def build_fem_face(face: FaceMesh, thickness: float = TISSUE_THICKNESS, layers: int = LAYERS,
                   top: float | None = None, saliva_gap: float | None = REST_GAP,
                   saliva_depth: float | None = SALIVA_DEPTH, lip_thickness: float | None = LIP_THICKNESS,
                   min_gap: float = 3e-4, seam_elements: int | None = None) -> FEMFace:
    """Extrude the lower face into hexahedra and bridge the lips with saliva elements.

    Parameters
    ----------
    face : FaceMesh
        Needs the regions ``lip_seam_upper``, ``lip_seam_lower`` and ``jaw``
        and the landmarks of docs/conventions.md.
    thickness : float
        Tissue depth (m).
    layers : int
        Element layers through the depth.
    top : float, optional
        See :func:`fem_quads`.
    saliva_gap : float or None
        Rest thickness (m) of the saliva layer. The seam pairs are moved apart
        symmetrically (along +y) to this uniform gap, so every saliva element
        has the same thickness, as Leach & Maddock's (2018) breaking rule assumes ("all the
        elements being the same thickness", §3.4.3); a face with closed lips
        (``rest_gap=0``) works too. None keeps the face's own gaps and drops
        pairs thinner than ``min_gap``. The model's ``face`` is the re-gapped
        copy; :meth:`FEMFace.display_vertices` draws the gap closed.
    lip_thickness : float or None
        Tissue depth under the ``upper_lip``/``lower_lip`` regions (blended
        into ``thickness`` over two rings of neighbours). Thin lips anchored
        to the teeth let the jaw pull the centre of the seam hardest, so the
        saliva fails there first; with lips as deep as the cheeks the upper
        lip follows the lower one at the centre and the seam fails from the
        corners (measured, see scripts/sticky_figures.py). None: uniform.
    saliva_depth : float or None
        With two or more layers, the first layer is this deep (the rest share
        the remaining depth evenly) and the saliva bridges the lips over this
        front band only. The band matters: the saliva (P-wave modulus
        K + 4μ/3 ≈ 200 kPa, breaking at 4 % stretch with glue 0.08) holds
        ≈ 8 kPa, ten times what soft tissue (μ = 800 Pa) carries at
        moderate strain, so saliva as deep as the lips would never let go;
        a shallow band is the real contact zone of the wet lips. None: all
        layers equal and saliva through the full depth.
    min_gap : float
        Smallest rest gap (m) accepted between paired seam vertices: thinner
        saliva would force a time step under Leach & Maddock's (2018) 1e-5 s.
    seam_elements : int or None
        At least this many tissue elements along the lip seam
        (:func:`visemeface.face.refine.refine_lip_seam`: the quad strips across the seam split,
        conformingly), their extrusion (normals, depth, lip weight) interpolated from the
        unsplit face's so the tissue is the same, only finer along the mouth. The model's
        ``face`` is the refined one; a rig for it is ``MuscleRig.from_file(refine_lip_seam(face, n))``.
        Simulate it with ``PhysicsSettings(multirate=False)``: at the multi-rate step a fast /uw/ inverted
        a lip element holding a film node (measured, README).

    Returns
    -------
    FEMFace
    """
    if not (np.isfinite(thickness) and thickness > 0):
        raise InputError(f"tissue thickness must be > 0, got {thickness}")
    _check_regions(face)
    mask = fem_quads(face, top=top)
    quads = face.quads[mask]
    pairs = seam_pairs(face)
    if saliva_gap is not None:
        face = _regap(face, pairs, saliva_gap, min_gap)
    used = np.unique(quads)
    missing = np.setdiff1d(pairs.ravel(), used)
    if len(missing):
        raise InputError(f"lip seam vertex {int(missing[0])} is on no tissue quad of the lower face")
    pairs = _gapped_pairs(face, pairs, min_gap)
    tissue, depth_fraction, lip_w = _tissue(face, quads, pairs, thickness, layers, lip_thickness, saliva_depth)
    S = len(tissue.surface_vertices)
    if seam_elements is not None:
        face, tissue, depth_fraction, lip_w = _refined(face, mask, tissue, depth_fraction, lip_w, seam_elements)
        pairs, S = _gapped_pairs(face, seam_pairs(face), min_gap), len(tissue.surface_vertices)
    saliva_layers = 1 if (saliva_depth is not None and layers >= 2) else layers
    node_of = np.full(face.n_vertices, -1, dtype=np.int64)
    node_of[tissue.surface_vertices] = np.arange(S)

    axis, origin = _mouth_axis(face)
    width = float(np.linalg.norm(face.landmark_position("mouth_corner_left")
                                 - face.landmark_position("mouth_corner_right")))
    seam_s = ((face.vertices[pairs] - origin) @ axis).mean(axis=1) / (0.5 * width)
    a = np.arange(len(pairs) - 1)
    b = a + 1
    sal = _saliva_hexes(node_of[pairs[:, 0]], node_of[pairs[:, 1]], S, saliva_layers)
    hexes = np.concatenate([tissue.hexes, sal])
    material = np.concatenate([tissue.material, np.full(len(sal), SALIVA)])

    mesh = HexMesh(tissue.nodes, hexes, material=material, node_sets=_bone_sets(face, tissue, layers),
                   surface_vertices=tissue.surface_vertices)
    check_quality(mesh, max_aspect=None)
    saliva = np.arange(len(tissue.hexes), len(hexes))
    corners, corner_s = _corner_wedges(face, pairs, node_of, seam_s, S, saliva_layers)
    return FEMFace(face=face, mesh=mesh, surface_vertices=tissue.surface_vertices, layers=layers,
                   saliva=saliva, saliva_pairs=np.tile(np.stack([a, b], axis=1), (saliva_layers, 1)),
                   saliva_s=np.tile(0.5 * (seam_s[a] + seam_s[b]), saliva_layers),
                   seam_pairs=pairs, seam_s=seam_s, mouth_width=width,
                   depth_fraction=depth_fraction, lip_weight=lip_w,
                   corner_hexes=corners, corner_s=corner_s)


def _check_regions(face: FaceMesh) -> None:
    missing = [n for n in PHYSICS_REGIONS if n not in face.regions]
    if missing:
        raise InputError(f"this face has no {' or '.join(repr(n) for n in missing)} region, which the physical "
                         "face needs (the skin the mandible carries and the lips' contact); the physics runs on "
                         "the procedural face and on meshes whose landmarks file names these regions; "
                         "--physics none animates any face")


def _tissue(face: FaceMesh, quads, pairs, thickness, layers: int, lip_thickness, saliva_depth):
    """The extruded tissue (bone side relaxed), its depth fractions and lip weight per surface node."""
    # Paired seam vertices share one extrusion direction so each saliva element is a slab.
    normals = smoothed_normals(face.vertices, quads, NORMAL_SMOOTHING)
    common = normals[pairs[:, 0]] + normals[pairs[:, 1]]
    common /= np.linalg.norm(common, axis=1, keepdims=True)
    normals[pairs[:, 0]] = common
    normals[pairs[:, 1]] = common
    depth, lip_w = _lip_depth(face, quads, thickness, lip_thickness)
    tissue = extrude_quads(face.vertices, quads, depth, layers=layers, material=TISSUE, normals=normals,
                           check=False)
    depth_fraction = _layer_nodes(tissue, normals, depth, layers, saliva_depth)
    if layers >= 2:
        tissue.nodes = relax_bone_side(tissue.nodes, tissue.hexes, len(tissue.surface_vertices), layers)
    return tissue, depth_fraction, lip_w[tissue.surface_vertices]


def _refined(face: FaceMesh, mask, tissue, depth_fraction, lip_w, elements: int):
    """The face refined along the lip seam (:func:`~visemeface.face.refine.lip_refinement`) and its tissue:
    every node layer, depth fraction and lip weight interpolated from the unsplit tissue's, so each new
    hexahedron is exactly a slice of an old one (the trilinear map restricted)."""
    from visemeface.face.refine import lip_refinement
    fine, P, parent = lip_refinement(face, elements)
    quads = fine.quads[mask[parent]]
    layers = len(depth_fraction) - 1
    out = extrude_quads(fine.vertices, quads, 1.0, layers=layers, material=TISSUE, check=False)
    Ps = P[out.surface_vertices][:, tissue.surface_vertices]
    if Ps.shape[0] and np.any(np.abs(np.asarray(Ps.sum(axis=1)).ravel() - 1.0) > 1e-9):
        raise InputError("a refined lip vertex lies on an edge outside the face's tissue")
    S = len(tissue.surface_vertices)
    out.nodes = np.concatenate([Ps @ tissue.nodes[L * S:(L + 1) * S] for L in range(layers + 1)])
    return fine, out, np.stack([Ps @ d for d in depth_fraction]), Ps @ lip_w


def _corner_wedges(face: FaceMesh, pairs, node_of, seam_s, S: int, layers: int):
    """Saliva wedges from the end seam pairs into the mouth corners (where the seams meet), per layer."""
    hexes, ends = [], []
    for name, end, sign in (("mouth_corner_right", 0, -1.0), ("mouth_corner_left", -1, 1.0)):
        c = face.landmarks.get(name)
        if c is None or node_of[c] < 0 or not (np.isin(c, face.region("lip_seam_upper"))
                                               and np.isin(c, face.region("lip_seam_lower"))):
            continue
        up, lo = node_of[[c, pairs[end, 0]]], node_of[[c, pairs[end, 1]]]
        if sign > 0:
            up, lo = up[::-1], lo[::-1]
        hexes.append(_saliva_hexes(up, lo, S, layers))
        ends.append(np.tile(sorted([sign, seam_s[end]]), (layers, 1)))
    if not hexes:
        return np.zeros((0, 8), np.int64), np.zeros((0, 2))
    return np.concatenate(hexes), np.concatenate(ends)


def _gapped_pairs(face: FaceMesh, pairs, min_gap: float) -> np.ndarray:
    """The seam pairs at least ``min_gap`` apart: toward the corners the lips meet, and
    saliva thinner than that would force a smaller time step."""
    gaps = np.linalg.norm(face.vertices[pairs[:, 0]] - face.vertices[pairs[:, 1]], axis=1)
    keep = gaps >= min_gap
    if keep.sum() < 2:
        raise InputError(f"rest gap between the lips is {gaps.max() * 1e3:.3g} mm at most, "
                         f"< {min_gap * 1e3:.3g} mm: too thin for saliva elements at dt 1e-5 s; "
                         f"build the face with a rest gap (default_face(rest_gap={REST_GAP}))")
    return pairs[keep]


def _layer_nodes(tissue, normals, depth, layers: int, saliva_depth) -> np.ndarray:
    """Place the node layers (the first ``saliva_depth`` deep) in place; their depth fractions (layers + 1, S)."""
    S = len(tissue.surface_vertices)
    t_s = depth[tissue.surface_vertices][:, None]
    if saliva_depth is None or layers < 2:
        return np.repeat(np.linspace(0.0, 1.0, layers + 1)[:, None], S, axis=1)
    if not (0 < saliva_depth < t_s.min()):
        raise InputError(f"saliva depth must be in (0, {t_s.min() * 1e3:.3g} mm), got {saliva_depth * 1e3:.3g} mm")
    surf, n = tissue.nodes[:S], normals[tissue.surface_vertices]
    fr = [np.zeros_like(t_s), np.full_like(t_s, saliva_depth)] + \
         [saliva_depth + (t_s - saliva_depth) * k / (layers - 1) for k in range(1, layers)]
    tissue.nodes = np.concatenate([surf - d * n for d in fr])
    return np.stack([d[:, 0] for d in fr]) / t_s[:, 0]


def _bone_sets(face: FaceMesh, tissue, layers: int) -> dict:
    """The tissue's node sets plus ``jaw`` (bone side under the jaw region) and ``fixed`` (the rest)."""
    S = len(tissue.surface_vertices)
    bone = tissue.node_sets["inner"]
    jaw_vertices = np.zeros(face.n_vertices, dtype=bool)
    jaw_vertices[face.region("jaw")] = True
    on_jaw = jaw_vertices[tissue.surface_vertices[bone - layers * S]]
    return {**tissue.node_sets, "jaw": bone[on_jaw], "fixed": bone[~on_jaw]}


def _regap(face: FaceMesh, pairs, saliva_gap: float, min_gap: float) -> FaceMesh:
    """A copy of ``face`` with each seam pair moved apart (along y) to the uniform ``saliva_gap``."""
    if not (np.isfinite(saliva_gap) and saliva_gap >= min_gap):
        raise InputError(f"saliva gap must be >= {min_gap * 1e3:.3g} mm for a stable 1e-5 s step, "
                         f"got {saliva_gap * 1e3:.3g} mm")
    v = face.vertices.copy()
    mid = 0.5 * (v[pairs[:, 0]] + v[pairs[:, 1]])
    v[pairs[:, 0]] = mid + [0.0, 0.5 * saliva_gap, 0.0]
    v[pairs[:, 1]] = mid - [0.0, 0.5 * saliva_gap, 0.0]
    return FaceMesh(v, face.quads, face.tris, dict(face.regions), dict(face.landmarks), face.colors)


def _lip_depth(face: FaceMesh, quads, thickness: float, lip_thickness):
    """Tissue depth per face vertex and the lip weight (1 under the lips, blended over two rings)."""
    depth = np.full(face.n_vertices, float(thickness))
    lip_w = np.zeros(face.n_vertices)
    if lip_thickness is None:
        return depth, lip_w
    if not (np.isfinite(lip_thickness) and lip_thickness > 0):
        raise InputError(f"lip thickness must be > 0, got {lip_thickness}")
    lips = np.zeros(face.n_vertices, dtype=bool)
    for name in ("upper_lip", "lower_lip"):
        if name in face.regions:
            lips[face.regions[name]] = True
    lip_w = _smooth_on_quads(lips.astype(np.float64), quads, passes=2)
    # The depth changes three-fold from lips to cheeks: spread that change over
    # more elements than the lip weight, or the mouth corners' deep hexahedra
    # come out nearly flat (scaled Jacobian ~0.05) and invert on wide openings.
    depth_w = _smooth_on_quads(lips.astype(np.float64), quads, passes=DEPTH_SMOOTHING)
    return thickness + (lip_thickness - thickness) * depth_w, lip_w


def _saliva_hexes(up, lo, S: int, layers: int) -> np.ndarray:
    """Saliva hexahedra between neighbouring seam pairs (surface node ids ``up``/``lo``), per layer.

    Node order (ξ along the seam toward the subject's left, η from the lower lip
    up, ζ from the bone side out).
    """
    a = np.arange(len(up) - 1)
    b = a + 1
    sal = []
    for L in range(layers):
        inner, outer = (L + 1) * S, L * S
        sal.append(np.stack([lo[a] + inner, lo[b] + inner, up[b] + inner, up[a] + inner,
                             lo[a] + outer, lo[b] + outer, up[b] + outer, up[a] + outer], axis=1))
    return np.concatenate(sal)
