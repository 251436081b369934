"""Mouth opening inside the face mesh's inner-lip contour (the default method of ``analyze``).

Segmenting the lips by colour (:mod:`~visemeface.analysis.lips`: redder than
skin) has little to hold on when the lips are the skin's own tone, a
moustache sits above them or the video is grey. This method takes *where*
the opening can be from the face mesh (MediaPipe's 468-point model,
:mod:`~visemeface.analysis.landmarks`; ``MouthBox.lips``) and *whether* it is
open from image evidence measured relative to the speaker's own lips, so no
absolute colour or lightness enters:

1. The region is resampled to at least
   :data:`~visemeface.analysis.lips.WORK_WIDTH` px across the mouth (as the
   ``lips`` method) and smoothed (Gaussian, 0.75 original pixels).
2. *Bound*: the inner-lip polygon grown by :data:`BOUND_GROW` of the mouth
   width up and down (the mesh's inner contour is smooth and sits inside the
   visible opening, by up to 2-4 px on a 40 px GRID mouth), never beyond the
   outer lip contour shrunk by :data:`OUTER_SHRINK`: a moustache, a beard or
   the nostrils lie outside the outer contour and are never looked at. Teeth or
   a cavity may run on past the bound into a thin *halo* (:data:`HALO`) and end
   there; what reaches the halo's edge over the middle of the mouth is hair or
   skin, not an opening.
3. *Reference*: the lips themselves, the pixels between the outer contour
   and the bound, the upper and the lower lip apart (one is often shaded):
   median CIE lightness :math:`\\tilde L_u, \\tilde L_l` and chroma
   :math:`\\tilde C_u, \\tilde C_l` (OpenCV's 8-bit Lab). A pixel of the bound
   above the inner contour's mid-line is compared with the upper lip, one
   below it with the lower lip (with the lower lip where the upper is much less
   coloured, :data:`SAME_LIP`: a moustache over it).
4. *Evidence* (:func:`evidence`): a pixel is unlike lip when it is a dark
   cavity, :math:`L \\le \\rho_d \\tilde L`; a tooth, brighter
   :math:`L \\ge \\rho_b \\tilde L` or, when the lips have colour at all
   (:math:`\\tilde C \\ge` :data:`MIN_LIP_CHROMA`), greyer,
   :math:`C \\le \\rho_c \\tilde C` and not darker than the lip; these are
   ratios, the same on light and dark skin and in grey video (where the
   chroma cue is off). The teeth, tongue and cavity between the first and the
   last unlike pixel of a column are the opening (a tongue is lip-coloured).
5. *Shape* (:func:`~visemeface.analysis.lips.plausible_openings`): a region
   less than ``min_height`` thick is the seam of closed lips; one narrower is
   a speck. Lip-like columns between two openings (lips glued at the centre)
   are not bridged beyond :data:`BRIDGE` of the mouth width, so two openings
   with a glued centre count as two.

Where no mesh is known for a frame (a box given by hand or a sidecar, or a
close-up without eyes the face detector cannot find), the bound and the
reference come from the lips segmented by colour (the ``lips`` method's
region enclosed between them, :func:`~visemeface.analysis.lips.lip_mask`), and
steps 3-5 are the same.
"""

from __future__ import annotations

import cv2
import numpy as np

from visemeface.analysis.lips import _odd, enclosed_mask, lip_mask, plausible_openings, work_scale
from visemeface.numeric import quantile

#: Bound: the inner-lip polygon grown up and down by this fraction of the mouth width. Tuned on
#: swwp2s and bbaf2n (../shared/realdata): the hand-read opening reaches up to 0.1 w beyond the
#: mesh's inner contour.
BOUND_GROW = 0.08

#: ... tapering (as an ellipse over the inner contour's width) to this fraction of it at the corners,
#: where the lips meet and an opening is never as tall as at the centre.
CORNER_GROW = 0.3

#: Halo: teeth or a cavity may run past the bound by up to this fraction of the mouth width more (as the
#: bound, tapering to the corners) and end there, enclosed by lip; unlike pixels that reach the halo's edge
#: are hair or skin. At 0 (the bound's own edge) an /eh/ or /iy/ of swwp2s whose upper lip lifts off the
#: teeth reads as closed (the teeth run past the bound). 0.02 is the smallest that reads every hand-labelled
#: open frame of the three GRID clips as open.
HALO = 0.02

