r"""Headless OpenGL rendering of a face (moderngl, EGL, Mesa llvmpipe: no display, no GPU).

One :class:`Renderer` keeps one GL context, one vertex buffer (positions and
normals, rewritten with ``vbo.write`` each frame), a static colour buffer and
an index buffer. Each frame recomputes smooth vertex normals from the posed
positions (:class:`visemeface.face.normals.NormalAccumulator`), draws into a
multisampled framebuffer, resolves it and reads RGB back. Given the vertices
a caller's frames leave at rest (``still``), a renderer without MSAA leaves out
the still triangles no pixel shows, and every renderer draws closed, outward-facing
surfaces (teeth, eyeballs, a scanned head's skin) one-sided
(:mod:`visemeface.render.culling`): the same image, in about half the time on
the ICT head.

Camera
------
Views look at the face from the front (``face``: whole face; ``mouth``: the
mouth region, for the opening analysis) or from 35° toward the subject's left
(``three-quarter``). Perspective cameras use a vertical field of view of
:math:`\theta = 18°` at distance :math:`d = r / \tan(\theta/2)` for a framed
half-height :math:`r`; orthographic ones frame the same half-height. Pixel
coordinates of a point :math:`p`: :math:`c = P V p`, :math:`u = (c_x/c_w + 1)
W/2`, :math:`v = (1 - c_y/c_w) H/2` (row 0 at the top).

Shading
-------
Two directional lights and ambient, Lambert diffuse plus a weak Blinn–Phong
highlight (:mod:`visemeface.render.shaders`), both sides lit where a back face may
show (it uses the flipped normal), on a dark background; the colours come from :meth:`FaceMesh.vertex_colors`, so the
mouth cavity renders dark, and skin the pose compresses shades darker, as its
folds would (:mod:`visemeface.render.folds`; a face at rest is unchanged).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from visemeface.errors import InputError, RenderUnavailable
from visemeface.face.mesh import FaceMesh
from visemeface.render.culling import draw_sides, one_sided, outside_frustum
from visemeface.render.folds import fold_shade
from visemeface.render.shaders import shader

from visemeface.render import PROJECTIONS, VIEWS  # noqa: E402  (re-exported)
BACKGROUND = (0.045, 0.047, 0.06)
FOV_Y_DEG = 18.0
THREE_QUARTER_DEG = 35.0

def _look_at(eye, target, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    eye, target, up = (np.asarray(a, dtype=np.float64) for a in (eye, target, up))
    f = target - eye
    f /= np.linalg.norm(f)
    s = np.cross(f, up)
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def _perspective(fov_y, aspect, near, far) -> np.ndarray:
    f = 1.0 / math.tan(fov_y / 2)
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = f / aspect, f
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def _orthographic(half_w, half_h, near, far) -> np.ndarray:
    m = np.eye(4)
    m[0, 0], m[1, 1] = 1 / half_w, 1 / half_h
    m[2, 2] = -2 / (far - near)
    m[2, 3] = -(far + near) / (far - near)
    return m


#: The largest frame side (px) the renderer draws.
MAX_SIZE = 4096


def _check_size(size) -> tuple[int, int]:
    try:
        w, h = (int(size), int(size)) if np.isscalar(size) else (int(size[0]), int(size[1]))
    except (TypeError, ValueError, IndexError):
        raise InputError(f"size must be an integer or (width, height), got {size!r}") from None
    for v in (w, h):
        if v < 16 or v > MAX_SIZE or v % 16:
            raise InputError(f"frame size must be a multiple of 16 from 16 to {MAX_SIZE}, got {w}x{h}")
    return w, h


def parse_size(text: str) -> tuple[int, int]:
    """A ``--size`` option: ``"512"`` -> (512, 512), ``"640x480"`` -> (640, 480); InputError otherwise."""
    parts = str(text).lower().split("x")
    try:
        vals = [int(v) for v in parts]
    except ValueError:
        vals = []
    if len(vals) not in (1, 2):
        raise InputError(f"--size must be N or WxH in pixels, got {text!r}")
    try:
        return _check_size(vals[0] if len(vals) == 1 else vals)
    except InputError:
        raise InputError(f"--size must be multiples of 16 from 16 to 4096, got {text!r}") from None


#: A mesh taller than this many nasion-to-chin heights is a whole head, framed by its face (the default face
#: is 2.4, the ICT head with its neck and shoulders 3.0).
HEAD_FRAMING = 2.7


class Renderer:
    """Offscreen renderer for one face topology.

    Parameters
    ----------
    face : FaceMesh
        Topology, colours, rest positions and landmarks (the mouth corners and
        lip landmarks frame the ``mouth`` view and :meth:`mouth_box`).
    size : int or (int, int)
        Frame (width, height) in pixels, each a multiple of 16.
    view : {"face", "mouth", "three-quarter"}
    projection : {"perspective", "orthographic"}
    samples : int
        MSAA samples (clamped to what the driver offers; 0 disables).
    still : (N,) bool array, optional
        Vertices the caller's frames leave at rest (:meth:`MuscleRig.still_vertices`). Without MSAA the
        still triangles that show at no pixel at rest are then left out of every frame whose still
        vertices are at rest (the same image, :mod:`visemeface.render.culling`); other frames draw all.

    Examples
    --------
    >>> from visemeface.face.procedural import default_face
    >>> r = Renderer(default_face(), size=256)
    >>> r.render().shape
    (256, 256, 3)
    """

    def __init__(self, face: FaceMesh, size=(512, 512), view: str = "face",
                 projection: str = "perspective", samples: int = 4, still=None):
        from visemeface.errors import close_matches
        if view not in VIEWS:
            raise InputError(f"unknown view {view!r}{close_matches(view, VIEWS)}; choose from {', '.join(VIEWS)}")
        if projection not in PROJECTIONS:
            raise InputError(f"unknown projection {projection!r}{close_matches(projection, PROJECTIONS)}; "
                             f"choose from {', '.join(PROJECTIONS)}")
        self.face = face
        self.size = _check_size(size)
        self.view = view
        self.projection = projection
        tris = face.triangles
        if "enclosed" in face.regions:      # parts inside others (ICT's iris shells): never drawn
            tris = tris[~np.isin(tris, face.regions["enclosed"]).all(axis=1)]
        self._triangles = np.ascontiguousarray(tris, dtype=np.int32)
        self._normals = face.normal_accumulator()
        self._setup_camera()
        self._setup_sides()
        self._setup_gl(samples)
        self._model = None
        self._set_model(np.eye(4))
        self._setup_culling(still)

    # ------------------------------------------------------------ camera
    def _setup_camera(self):
        face = self.face
        v = face.vertices
        keep = np.ones(len(v), bool)
        if "mouth_cavity" in face.regions:
            keep[face.regions["mouth_cavity"]] = False
        w, h = self.size
        aspect = w / h
        lm = face.landmarks
        if self.view == "mouth" and {"mouth_corner_left", "mouth_corner_right"} <= lm.keys():
            cl, cr = v[lm["mouth_corner_left"]], v[lm["mouth_corner_right"]]
            width = np.linalg.norm(cl - cr)
            target = 0.5 * (cl + cr)
            lip = [lm[k] for k in ("upper_lip_mid", "lower_lip_mid") if k in lm]
            if lip:
                target = target.copy()
                target[2] = v[lip, 2].mean()
            # the mouth with about a third of its width as margin on each side
            half_h = max(0.8 * width / aspect, 0.45 * width)
        else:
            pts = v[keep]
            if {"nasion", "chin"} <= lm.keys():
                # a whole head (neck, shoulders, scalp: a scanned head) is framed by its face: from under the
                # chin to the top of the forehead (a face mask like the default face is framed whole)
                top, chin = v[lm["nasion"], 1], v[lm["chin"], 1]
                span = top - chin
                if span > 0 and pts[:, 1].max() - pts[:, 1].min() > HEAD_FRAMING * span:
                    pts = pts[(pts[:, 1] >= chin - 0.3 * span) & (pts[:, 1] <= top + 0.75 * span)]
            lo, hi = pts.min(0), pts.max(0)
            target = 0.5 * (lo + hi)
            target[2] = hi[2] - 0.35 * (hi[2] - lo[2])
            half_h = 0.53 * max(hi[1] - lo[1], (hi[0] - lo[0]) / aspect)
        self._target = np.asarray(target, float)
        self._half_h = float(half_h)
        fov = math.radians(FOV_Y_DEG)
        dist = half_h / math.tan(fov / 2)
        yaw = math.radians(THREE_QUARTER_DEG) if self.view == "three-quarter" else 0.0
        direction = np.array([math.sin(yaw), 0.0, math.cos(yaw)])
        eye = self._target + dist * direction
        self._eye = eye
        self.view_matrix = _look_at(eye, self._target)
        extent = float(np.linalg.norm(v.max(0) - v.min(0)))
        near, far = max(dist - 2 * extent, 1e-3), dist + 2 * extent
        if self.projection == "perspective":
            self.projection_matrix = _perspective(fov, aspect, near, far)
        else:
            self.projection_matrix = _orthographic(half_h * aspect, half_h, near, far)
        self.mvp = self.projection_matrix @ self.view_matrix

    def project(self, points: np.ndarray) -> np.ndarray:
        """Pixel coordinates (u right, v down; (0, 0) the top-left pixel corner) of 3-D points."""
        p = np.atleast_2d(np.asarray(points, dtype=np.float64))
        c = np.concatenate([p, np.ones((len(p), 1))], 1) @ self.mvp.T
        ndc = c[:, :3] / c[:, 3:4]
        w, h = self.size
        return np.stack([(ndc[:, 0] + 1) * w / 2, (1 - ndc[:, 1]) * h / 2], 1)

    def mouth_box(self) -> tuple[int, int, int, int]:
        """Pixel box (x, y, w, h) of the rest mouth.

        ``x`` and ``w`` span the two mouth corners (``w`` is the natural mouth
        width in pixels that Leach & Maddock (2019) normalise by); ``y`` and ``h`` span the
        rest lips from ``upper_lip_top`` to ``lower_lip_bottom`` when those
        landmarks exist, else the corners' own rows.
        """
        lm = self.face.landmarks
        try:
            names = ["mouth_corner_left", "mouth_corner_right"]
            pts = self.project(self.face.vertices[[lm[n] for n in names]])
        except KeyError:
            raise InputError("the face has no mouth_corner_left/mouth_corner_right landmarks") from None
        ys = pts[:, 1]
        extra = [lm[k] for k in ("upper_lip_top", "lower_lip_bottom") if k in lm]
        if extra:
            ys = np.concatenate([ys, self.project(self.face.vertices[extra])[:, 1]])
        x0, x1 = round(pts[:, 0].min()), round(pts[:, 0].max())
        y0, y1 = round(ys.min()), round(ys.max())
        return int(x0), int(y0), int(x1 - x0), max(1, int(y1 - y0))

    def camera_info(self) -> dict:
        """JSON-able description of the camera (for an analysis sidecar)."""
        lm = self.face.landmarks
        info = {
            "view": self.view,
            "projection": self.projection,
            "size": list(self.size),
            "fov_y_deg": FOV_Y_DEG if self.projection == "perspective" else None,
            "eye": self._eye.tolist(),
            "target": self._target.tolist(),
            "view_matrix": self.view_matrix.tolist(),
            "projection_matrix": self.projection_matrix.tolist(),
        }
        if {"mouth_corner_left", "mouth_corner_right"} <= lm.keys():
            box = self.mouth_box()
            corners = self.project(self.face.vertices[[lm["mouth_corner_right"], lm["mouth_corner_left"]]])
            info["mouth_box"] = list(box)
            info["mouth_width_px"] = float(np.linalg.norm(corners[1] - corners[0]))
            info["mouth_corners_px"] = corners.tolist()
        return info

    def _setup_sides(self):
        """The surfaces that may be drawn one-sided (:func:`visemeface.render.culling.one_sided`)."""
        # The image is drawn upside down (y flipped in clip space, so winding flips too) because
        # GL's row 0 is the bottom: the read-back is then already top-down, with no flip copy.
        self._clip = np.diag([1.0, -1.0, 1.0, 1.0]) @ self.mvp
        self._closed, self._holed = one_sided(self._triangles, self.face.vertices)

    def _order(self, members):
        """Order the triangles: the closed surfaces', the holed ``members``', then the two-sided rest."""
        holed = np.zeros(len(self._triangles), bool)
        for i in members:
            holed |= self._holed[i][0]
        rank = np.where(self._closed, 0, np.where(holed, 1, 2))
        order = np.argsort(rank, kind="stable")
        self._closed, self._triangles, self._rank = self._closed[order], self._triangles[order], rank[order]
        self._holed = [(m[order], rim) for m, rim in self._holed]
        self._split = self._splits(self._rank)

    @staticmethod
    def _splits(rank) -> tuple[int, int, int]:
        """(closed, closed + holed, all): where the one-sided triangles end, without and with the holed."""
        return int((rank == 0).sum()), int((rank <= 1).sum()), len(rank)

    # ------------------------------------------------------------ GL
    def _setup_gl(self, samples):
        import moderngl
        try:
            self.ctx = moderngl.create_context(standalone=True, backend="egl")
        except Exception as exc:  # no EGL: say so on one line
            raise RenderUnavailable(f"cannot create a headless OpenGL (EGL) context: {exc}") from None
        ctx = self.ctx
        self.program, self.program_front = (
            ctx.program(vertex_shader=shader("vertex", two), fragment_shader=shader("fragment", two))
            for two in (True, False))
        n = self.face.n_vertices
        self._vbo_data = np.empty((n, 7), dtype="f4")
        self._lengths = np.empty(n, dtype="f4")
        self._rest_lengths = np.empty(n, dtype="f4")
        self._normals(self.face.vertices, dtype=np.float32, lengths=self._rest_lengths)
        self.vbo = ctx.buffer(reserve=self._vbo_data.nbytes, dynamic=True)
        self.cbo = ctx.buffer(np.ascontiguousarray(self.face.vertex_colors(), dtype="f4").tobytes())
        w, h = self.size
        samples = int(min(max(samples, 0), ctx.max_samples))
        self.samples = samples
        self.fbo = ctx.framebuffer(color_attachments=[ctx.renderbuffer((w, h), 4)],
                                   depth_attachment=ctx.depth_renderbuffer((w, h)))
        if samples > 1:
            self.fbo_ms = ctx.framebuffer(
                color_attachments=[ctx.renderbuffer((w, h), 4, samples=samples)],
                depth_attachment=ctx.depth_renderbuffer((w, h), samples=samples))
        else:
            self.fbo_ms = self.fbo

    def _vertex_array(self, ibo, program=None):
        """The face's vertex array drawing the triangles of index buffer ``ibo`` (two-sided, or with ``program``)."""
        return self.ctx.vertex_array(program or self.program,
                                     [(self.vbo, "3f 3f 1f", "in_pos", "in_normal", "in_fold"),
                                      (self.cbo, "3f", "in_color")], index_buffer=ibo, index_element_size=4)

    def _setup_culling(self, still):
        """The index buffers: every triangle, and (given ``still``, no MSAA) those a frame with its still
        vertices at rest draws. A holed surface is one-sided in a frame whose hole rims are out of view, or
        whose still vertices are at rest if its rims are still and the cap over its holes shows at no pixel
        among the still triangles at rest (any ray that meets the surface then meets it as a closed one)."""
        from visemeface.render.culling import shown_triangles
        rest = self.face.vertices
        out = [outside_frustum(self._clip, rest[np.unique(rim)]) for _, rim in self._holed]
        use_still = still is not None and self.samples <= 1
        if use_still:
            still = np.asarray(still, dtype=bool)
            if still.shape != (self.face.n_vertices,):
                raise InputError(f"still must be ({self.face.n_vertices},) booleans, got shape {still.shape}")
        capped = [i for i, (_, rim) in enumerate(self._holed) if use_still and not out[i] and still[rim].all()]
        with self.ctx:
            while True:
                members = [i for i in range(len(self._holed)) if out[i] or i in capped]
                self._order(members)
                if not use_still:
                    break
                keep, hidden = shown_triangles(self.ctx, self._clip, rest.astype(np.float32), self._triangles,
                                               still, self.size, one_sided=self._split[1],
                                               caps=[self._holed[i][1] for i in capped])
                if hidden.all():
                    break
                capped = [i for i, h in zip(capped, hidden) if h]
            self._rims = [np.unique(self._holed[i][1]) for i in members]
            self._capped = [i in capped for i in members]
            self.ibo = self.ctx.buffer(self._triangles.tobytes())
            self.vao, self.vao_front = self._vertex_array(self.ibo), self._vertex_array(self.ibo, self.program_front)
            self._still = self.vao_shown = None
            self.n_shown, self._split_shown = len(self._triangles), self._split
            if not use_still:
                return
            self.vao_shown, self.vao_shown_front = self.vao, self.vao_front
            if not keep.all():
                self.ibo_shown = self.ctx.buffer(np.ascontiguousarray(self._triangles[keep]).tobytes())
                self.vao_shown = self._vertex_array(self.ibo_shown)
                self.vao_shown_front = self._vertex_array(self.ibo_shown, self.program_front)
        self.n_shown = int(keep.sum())
        self._split_shown = self._splits(self._rank[keep])
        self._still = np.flatnonzero(still)
        self._still_rest = rest.astype(np.float32)[self._still]

    def render(self, vertices: np.ndarray | None = None, model: np.ndarray | None = None) -> np.ndarray:
        """Render one frame; returns a new uint8 (H, W, 3) RGB array, row 0 at the top.

        Parameters
        ----------
        vertices : (N, 3) array, optional
            Posed positions of the face's vertices (rest positions if None).
        model : (4, 4) array, optional
            A rigid transform the vertices are drawn with (a turned head,
            :func:`visemeface.speech.gestures.head_matrices`), drawn by the GPU; a frame so turned is drawn
            whole (its still triangles turn too, so what hides them at rest may not).
        """
        import moderngl
        if self.ctx is None:
            raise RuntimeError("this renderer is closed (its `with` block has ended); make a new one")
        v = self.face.vertices if vertices is None else np.asarray(vertices)
        if v.shape != (self.face.n_vertices, 3):
            raise InputError(f"vertices must have shape ({self.face.n_vertices}, 3), got {v.shape}")
        if not np.isfinite(v).all():
            raise InputError("vertices hold NaN or infinite values")
        self._vbo_data[:, :3] = v
        self._vbo_data[:, 3:6] = self._normals(v, dtype=np.float32, lengths=self._lengths)
        self._vbo_data[:, 6] = fold_shade(self._lengths, self._rest_lengths)
        clip = self._set_model(np.eye(4) if model is None else np.asarray(model, dtype=np.float64))
        turned = model is not None and not np.array_equal(model, np.eye(4))
        at_rest = self._still is not None and not turned and np.array_equal(self._vbo_data[self._still, :3], self._still_rest)
        holed = all((at_rest and c) or outside_frustum(clip, v[rim]) for rim, c in zip(self._rims, self._capped))
        # the still vertices at rest: the still triangles hidden at rest stay so
        vaos, split = (((self.vao_shown_front, self.vao_shown), self._split_shown) if at_rest and holed
                       else ((self.vao_front, self.vao), self._split))
        cut = split[1] if holed else split[0]           # the one-sided triangles come first
        ctx = self.ctx
        w, h = self.size
        with ctx:   # make this renderer's context current (several renderers may coexist)
            self.vbo.write(self._vbo_data)
            self.fbo_ms.use()
            ctx.enable(moderngl.DEPTH_TEST)
            ctx.front_face = "cw"   # the y flip above mirrors the winding
            ctx.clear(*BACKGROUND, 1.0, depth=1.0)
            draw_sides(ctx, vaos[1], cut, split[2], front=vaos[0])
            if self.fbo_ms is not self.fbo:
                ctx.copy_framebuffer(self.fbo, self.fbo_ms)
            image = np.empty((h, w, 3), dtype=np.uint8)
            self.fbo.read_into(image, components=3, alignment=1)
        return image

    def _set_model(self, model: np.ndarray) -> np.ndarray:
        """Draw with the rigid transform ``model`` (4, 4) from now on; returns its clip matrix."""
        if model.shape != (4, 4) or not np.isfinite(model).all():
            raise InputError(f"model must be a finite (4, 4) matrix, got shape {model.shape}")
        if self._model is None or not np.array_equal(model, self._model):
            self._model = model.copy()
            with self.ctx:
                for program in (self.program, self.program_front):
                    for name, matrix in (("u_mvp", self._clip @ model), ("u_view", self.view_matrix @ model)):
                        if name in program:          # a uniform the shader does not use is optimised away
                            program[name].write(matrix.T.astype("f4").tobytes())
        return self._clip @ model

    def surface_points(self, pixels: np.ndarray) -> np.ndarray:
        """The visible surface's 3-D points (mesh units) under ``pixels`` ``(n, 2)`` (u, v as :meth:`project`
        gives them) in the last rendered frame, from its depth buffer; NaN rows where no surface was drawn."""
        if self.ctx is None:
            raise RuntimeError("this renderer is closed (its `with` block has ended); make a new one")
        w, h = self.size
        with self.ctx:
            raw = self.fbo.read(components=1, attachment=-1, dtype="f4")
        depth = np.frombuffer(raw, dtype=np.float32).reshape(h, w)
        px = np.atleast_2d(np.asarray(pixels, dtype=np.float64))
        col = np.clip(np.floor(px[:, 0]).astype(int), 0, w - 1)
        row = np.clip(np.floor(px[:, 1]).astype(int), 0, h - 1)
        d = depth[row, col].astype(np.float64)
        ndc = np.stack([2 * px[:, 0] / w - 1, 1 - 2 * px[:, 1] / h, 2 * d - 1, np.ones(len(px))], axis=1)
        p = ndc @ np.linalg.inv(self.mvp).T
        out = p[:, :3] / p[:, 3:4]
        out[d >= 1.0] = np.nan               # the background (the cleared depth)
        return out

    def release(self):
        """Free the GL objects and context (also done when garbage-collected)."""
        ctx = getattr(self, "ctx", None)
        if ctx is not None:
            ctx.release()
            self.ctx = None

    def __del__(self):
        try:
            self.release()
        except Exception:               # at interpreter exit the GL library may be gone already
            pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()


def save_png(path: str | Path, image: np.ndarray, force: bool = False) -> Path:
    """Write an RGB uint8 image as PNG through :func:`visemeface.outputs.atomic_output`."""
    import cv2

    from visemeface.outputs import atomic_output, check_suffix
    check_suffix(path, ".png")
    image = np.asarray(image)
    if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
        raise ValueError(f"expected a uint8 (H, W, 3) image, got {image.dtype} {image.shape}")
    with atomic_output(path, force) as tmp:
        ok, buf = cv2.imencode(".png", np.ascontiguousarray(image[:, :, ::-1]))
        if not ok:
            raise RuntimeError("PNG encoding failed")
        Path(tmp).write_bytes(buf.tobytes())
    return Path(path)
