"""Waters muscle functions: pure numpy displacement fields on vertex arrays.

Every function takes rest positions ``points`` (N, 3) in metres and returns a
displacement (N, 3) for activation 1; displacements of the linear and sphincter
muscles are linear in the activation (Edge & Maddock 2001, §2.1, Waters 1987), so a rig can
precompute them once as basis fields. The jaw is a rotation, nonlinear in its
angle, and is evaluated on demand from :func:`jaw_rotation_displacement`.

Axes follow ``docs/conventions.md``: +x subject's left, +y up, +z forward.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "smoothstep",
    "linear_muscle_displacement",
    "linear_muscle_falloff",
    "sphincter_displacement",
    "seam_height",
    "lip_trim_weights",
    "jaw_centre_weight",
    "jaw_rotation_displacement",
    "local_displacement",
    "turn_displacement",
    "modiolus_share",
    "modiolus_blend",
]


def smoothstep(edge0: float, edge1: float, x: np.ndarray) -> np.ndarray:
    r"""Hermite step, 0 below ``edge0``, 1 above ``edge1``, C1 in between.

    .. math:: t = \mathrm{clip}\left(\frac{x - e_0}{e_1 - e_0}, 0, 1\right),\quad s = t^2 (3 - 2t)
    """
    t = np.clip((np.asarray(x, dtype=float) - edge0) / (edge1 - edge0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _unit(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v)
    if not np.isfinite(n) or n == 0.0:
        raise ValueError(f"cannot normalise vector {v!r}")
    return v / n


def linear_muscle_falloff(points: np.ndarray, attachment, insertion, zone_angle: float,
                          falloff_start: float, falloff_end: float) -> np.ndarray:
    r"""Scalar influence (N,) of a Waters linear muscle, in [0, 1].

    With :math:`\mathbf v = \mathbf p - A`, :math:`D = |\mathbf v|` and
    :math:`\alpha = \angle(\mathbf v, I - A)`, a vertex is inside the zone when
    :math:`\alpha \le \Omega` and :math:`D \le R_f`. There

    .. math::
        a(\alpha) = \cos\left(\frac{\alpha}{\Omega}\frac{\pi}{2}\right),\qquad
        r(D) = \begin{cases}
            \cos\left((1 - D/R_s)\,\pi/2\right) & D < R_s \\
            \cos\left(\frac{D - R_s}{R_f - R_s}\,\pi/2\right) & R_s \le D \le R_f
        \end{cases}

    and the influence is :math:`a\,r`; it is 0 outside the zone. Both factors
    vanish at the zone edge (:math:`\alpha = \Omega`, :math:`D = R_f`) and at the
    attachment (:math:`D = 0`); the radial factor peaks at :math:`D = R_s` (put
    :math:`R_s = |I - A|` for the maximum at the insertion).

    Parameters
    ----------
    points : (N, 3) array
    attachment, insertion : (3,) arrays
        Bony attachment A and skin insertion I.
    zone_angle : float
        Half-angle Ω of the zone of influence (radians, 0 < Ω < π).
    falloff_start, falloff_end : float
        Radial distances R_s < R_f from A (metres).
    """
    if not 0.0 < zone_angle < np.pi:
        raise ValueError(f"zone_angle must be in (0, pi), got {zone_angle}")
    if not 0.0 < falloff_start < falloff_end:
        raise ValueError(f"need 0 < falloff_start < falloff_end, got {falloff_start}, {falloff_end}")
    points = np.asarray(points, dtype=float)
    a = np.asarray(attachment, dtype=float)
    axis = _unit(np.asarray(insertion, dtype=float) - a)
    v = points - a
    dist = np.linalg.norm(v, axis=1)
    safe = np.where(dist > 0.0, dist, 1.0)
    cos_alpha = np.clip((v @ axis) / safe, -1.0, 1.0)
    alpha = np.arccos(cos_alpha)
    inside = (alpha < zone_angle) & (dist < falloff_end) & (dist > 0.0)
    angular = np.cos(np.minimum(alpha / zone_angle, 1.0) * np.pi / 2)
    near = np.cos((1.0 - np.minimum(dist / falloff_start, 1.0)) * np.pi / 2)
    far = np.cos(np.clip((dist - falloff_start) / (falloff_end - falloff_start), 0.0, 1.0) * np.pi / 2)
    radial = np.where(dist < falloff_start, near, far)
    return np.where(inside, np.clip(angular * radial, 0.0, 1.0), 0.0)


def linear_muscle_displacement(points: np.ndarray, attachment, insertion, zone_angle: float,
                               falloff_start: float, falloff_end: float, k: float = 1.0) -> np.ndarray:
    r"""Displacement (N, 3) of a Waters linear muscle at activation 1.

    .. math:: \Delta\mathbf p = k\, a(\alpha)\, r(D)\, \frac{A - \mathbf p}{D}

    with the angular and radial factors of :func:`linear_muscle_falloff`: skin is
    pulled toward the bony attachment, most near the insertion, not at all at the
    edge of the zone or beyond :math:`R_f`. ``k`` is the largest displacement (m).

    Examples
    --------
    >>> import numpy as np
    >>> p = np.array([[1.0, 0, 0], [0, 1.0, 0], [3.0, 0, 0]])
    >>> d = linear_muscle_displacement(p, [0, 0, 0], [1, 0, 0], np.pi / 4, 1.0, 2.0, k=0.1)
    >>> (np.round(d, 6) + 0.0).tolist()
    [[-0.1, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    """
    points = np.asarray(points, dtype=float)
    f = linear_muscle_falloff(points, attachment, insertion, zone_angle, falloff_start, falloff_end)
    v = np.asarray(attachment, dtype=float) - points
    dist = np.linalg.norm(v, axis=1)
    unit = v / np.where(dist > 0.0, dist, 1.0)[:, None]
    return k * f[:, None] * unit


def sphincter_displacement(points: np.ndarray, centre, axis_x, axis_y, semi_x: float, semi_y: float,
                           k: float = 0.5, protrusion: float = 0.0, depth: float | None = None,
                           shield: float | None = None, ramp: float | None = None) -> np.ndarray:
    r"""Displacement (N, 3) of a sphincter (orbicularis oris) at activation 1.

    In the ellipse's frame (centre :math:`c`, in-plane unit axes
    :math:`\mathbf e_x, \mathbf e_y`, normal :math:`\mathbf n = \mathbf e_x \times \mathbf e_y`)
    a vertex has local coordinates :math:`(x, y, z)`, elliptic radius
    :math:`\rho_e = \sqrt{x^2/l_x^2 + y^2/l_y^2}` and in-plane radius
    :math:`\rho = \sqrt{x^2 + y^2}`. Inside the ellipse (:math:`\rho_e < 1`):

    .. math::
        d &= \cos^2\left(\rho_e \frac{\pi}{2}\right) \\
        \Delta\mathbf p &= -k\, d\, g(\rho - r_s)\, \frac{x\mathbf e_x + y\mathbf e_y}{\rho}
                         + k_p\, (1 - \rho_e^2)^2\, \mathbf n

    The drawstring contraction pulls tissue toward the centre, by the fraction
    :math:`k\,d` of its distance to the *shielded disc* of radius :math:`r_s`
    (Edge & Maddock 2001, §2.1.2: the semi-minor axis :math:`l_y`, the default), where
    :math:`g` is a C1 ramp: 0 for :math:`s \le 0`, :math:`s^2/2\delta` up to
    :math:`\delta` (``ramp``, default :math:`r_s`), then :math:`s - \delta/2`, so
    :math:`0 \le g \le s` and :math:`0 \le g' \le 1` (no shading crease at
    the disc's rim). Inside the disc nothing is pulled, and for :math:`k < 1`
    the radial map :math:`\rho \mapsto \rho - k d\, g(\rho - r_s)` is
    increasing and stays :math:`\ge r_s`: vertices neither collect at the centre nor enter the disc
    nor fold over each other, while the mouth corners, outside it, draw in (the
    mouth narrows). Protrusion along the normal grows toward the centre
    (puckering; :math:`k_p` in metres). ``depth`` (m), when given, fades the
    effect for :math:`|z|` between depth and 2·depth, so tissue far behind the
    lips (inside the mouth) is not pulled.

    Parameters
    ----------
    points : (N, 3) array
    centre, axis_x, axis_y : (3,) arrays
        Ellipse centre and in-plane directions (``axis_y`` is orthogonalised
        against ``axis_x``).
    semi_x, semi_y : float
        Semi-axes l_x >= l_y (m).
    k : float
        Contraction fraction, 0 <= k < 1 (dimensionless).
    protrusion : float
        Largest forward push k_p (m), at the centre.
    shield : float, optional
        Radius r_s of the shielded disc (m); default ``semi_y``.
    ramp : float, optional
        Width δ of the ramp at the disc's rim (m); default ``shield``.
    """
    if not 0.0 < semi_y <= semi_x:
        raise ValueError(f"need 0 < semi_y <= semi_x, got {semi_x}, {semi_y}")
    if not 0.0 <= k < 1.0:
        raise ValueError(f"contraction fraction k must be in [0, 1), got {k}")
    shield = semi_y if shield is None else float(shield)
    points = np.asarray(points, dtype=float)
    ex = _unit(axis_x)
    ey = np.asarray(axis_y, dtype=float)
    ey = _unit(ey - (ey @ ex) * ex)
    n = np.cross(ex, ey)
    rel = points - np.asarray(centre, dtype=float)
    x, y, z = rel @ ex, rel @ ey, rel @ n
    rho_e = np.sqrt((x / semi_x) ** 2 + (y / semi_y) ** 2)
    rho = np.hypot(x, y)
    inside = rho_e < 1.0
    d = np.where(inside, np.cos(np.minimum(rho_e, 1.0) * np.pi / 2) ** 2, 0.0)
    pull = k * d * _soft_ramp(rho - shield, ramp if ramp is not None else shield) / np.where(rho > 0, rho, 1.0)
    push = np.where(inside, protrusion * (1.0 - np.minimum(rho_e, 1.0) ** 2) ** 2, 0.0)
    if depth is not None:
        fade = 1.0 - smoothstep(depth, 2.0 * depth, np.abs(z))
        pull, push = pull * fade, push * fade
    return -pull[:, None] * (x[:, None] * ex + y[:, None] * ey) + push[:, None] * n


def _soft_ramp(s: np.ndarray, width: float) -> np.ndarray:
    """C1 ramp: 0 below 0, s²/(2 width) up to width, then s - width/2."""
    s = np.asarray(s, dtype=float)
    if width <= 0:
        return np.maximum(s, 0.0)
    return np.where(s <= 0, 0.0, np.where(s < width, s * s / (2 * width), s - width / 2))


def seam_height(u: np.ndarray, seam_u: np.ndarray, seam_v: np.ndarray, smooth: float = 0.0) -> np.ndarray:
    r"""Height of the lip-trim surface above each lateral position ``u``.

    The trim surface is the cylinder :math:`v = h(u)` (extruded along the face
    normal) through the lip-seam points :math:`(u_i, v_i)`: piecewise-linear
    interpolation, held constant beyond the outermost seam points, optionally
    smoothed by a Gaussian of width ``smooth`` so the surface has no kinks.
    """
    seam_u = np.asarray(seam_u, dtype=float)
    seam_v = np.asarray(seam_v, dtype=float)
    order = np.argsort(seam_u, kind="stable")
    su, sv = seam_u[order], seam_v[order]
    u = np.asarray(u, dtype=float)
    if smooth <= 0.0:
        return np.interp(u, su, sv)
    # Smooth by sampling the interpolant on a fine grid and convolving with a Gaussian.
    lo, hi = min(su[0], u.min()) - 4 * smooth, max(su[-1], u.max()) + 4 * smooth
    grid = np.linspace(lo, hi, 1024)
    g = np.interp(grid, su, sv)
    step = grid[1] - grid[0]
    half = int(np.ceil(4 * smooth / step))
    kern = np.exp(-0.5 * (np.arange(-half, half + 1) * step / smooth) ** 2)
    kern /= kern.sum()
    padded = np.concatenate([np.full(half, g[0]), g, np.full(half, g[-1])])
    gs = np.convolve(padded, kern, mode="valid")
    return np.interp(u, grid, gs)


def lip_trim_weights(u: np.ndarray, v: np.ndarray, surface_v: np.ndarray, side: np.ndarray,
                     inner_width: float, outer_width: float, corner_start: float = 0.75,
                     corner_end: float = 1.15, tag: float = 2.0) -> np.ndarray:
    r"""Weight (N,) in [0, 1] of *upper-lip* muscles; lower-lip muscles use ``1 - w``.

    Positions are in the mouth frame: ``u`` lateral in half mouth widths
    (corners at :math:`u = \pm 1`), ``v`` vertical (m), ``surface_v`` the trim
    surface height :math:`h(u)` (:func:`seam_height`). ``side`` is +1 for
    vertices of the upper lip, -1 for the lower lip, 0 elsewhere: where the two
    lips' seam vertices coincide geometry alone cannot separate them.

    .. math::
        c &= \mathrm{smoothstep}(u_0, u_1, |u|) \quad\text{(0 between the lips, 1 past the corners)}\\
        w_b &= w_i + (w_o - w_i)\,c \\
        t &= \frac{v - h(u)}{w_b} + \tau\sigma\,(1 - c) \\
        w &= \mathrm{smoothstep}(-1, 1, t)

    Between the lips the cut is sharp (width :math:`w_i`) and the tag
    :math:`\sigma` (strength :math:`\tau`, ``tag``; 2 makes coincident seam
    copies exactly 0 or 1) decides the seam vertices, so the lips part. Toward and past
    the corners, where skin is continuous, the blend widens to :math:`w_o` and
    the tag fades, so upper and lower muscles share the corner smoothly (no
    tear, no crease).
    """
    u = np.asarray(u, dtype=float)
    c = smoothstep(corner_start, corner_end, np.abs(u))
    width = inner_width + (outer_width - inner_width) * c
    t = (np.asarray(v, dtype=float) - surface_v) / width + tag * np.asarray(side, dtype=float) * (1.0 - c)
    return smoothstep(-1.0, 1.0, t)


def modiolus_share(points: np.ndarray, corner, radius: float, core: float = 0.3) -> np.ndarray:
    r"""Each vertex's share (N,) of a mouth corner's common motion: 1 within ``core`` x ``radius`` of the
    corner ``corner`` (a point), falling as a smoothstep to 0 at ``radius`` (metres).

    At each corner the muscles of the cheek and lips (zygomatic major, risorius, the depressor and
    levator anguli oris, buccinator, orbicularis oris) insert into one fibromuscular knot beside the corner,
    the modiolus, about 1 cm across, that moves as a unit (Standring 2016, *Gray's Anatomy*): the skin of
    the upper and the lower lip converges on it and goes with it. A rig field
    blended toward the corner's own over this share, :math:`(1-s)\,f + s\,\bar f`, moves the corner as
    one piece, so the lips' rows that converge there (a fraction of a millimetre apart on a dense scan)
    cannot pass each other and fold.
    """
    d = np.linalg.norm(np.asarray(points, dtype=float) - np.asarray(corner, dtype=float), axis=1)
    return smoothstep(radius, core * radius, d)


def modiolus_blend(points: np.ndarray, bases: np.ndarray, jaw_weight: np.ndarray, corners, radius: float,
                   core: float, held: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fields ``bases`` (K, N, 3) and the jaw's weight (N,) blended about each of ``corners`` toward the mean
    over the corner's core (:func:`modiolus_share`); the vertices ``held`` ((N,) bool: teeth, tongue, eyes)
    keep their own."""
    for corner in corners:
        s = modiolus_share(points, corner, radius, core)
        s[held] = 0.0
        inner = s >= 1.0
        if not inner.any():             # the corner itself held (no skin there to blend)
            continue
        bases = bases * (1.0 - s)[None, :, None] + s[None, :, None] * bases[:, inner].mean(axis=1)[:, None, :]
        jaw_weight = jaw_weight * (1.0 - s) + s * jaw_weight[inner].mean()
    return bases, jaw_weight


def jaw_centre_weight(u: np.ndarray, reach: float) -> np.ndarray:
    r"""Jaw rotation weight (N,) from the centre line: :math:`\cos^2(\frac{\pi}{2}\min(|u|/U, 1))`.

    1 on the face's centre line (:math:`u = 0`), falling smoothly to 0 at
    :math:`|u| = U` (``reach``, same units as ``u``), so the open mouth is a
    smooth curve with the largest drop at the centre of the lower lip
    (Edge & Maddock 2001, §2.1.4).
    """
    return np.cos(np.minimum(np.abs(np.asarray(u, dtype=float)) / reach, 1.0) * np.pi / 2) ** 2


def jaw_neck_weight(points: np.ndarray, joint_left, joint_right, chin, forward, fade: float) -> np.ndarray:
    r"""Jaw weight factor (N,) that keeps the mandible's motion off the throat and the back of the head.

    About the jaw axis (through the joints), each point has an angle :math:`\phi` measured from the forward
    direction turning down and back; the chin lies at :math:`\phi_c`. The factor is 1 for
    :math:`\phi \le \phi_c` (the lips, chin and cheeks in front of the chin's line) and falls smoothly
    (smoothstep) to 0 at :math:`\phi_c + ` ``fade`` (radians): the skin under the chin follows partly, the
    throat and the nape not at all. A face that ends at the chin (the default face) is unchanged.
    """
    jl, jr = np.asarray(joint_left, float), np.asarray(joint_right, float)
    k = _unit(jl - jr)
    f = np.asarray(forward, float)
    f = _unit(f - (f @ k) * k)
    down = np.cross(k, f)                      # left x forward = down
    o = 0.5 * (jl + jr)

    def angle(p):
        r = np.asarray(p, float) - o
        return np.arctan2(r @ down, r @ f)      # 0 forward, +pi/2 straight down, pi behind

    phi = angle(points)
    phi = np.where(phi < -np.pi / 2, phi + 2 * np.pi, phi)   # above-behind (the scalp) counts as far behind
    return 1.0 - smoothstep(float(angle(chin)), float(angle(chin)) + fade, phi)


def jaw_angle_for_drop(joint_left, joint_right, point, drop: float) -> float:
    """The jaw angle (rad) that moves ``point`` (the lower lip's centre) by the chord ``drop`` (m) about the
    joints' axis; NaN when ``drop`` is not positive or beyond the point's reach (twice its radius)."""
    jl, jr = np.asarray(joint_left, float), np.asarray(joint_right, float)
    k = _unit(jl - jr)
    r = np.asarray(point, float) - jr
    radius = float(np.linalg.norm(r - (r @ k) * k))
    return float(2.0 * np.arcsin(drop / (2.0 * radius))) if 0 < drop < 2 * radius else float("nan")


def jaw_rotation_displacement(points: np.ndarray, joint_left, joint_right, angle: float,
                              weights: np.ndarray) -> np.ndarray:
    r"""Displacement (N, 3) rotating each vertex about the jaw axis by ``angle * weights``.

    The axis passes through both jaw joints, direction
    :math:`\mathbf k = (J_l - J_r)/|J_l - J_r|` (+x on the default face), so a
    positive angle swings the chin down and back (opens the mouth). With
    :math:`\mathbf r = \mathbf p - J_r` and per-vertex angle :math:`\theta_i = \theta w_i`
    (Rodrigues):

    .. math::
        \Delta\mathbf p = (\cos\theta_i - 1)\,(\mathbf r - (\mathbf k\cdot\mathbf r)\mathbf k)
                          + \sin\theta_i\,(\mathbf k \times \mathbf r)

    Nonlinear in the angle, so not a basis field: evaluate per pose.
    """
    points = np.asarray(points, dtype=float)
    jr = np.asarray(joint_right, dtype=float)
    kax = _unit(np.asarray(joint_left, dtype=float) - jr)
    r = points - jr
    perp = r - np.outer(r @ kax, kax)
    cross = np.cross(kax, r)
    theta = angle * np.asarray(weights, dtype=float)
    return (np.cos(theta) - 1.0)[:, None] * perp + np.sin(theta)[:, None] * cross


def local_displacement(points: np.ndarray, centre, radii, direction, mask: np.ndarray,
                       axes: np.ndarray | None = None, inner: float | None = None) -> np.ndarray:
    r"""A smooth local push (N, 3) at activation 1: the tongue's and the lip shaping's functions.

    Each vertex in ``mask`` moves along ``direction`` (a vector, m) scaled by a
    Gaussian of its ellipsoidal distance to ``centre``,

    .. math:: \Delta\mathbf p = \mathbf d\,\exp\Big(-\sum_k \big(q_k / r_k\big)^2\Big),
              \quad \mathbf q = A(\mathbf p - \mathbf c),

    with per-axis radii ``radii`` (m) along the rows of ``axes`` (a rig's mouth
    frame; default the world axes); vertices outside ``mask`` stay. With
    ``inner`` (m) the lateral factor is a *band* instead,
    :math:`s\big((|q_x| - \text{inner}) / r_x\big)` (``smoothstep``): nothing moves
    within ``inner`` of the centre, everything beyond ``inner + r_x`` fully, and the
    x component of ``direction`` points away from the centre line on each side
    (negative: toward it). Linear in the activation, so a rig precomputes it as a
    basis field.
    """
    points = np.asarray(points, dtype=float)
    axes = np.eye(3) if axes is None else np.asarray(axes, dtype=float)
    local = (points - np.asarray(centre, dtype=float)) @ axes.T
    q = local / np.asarray(radii, dtype=float)
    d = np.broadcast_to(np.asarray(direction, dtype=float), points.shape).copy()
    if inner is None:
        w = np.exp(-(q ** 2).sum(axis=1))
    else:
        w = np.exp(-(q[:, 1:] ** 2).sum(axis=1)) * smoothstep(inner, inner + radii[0], np.abs(local[:, 0]))
        dl = d @ axes.T                                  # direction in the frame, x flipped on the -x side
        dl[:, 0] *= np.where(local[:, 0] < 0, -1.0, 1.0)
        d = dl @ axes
    return (w * np.asarray(mask, dtype=float))[:, None] * d


def turn_weight(points: np.ndarray, line, mask: np.ndarray, radius: float | None = None, view=(0.0, 0.0, 1.0),
                lids: np.ndarray | None = None, lid_radius: float | None = None) -> np.ndarray:
    """Each vertex's share (N,) of a turn's angle (:func:`turn_displacement`): 1 on ``mask`` (within ``radius``
    of the line through ``line`` along ``view``, when given), the lids' shares fading toward the eye's corners."""
    r = np.asarray(points, dtype=float) - np.asarray(line, dtype=float)
    v = _unit(view)
    d = np.linalg.norm(r - np.outer(r @ v, v), axis=1)
    w = np.asarray(mask, dtype=float)
    if radius is not None:
        w = w * smoothstep(radius, 0.7 * radius, d)
    if lids is not None and lid_radius:
        w = w + np.asarray(lids, dtype=float) * smoothstep(lid_radius, 0.5 * lid_radius, d)
    return w


def turn_displacement(points: np.ndarray, centre, axis, angle: float, mask: np.ndarray,
                      radius: float | None = None, view=(0.0, 0.0, 1.0), lids: np.ndarray | None = None,
                      lid_radius: float | None = None, line=None) -> np.ndarray:
    r"""A small rotation (N, 3) of the vertices in ``mask`` about ``axis`` through ``centre``, linearised:

    .. math:: \Delta\mathbf p = w\,\theta\,\mathbf k \times (\mathbf p - \mathbf c),

    exact to first order in :math:`\theta` (a rig turning an eyeball rigidly adds the rotation's higher
    orders, :func:`rotation_terms`). With ``radius`` only the part within
    ``radius`` of the line through ``centre`` along ``view`` turns (:math:`w` falls
    from 1 at 0.7 ``radius`` to 0 at ``radius``): the iris slides over the sclera,
    and the eyeball's wide sides stay under the lids.

    With ``lids`` ((N,) each vertex's share of the angle, 0 off the lids) the lid vertices turn too, by
    their share, about the same centre, so they slide over the globe with it, fading from full at half
    ``lid_radius`` from that line to none at ``lid_radius`` (the eye's corners, held by the canthal tendons,
    barely move): the upper lid follows vertical gaze about one to one (Becker & Fuchs 1988), so looking up
    or down neither bares the white above the iris nor drives the lid through it. The forward line runs
    through ``line`` (default ``centre``): a point on the eye's axis in front of the centre.
    """
    w = turn_weight(points, centre if line is None else line, mask, radius, view, lids, lid_radius)
    r = np.asarray(points, dtype=float) - np.asarray(centre, dtype=float)
    return float(angle) * np.cross(_unit(axis), r) * w[:, None]


def rotation_terms(perp: np.ndarray, cross: np.ndarray, w: np.ndarray, degrees) -> np.ndarray:
    r"""The Taylor terms :math:`C_j` (len(degrees), N, 3) of a rotation by :math:`\theta w_i` about an axis:

    .. math:: (\cos\theta w_i - 1)\,\mathbf r_\perp + \sin\theta w_i\,(\mathbf k \times \mathbf r)
              = \sum_{j \ge 1} \theta^j C_j, \quad
              C_j = \frac{(-1)^{\lfloor j/2 \rfloor} w_i^j}{j!}\,
              \begin{cases} \mathbf k \times \mathbf r & j \text{ odd} \\ \mathbf r_\perp & j \text{ even}\end{cases}

    (``perp``: each point's offset from the axis, ``cross``: :math:`\mathbf k \times \mathbf r`, both (N, 3)).
    """
    from math import factorial
    w = np.asarray(w, dtype=float)
    return np.array([((-1.0) ** (j // 2) / factorial(j)) * (w ** j)[:, None] * (cross if j % 2 else perp)
                     for j in degrees]).reshape(len(degrees), *np.shape(perp))


def series_degree(theta_max: float, radius: float, tolerance: float = 1e-10) -> int:
    """The degree at which a rotation's Taylor series (:func:`rotation_terms`) is cut: its next term is below
    ``tolerance`` (m) for every angle up to ``theta_max`` at ``radius`` (m) from the axis."""
    from math import factorial
    degree = 1
    while theta_max ** (degree + 1) / factorial(degree + 1) * radius > tolerance and degree < 40:
        degree += 1
    return degree


def closing_scale(points: np.ndarray, field: np.ndarray, target: np.ndarray, axes: np.ndarray,
                  overlap: float = 0.0, column: float = 1e-3, most: float = 3.0) -> np.ndarray:
    """Per-vertex factors (N,) that size a downward ``field`` (N, 3), a Gaussian push (:func:`local_displacement`),
    by the gap it closes (the eye's own opening): at each ``column`` (m) across the frame's x, the moved region's
    lowest vertex (its margin) comes onto the highest of ``target`` (indices: the lid below) within a column of
    it and ``overlap`` (m) past; interpolated in x between. Columns barely open (under a quarter of the widest)
    or with a factor over twice the median (a margin the target's band misses), the corners, take their
    neighbours'; columns the field hardly moves (under 5 % of its most) keep 1; factors are at most ``most``.
    """
    p = np.asarray(points, dtype=float) @ np.asarray(axes, dtype=float).T
    dy = np.asarray(field, dtype=float) @ np.asarray(axes, dtype=float)[1]
    moved = np.flatnonzero(-dy > 0.05 * max(float(-dy.min()), 0.0))
    scale = np.ones(len(p))
    if not len(moved):
        return scale
    target, got = np.asarray(target), []
    for x in np.arange(p[moved, 0].min(), p[moved, 0].max() + column, column):
        here = moved[np.abs(p[moved, 0] - x) <= 0.5 * column]
        if not len(here):
            continue
        margin = here[np.argmin(p[here, 1])]
        # the lid below: its highest within a column of the margin (a scan's rows do not fall in every column)
        below = target[np.abs(p[target, 0] - p[margin, 0]) <= column]
        if len(below):
            got.append((p[margin, 0], p[margin, 1] - p[below, 1].max() + overlap, -dy[margin]))
    if got:
        x, need, travel = np.array(got).T
        s, wide = need / travel, need > 0.25 * need.max()
        keep = wide & (s < 2.0 * np.median(s[wide]))          # the corners take their neighbours'
        on = (dy < 0) & (p[:, 0] >= p[moved, 0].min() - column) & (p[:, 0] <= p[moved, 0].max() + column)
        scale[on] = np.interp(p[on, 0], x[keep], np.clip(s[keep], 0.0, most))
    return scale