#: Reference: lips are one tissue, so an upper lip much less coloured than the lower (its chroma below this
#: fraction of the lower's) has something over it -- a moustache -- and is compared with the lower lip's
#: lightness and chroma instead. The GRID lips differ by at most 10 %; 0.7-0.9 read the same.
SAME_LIP = 0.8

#: Bound: the outer lip contour shrunk by this fraction of the mouth width (its own few-pixel error:
#: the skin just outside the lips, a moustache's edge, is never opening).
OUTER_SHRINK = 0.02

#: Reference: the lips' pixels between the bound and the outer contour shrunk by this fraction of the
#: mouth width (a moustache hanging over the upper lip, the skin just outside the mesh's outline).
REF_SHRINK = 0.05

#: Unlike-lip pixels connected to the bound's top or bottom edge over this middle fraction of the
#: mouth (of the inner contour's half width) are hair or skin, not an opening: an opening is
#: enclosed by lips.
EDGE_SPAN = 0.6

#: Reference: lip pixels darker than this fraction of the 90th percentile of their side's lightness
#: are hair (a moustache over the lip's edge) or shadow and left out of its median.
HAIR_RATIO = 0.7

#: A cavity pixel is at most this fraction of the lip's lightness (:math:`Y^{1/3}`, like all the ratios
#: here; tuned as 0.72 of CIE L* on swwp2s and bbaf2n, then carried over to :math:`Y^{1/3}`).
DARK_RATIO = 0.79

#: A tooth is at least this multiple of the lip's lightness ...
BRIGHT_RATIO = 1.11

#: ... or, where the lips have colour, whiter than lip: :math:`L / \tilde L - C / \tilde C` at least this
#: (and :math:`L \ge 0.9 \tilde L`). Tuned on swwp2s and bbaf2n: tooth-like pixels of closed frames
#: reach 0.32, swwp2s's teeth (barely brighter than its lips, much greyer) 0.4-0.56.
WHITENESS = 0.33

#: ... or at most this fraction of the lips' chroma, whatever its lightness (teeth in shadow, the tongue's
#: underside).
GREY_RATIO = 0.65

#: Below this median chroma (8-bit Lab a*, b* about 128) the lips have no colour to compare
#: (grey-scale video): the chroma cue is off.
MIN_LIP_CHROMA = 6.0

#: Lip-like columns between two unlike ones are bridged up to this fraction of the mouth width
#: (a shaded gap between two teeth); wider ones (lips glued together) separate two openings.
BRIDGE = 0.025

#: A region is an opening when it shows teeth over at least this area (fraction of the mouth width
#: squared) ...
TEETH_AREA = 0.002

#: ... or a cavity at most :data:`DEEP_RATIO` of the lip's lightness at least this thick (fraction of
#: the mouth width, the thickest column). Both tuned on swwp2s and bbaf2n: the shaded seam of their
#: closed lips is at most 2.6 px (0.068 w) deep-dark and shows at most 1.5 px of tooth-like pixels;
#: their open frames without teeth are 3.0 px (0.077 w) or more.
DEEP_THICK = 0.065

#: A cavity pixel for :data:`DEEP_THICK`.
DEEP_RATIO = 0.7

#: A region's cavity thickness: this percentile over its columns of the cavity pixels in each (a
#: closed seam darkens into the corners; an opening is deep over much of its width).
DEPTH_PERCENTILE = 80

#: The opening's edge: this fraction of the way from the darkest cavity (5th percentile) to the lip.
EDGE = 0.4

#: ... or a black cavity (at most this fraction of the lip's lightness; a GRID seam is no darker than
#: 0.53, the mouth of our renders 0.1-0.2) over at least :data:`BLACK_AREA` of the mouth width
#: squared: lips that have just parted. Such a slit counts when it is :data:`THIN_SLIT` of the mouth
#: width thick (at least 2 working pixels), not ``min_height``; only for a mouth at least
#: :data:`~visemeface.analysis.lips.WORK_WIDTH` px wide (not resampled: on a small, blurred mouth the
#: seam of closed lips is as dark as a 1-2 px gap; the GRID clips' seams reach 0.35 when darkened).
BLACK_RATIO = 0.5
BLACK_AREA = 0.0002
THIN_SLIT = 0.006



def _poly_mask(shape, pts: np.ndarray) -> np.ndarray:
    """Filled polygon of float pixel-centre points (4 bits of sub-pixel precision), bool."""
    m = np.zeros(shape, np.uint8)
    cv2.fillPoly(m, [np.round(pts * 16).astype(np.int32)], 1, lineType=cv2.LINE_8, shift=4)
    return m.view(bool)


