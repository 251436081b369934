"""The simulation state round-trips exactly; the film's openings are measured slab by slab."""

from __future__ import annotations

import io

import numpy as np

from visemeface.physics.state import SimState


def test_state_round_trips_through_npz_bit_for_bit():
    rng = np.random.default_rng(1)
    saliva = {"broken": rng.random(7) > 0.5, "dry": rng.random(7) > 0.8, "stored": rng.normal(size=(7, 8, 3)),
              "stretch": rng.random(7) + 1.0, "flow": rng.random(7) * 0.1, "damage": rng.random(7)}
    st = SimState(rng.normal(size=(20, 3)), rng.normal(size=(20, 3)), 12345, 1.0 / 60 / 1667, saliva)
    buf = io.BytesIO()
    np.savez(buf, **st.to_dict())
    buf.seek(0)
    with np.load(buf, allow_pickle=False) as z:
        back = SimState.from_dict({k: z[k] for k in z.files})
    assert back.step == st.step and back.dt == st.dt and back.t == st.t
    for a, b in ((back.u, st.u), (back.u_prev, st.u_prev), *((back.saliva[k], st.saliva[k]) for k in saliva)):
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(a, b)
    c = st.copy()
    c.u[0, 0] += 1.0
    c.saliva["broken"][:] = ~c.saliva["broken"]
    assert st.u[0, 0] != c.u[0, 0] and (st.saliva["broken"] != c.saliva["broken"]).all()   # a deep copy
    # a checkpoint from before the film had a cohesive damage resumes with none
    old = {k: v for k, v in st.to_dict().items() if k != "saliva_damage"}
    np.testing.assert_array_equal(SimState.from_dict(old).saliva["damage"], np.zeros(7))


def test_film_openings_grow_slab_by_slab(fem_face):
    from visemeface.physics.film import FILM_ELEMENTS, SalivaFilm
    from visemeface.physics.openings import film_openings
    fem = fem_face
    film = SalivaFilm(fem.mesh.nodes, fem.mesh.hexes[fem.saliva], fem.seam_s[fem.saliva_pairs],
                      lambda s: np.zeros(len(s)), across=len(fem.seam_pairs) - 1)
    assert len(np.unique(film.s)) >= FILM_ELEMENTS
    upper = np.unique(film.n0[:, [2, 3, 6, 7]])
    x = fem.mesh.nodes[upper, 0]
    spans = []
    for half in np.linspace(0.0, 0.5, 11) * fem.mouth_width:
        u = np.zeros_like(fem.mesh.nodes)
        u[upper, 1] = 0.1 * fem.mouth_width * np.clip(1.0 - np.abs(x) / max(half, 1e-9), 0.0, 1.0)
        op = film_openings(film, u, fem.mouth_width)
        assert op["count"] == (1 if op["span"] > 0 else 0)
        spans.append(op["span"])
    assert np.all(np.diff(spans) >= 0) and len(set(np.round(spans, 4))) >= 8       # grows in many steps
