"""The live mouth is the offline timeline: the same frames once the phones are known, made on time."""

import numpy as np
import pytest

from visemeface.live.mouth import LiveMouth
from visemeface.speech.align import _segments
from visemeface.speech.timeline import activation_track

#: "bob ran home" as a decoder gives it (ARPAbet, silences), seconds.
PHONES = [("SIL", 0.0, 0.30), ("B", 0.30, 0.38), ("AA", 0.38, 0.55), ("B", 0.55, 0.62), ("R", 0.62, 0.70),
          ("AE", 0.70, 0.86), ("N", 0.86, 0.93), ("HH", 0.93, 1.00), ("OW", 1.00, 1.20), ("M", 1.20, 1.31),
          ("SIL", 1.31, 1.80)]


@pytest.fixture(scope="module")
def mouth_of(rig):
    def make(**kw):
        return LiveMouth(rig, ["arkit"], **kw)
    return make


def _stream(mouth, phones, end, step=0.01):
    frames, t = [], 0.0
    while t < end - 1e-9:
        t = min(end, t + step)
        known = [p for p in phones if p[1] < t]
        frames += mouth.advance(known, min(t, end), t)
    return frames + mouth.advance(phones, end, end, final=True)


def test_with_the_phones_known_the_frames_are_the_offline_tracks(rig, mouth_of):
    mouth = mouth_of(fps=30.0, latency=0.1)
    frames = []
    for k in range(0, 52):                     # every phone known from the start: no provisional ones
        frames += mouth.advance(PHONES, 1.8, k / 30 + 0.1)
    frames += mouth.advance(PHONES, 1.8, 1.8, final=True)
    offline = rig.track_matrix(activation_track(_segments(PHONES, 1.8, "t"), mouth.visemes, fps=30.0,
                                                ranges=mouth.ranges))
    assert [f.index for f in frames] == list(range(len(offline)))
    live = np.array([f.activations for f in frames])
    assert np.max(np.abs(live[:40] - offline[:40])) < 1e-6            # the window starts at 0
    assert np.max(np.abs(live - offline)) < 1e-5     # later its first phone is cut at its start: 2e-6 here


def test_a_frame_is_made_once_its_latency_has_been_heard(mouth_of):
    mouth = mouth_of(fps=30.0, latency=0.13)
    assert mouth.advance(PHONES, 0.2, 0.129) == []
    made = mouth.advance(PHONES, 0.2, 0.13 + 1e-9)
    assert [f.index for f in made] == [0]
    made = mouth.advance(PHONES, 0.3, 0.13 + 2 / 30 + 1e-9)
    assert [f.index for f in made] == [1, 2]


def test_bilabials_close_when_streamed_and_the_closure_is_what_clients_get(rig, mouth_of):
    """The streamed ARKit weights played on an ARKit rig (the reference ICT shapes) as a client plays them."""
    from visemeface.retarget import check
    from visemeface.retarget.rigs import arkit_names, canonical, reference_rig

    ict, names = reference_rig(), arkit_names()
    keys = [canonical(n) if canonical(n) in names else canonical(n).rsplit("_", 1)[0] for n in ict.shapes.names]

    def gap(w52):
        w = np.array([w52[names.index(k)] for k in keys])
        return check.measure(ict.face, ict.fit().play(w[None])).gap[0]

    mouth = mouth_of(fps=30.0, latency=0.13)
    frames = _stream(mouth, PHONES, 1.8)
    assert mouth.names("arkit") == names
    for _, s, e in [p for p in PHONES if p[0] in ("B", "M")]:
        f = frames[int(round((s + e) / 2 * 30))]
        assert f.phone in ("b", "m")
        assert abs(gap(f.weights["arkit"])) <= 1.5, f"lips open at {f.time:.2f} s"
    assert gap(frames[int(0.47 * 30)].weights["arkit"]) > 3.0


def test_catching_up_retargets_only_the_newest_frame(mouth_of):
    mouth = mouth_of(fps=30.0, latency=0.1)
    made = mouth.advance(PHONES, 1.0, 0.9, newest_only=True)
    assert len(made) > 5 and all(f.weights is None for f in made[:-1]) and made[-1].weights is not None
    assert all(f.activations is not None for f in made)


def test_the_driven_shapes_leave_the_eyes_to_the_client(mouth_of):
    mouth = mouth_of()
    names = mouth.names("arkit")
    driven = {n for n, d in zip(names, mouth.driven("arkit")) if d}
    assert {"jawOpen", "mouthClose", "mouthPucker"} <= driven
    assert not {n for n in driven if n.startswith("eyeBlink")}