#: sRGB level (0..255) -> linear relative luminance contribution, per channel.
_LINEAR = np.where(np.arange(256) / 255.0 <= 0.04045, np.arange(256) / 255.0 / 12.92,
                   ((np.arange(256) / 255.0 + 0.055) / 1.055) ** 2.4).astype(np.float32)
#: Rec.709 luminance weights of linear r, g, b.
_LUMA = np.array([[0.2126, 0.7152, 0.0722]], np.float32)


def _lab(crop: np.ndarray, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Lightness :math:`255\\,Y^{1/3}` (``Y`` the linear luminance: a darker skin multiplies reflectance,
    so ratios of this lightness are the same on any skin, unlike CIE L*'s near black) and Lab chroma."""
    lab = cv2.cvtColor(crop, cv2.COLOR_RGB2LAB)
    ab = cv2.GaussianBlur(lab[..., 1:].astype(np.float32) - 128.0, (0, 0), sigma)
    y = cv2.transform(cv2.LUT(crop, _LINEAR), _LUMA)
    light = cv2.GaussianBlur(255.0 * np.cbrt(y), (0, 0), sigma)
    return light, cv2.magnitude(np.ascontiguousarray(ab[..., 0]), np.ascontiguousarray(ab[..., 1]))


def evidence(light: np.ndarray, chroma: np.ndarray, ref_l, ref_c) -> tuple[np.ndarray, np.ndarray]:
    """Pixels unlike lip (bool): a dark cavity, and teeth (bright or, where lips have colour, white).

    ``ref_l`` and ``ref_c`` are the lip's lightness and chroma per pixel (broadcastable).
    """
    dark = light <= DARK_RATIO * ref_l
    rel = light / np.maximum(ref_l, 1.0)
    teeth = rel >= BRIGHT_RATIO
    crel = chroma / np.maximum(ref_c, 1.0)
    teeth |= (ref_c >= MIN_LIP_CHROMA) & (((rel >= 0.9) & (rel - crel >= WHITENESS)) | (crel <= GREY_RATIO))
    return dark, teeth


def _lip_reference(light: np.ndarray, chroma: np.ndarray, mask: np.ndarray) -> tuple[float, float]:
    """Median lightness and chroma of the lip pixels in ``mask``, hair and shadow left out: pixels
    darker than :data:`HAIR_RATIO` x the 90th percentile of their lightness do not count."""
    sel = light[mask]
    keep = sel >= HAIR_RATIO * quantile(sel, 0.9)
    return quantile(sel[keep], 0.5), quantile(chroma[mask][keep], 0.5)


def openings_in(light, chroma, bound, upper, lower, mid_row, min_px: float, bridge_px: float,
                outer_edge: np.ndarray | None = None, slits: bool = True, halo: np.ndarray | None = None
                ) -> np.ndarray:
    """0/1 uint8 opening mask inside ``bound`` given the upper/lower lip reference masks.

    ``mid_row`` ``(W,)`` is the row of the inner contour's mid-line in each column: pixels above it
    are compared with the upper lip, below with the lower. Unlike-lip pixels connected to
    ``outer_edge`` (bool, the pixels of the bound on the outer lip contour) are not an opening.
    ``slits``: whether a black gap thinner than ``min_px`` can be an opening (only in an image
    analysed at its own resolution: resampled up, a seam's blur and a 1-2 px gap look alike).
    """
    if not bound.any() or not (upper.any() or lower.any()):
        return np.zeros(bound.shape, np.uint8)
    lips = upper | lower
    up = upper if upper.sum() >= 8 else lips
    lo = lower if lower.sum() >= 8 else lips
    (lu, cu), (ll, cl) = _lip_reference(light, chroma, up), _lip_reference(light, chroma, lo)
    if cu < SAME_LIP * cl:                  # something over the upper lip (a moustache): the lower lip's colour
        lu, cu = ll, cl
    rows = np.arange(bound.shape[0])[:, None]
    above = rows < mid_row[None, :]
    ref_l = np.where(above, lu, ll).astype(np.float32)
    ref_c = np.where(above, cu, cl).astype(np.float32)
    dark, teeth = evidence(light, chroma, ref_l, ref_c)
    around = bound if halo is None else halo | bound
    # specks of noise: an opening pixel has unlike neighbours
    k = np.ones((3, 3), np.uint8)
    unlike = cv2.morphologyEx(((dark | teeth) & around).view(np.uint8), cv2.MORPH_OPEN, k)
    dark &= bound
    teeth &= bound
    deep = dark & (light <= DEEP_RATIO * ref_l)
    if slits:
        unlike |= (bound & (light <= BLACK_RATIO * ref_l)).view(np.uint8)
    # an opening is enclosed by lips: what is unlike lip where the halo (or the bound) meets the outer lip
    # contour (a moustache, a beard, the skin beyond a contour drawn too wide) is not part of it
    n_u, lab_u = cv2.connectedComponents(unlike, connectivity=8)
    touching = np.zeros(n_u, bool)
    if outer_edge is not None:
        touching[np.unique(lab_u[outer_edge & (unlike > 0)])] = True
    touching[0] = True
    unlike = ~touching[lab_u] & bound
    dark &= unlike
    teeth &= unlike
    deep &= unlike
    big = bound.shape[0]
    first = np.where(unlike, rows, big).min(axis=0)
    last = np.where(unlike, rows, -1).max(axis=0)
    span = ((rows >= first) & (rows <= last) & bound).view(np.uint8)
    kb = _odd(bridge_px)
    if kb > 1:
        span = cv2.morphologyEx(span, cv2.MORPH_CLOSE, np.ones((1, kb), np.uint8)) & bound.view(np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(span, connectivity=8)
    wpx = bridge_px / BRIDGE
    out = np.zeros_like(span)
    thin = np.zeros_like(span)
    for i in range(1, n):
        x, y, w, h = (int(v) for v in stats[i, :4])
        win = np.s_[y:y + h, x:x + w]
        region = labels[win] == i
        tooth = teeth[win] & region
        depth = quantile((deep[win] & region).sum(axis=0), DEPTH_PERCENTILE / 100)
        lw = light[win]
        black = slits and int(((lw <= BLACK_RATIO * ref_l[win]) & region).sum()) >= BLACK_AREA * wpx * wpx
        if tooth.sum() < TEETH_AREA * wpx * wpx and depth < DEEP_THICK * wpx and not black:
            continue
        # the opening's edge a fraction EDGE of the way from the region's darkest cavity to the lip:
        # the shaded inner lip around a deep cavity is lip
        slit = black and depth < DEEP_THICK * wpx
        if slit:                            # just parted: the black gap and what shows through it, which
            gap = region & (lw <= BLACK_RATIO * ref_l[win])         # lies between the gap's first and last
            cols = np.flatnonzero(gap.any(axis=0))                   # column (a lip's highlight beside it
            through = np.zeros(w, bool)                              # is no tooth)
            through[cols[0]:cols[-1] + 1] = True
            edge = gap | (tooth & through[None, :])
        else:
            floor = quantile(lw[region], 0.05)
            edge = region & ((lw <= floor + EDGE * (ref_l[win] - floor)) | tooth)
        r = rows[y:y + h]
        top = np.where(edge, r, big).min(axis=0)
        bot = np.where(edge, r, -1).max(axis=0)
        piece = ((r >= top) & (r <= bot) & region).view(np.uint8)
        if slit:
            thin[win] |= piece
        else:
            out[win] |= piece
    box = (0, 0, out.shape[1], out.shape[0] + 1)            # every region lies "above the box's bottom"
    # a black slit (the first gap of lips parting) is an opening however thin; thicker than a line
    found = plausible_openings(np.pad(out, 1), box, min_px)[1:-1, 1:-1]
    if thin.any():
        found |= plausible_openings(np.pad(thin, 1), box, max(2.0, THIN_SLIT * wpx))[1:-1, 1:-1]
    return found


def mesh_opening_mask(crop: np.ndarray, box_in_crop, lips_in_crop: np.ndarray | None, mouth_width: int,
                      min_height: float = 0.05, min_chroma: float = 6.0
                      ) -> tuple[np.ndarray, float | None, float]:
    """uint8 opening mask (255 = opening) at the working scale, a level (None: no mouth) and the scale.

    ``lips_in_crop`` is the face mesh's ``(40, 2)`` outer then inner lip contour in crop pixels, or None
    (the bound then comes from the lips segmented by colour, module notes). The level returned is the
    lips' median lightness (8-bit Lab L), for the ``threshold`` column of a detection.
    """
    s = work_scale(mouth_width)
    if s > 1.0:
        crop = cv2.resize(crop, None, fx=s, fy=s, interpolation=cv2.INTER_LINEAR)
    light, chroma = _lab(crop, 0.75 * s)
    shape = light.shape
    wpx = mouth_width * s
    if lips_in_crop is not None:
        pts = (np.asarray(lips_in_crop, float) + 0.5) * s - 0.5
        outer, inner = pts[:20], pts[20:]
        o_mask = _poly_mask(shape, outer)
        shrink = max(1, int(round(OUTER_SHRINK * wpx)))
        o_in = cv2.erode(o_mask.view(np.uint8), np.ones((2 * shrink + 1, 2 * shrink + 1), np.uint8)).view(bool)
        # face.toml's inner contour: corner 78, the lower lip's edge (95 ... 324), corner 308, the upper's
        lower_edge, upper_edge = inner[:11], np.vstack([inner[10:], inner[:1]])
        cols = np.arange(shape[1], dtype=float)
        top = _curve(upper_edge, cols)
        bot = _curve(lower_edge, cols)
        x0, x1 = inner[:, 0].min(), inner[:, 0].max()
        half = max(1.0, (x1 - x0) / 2)
        u = np.clip(np.abs(cols - (x0 + x1) / 2) / half, 0, 1)
        taper = wpx * np.maximum(np.sqrt(1 - u * u), CORNER_GROW)
        inside_x = (cols >= x0 - OUTER_SHRINK * wpx) & (cols <= x1 + OUTER_SHRINK * wpx)
        rows = np.arange(shape[0], dtype=float)[:, None]

        def grown(by: float) -> np.ndarray:
            """The inner contour grown up and down by ``by`` of the mouth width (tapered to the corners)."""
            g = by * taper
            return ((rows >= (np.minimum(top, bot) - g)[None, :]) & (rows <= (np.maximum(top, bot) + g)[None, :])
                    & inside_x[None, :])

        band = grown(BOUND_GROW)
        bound = band & o_in
        # the halo, and its top and bottom edge over the middle of the mouth (at the corners the contours
        # meet and the shaded corner of an opening reaches them)
        halo = grown(BOUND_GROW + HALO) & o_in
        b8 = halo.view(np.uint8)
        inner_rows = np.vstack([b8[1:], np.zeros_like(b8[:1])]) & np.vstack([np.zeros_like(b8[:1]), b8[:-1]])
        outer_edge = halo & ~inner_rows.view(bool) & (u <= EDGE_SPAN)[None, :]
        # the lips' own colour away from their outer edge (a moustache or the mesh's error overlaps it)
        core = max(1, int(round(REF_SHRINK * wpx)))
        ref = cv2.erode(o_mask.view(np.uint8), np.ones((2 * core + 1, 2 * core + 1), np.uint8)).view(bool) & ~band
        if ref.sum() < 16:
            ref = o_mask & ~band
        mid_row = (top + bot) / 2
    else:
        bx = tuple(int(round(v * s)) for v in box_in_crop)
        lips, t = lip_mask(crop, bx, s, min_chroma)
        if t is None:
            return np.zeros(shape, np.uint8), None, s
        bound = enclosed_mask(lips)
        bound = plausible_openings(bound.view(np.uint8), bx, 0.5 * min_height * wpx).view(bool)
        ref = lips
        outer_edge = halo = None
        cols = np.flatnonzero(bound.any(axis=0))
        rows = np.arange(shape[0])[:, None]
        top = np.where(bound, rows, shape[0]).min(axis=0)
        bot = np.where(bound, rows, -1).max(axis=0)
        mid_row = np.where(bot >= 0, (top + bot) / 2.0, np.nan)
        if cols.size:
            mid_row = np.interp(np.arange(shape[1]), cols, mid_row[cols])
        else:
            mid_row = np.full(shape[1], shape[0] / 2.0)
    rows = np.arange(shape[0])[:, None]
    upper = ref & (rows < mid_row[None, :])
    lower = ref & ~upper
    if not ref.any():
        return np.zeros(shape, np.uint8), None, s
    mask = openings_in(light, chroma, bound, upper, lower, mid_row, min_height * wpx, BRIDGE * wpx, outer_edge,
                       slits=s == 1.0, halo=halo)
    return mask * np.uint8(255), quantile(light[ref], 0.5), s


def _curve(pts: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Row of the polyline ``pts`` (corner to corner) at each column (held flat beyond its ends)."""
    order = np.argsort(pts[:, 0], kind="stable")
    return np.interp(cols, pts[order, 0], pts[order, 1])
