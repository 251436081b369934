"""The renderer's GLSL: per-vertex lighting of a face (:class:`visemeface.render.renderer.Renderer`)."""

from __future__ import annotations

# Lighting is evaluated per vertex (Gouraud). At the default face's density a
# triangle covers a few pixels at 512x512, so the picture matches per-pixel
# shading, while Mesa's software rasteriser runs a trivial fragment shader
# about 1.6x faster (benchmarks/render.py). Two-sided triangles are lit on
# both sides in the vertex stage, and the fragment stage picks the side facing
# the camera; one-sided ones (back faces culled) are lit on the front only, by
# the same source compiled without TWO_SIDED (a fifth less time on the ICT head).
_VERTEX_SHADER = """
uniform mat4 u_mvp;
uniform mat4 u_view;
in vec3 in_pos;
in vec3 in_normal;
in vec3 in_color;
in float in_fold;
out vec3 v_front;
#ifdef TWO_SIDED
out vec3 v_back;
#endif

vec3 shade(vec3 n, vec3 view_dir, vec3 color) {
    // key light from the upper left of the camera, fill from the right, in eye space
    vec3 key = normalize(vec3(-0.45, 0.55, 0.75));
    vec3 fill = normalize(vec3(0.6, 0.1, 0.6));
    float diff = 0.72 * max(dot(n, key), 0.0) + 0.25 * max(dot(n, fill), 0.0);
    float spec = pow(max(dot(n, normalize(key + view_dir)), 0.0), 28.0);
    vec3 c = color * (0.30 + diff) + 0.07 * spec * vec3(1.0, 0.97, 0.94) * length(color);
    return pow(clamp(c, 0.0, 1.0), vec3(1.0 / 1.15));
}

void main() {
    gl_Position = u_mvp * vec4(in_pos, 1.0);
    vec3 n = normalize(mat3(u_view) * in_normal);
    vec3 view_dir = normalize(-(u_view * vec4(in_pos, 1.0)).xyz);
    vec3 color = in_color * (1.0 - in_fold);     // compressed skin: a fold's shade (render/folds.py)
    v_front = shade(n, view_dir, color);
#ifdef TWO_SIDED
    v_back = shade(-n, view_dir, color);
#endif
}
"""

_FRAGMENT_SHADER = """
in vec3 v_front;
out vec4 f_color;
#ifdef TWO_SIDED
in vec3 v_back;
void main() {
    f_color = vec4(gl_FrontFacing ? v_front : v_back, 1.0);
}
#else
void main() {
    f_color = vec4(v_front, 1.0);
}
#endif
"""


def shader(stage: str, two_sided: bool) -> str:
    """The face's ``"vertex"`` or ``"fragment"`` shader, lighting both sides or (one-sided) the front only."""
    source = {"vertex": _VERTEX_SHADER, "fragment": _FRAGMENT_SHADER}[stage]
    return "#version 330\n" + ("#define TWO_SIDED\n" if two_sided else "") + source
