"""Segments -> ActivationTrack: interpolation, coarticulation, guaranteed closure, emotions, CSV."""

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from visemeface.errors import InputError
from visemeface.postures.phonemes import DECTALK, VOWELS
from visemeface.speech.timeline import MODES, activation_track, emotion_weights, load_track, save_track

ROUNDED = ("uw", "ow", "uh", "ao", "w", "oy", "yu", "or", "ur")


def toy_visemes():
    """A table where lip closure, contact and rounding are known column values.

    ``closure`` is 1 exactly for p b m (and ``jaw`` 0), ``contact`` 1 for f v,
    ``orbicularis_oris`` (rounding) 1 for rounded vowels and /w/.
    """
    rows = {}
    for s in DECTALK:
        rows[s] = dict(jaw=0.6 if s in VOWELS else 0.2, orbicularis_oris=1.0 if s in ROUNDED else 0.0,
                       closure=0.0, contact=0.0, risorius_left=0.7 if s in ("iy", "ih", "eh", "ae") else 0.0)
    for s in ("p", "b", "m"):
        rows[s].update(jaw=0.0, closure=1.0)
    for s in ("f", "v"):
        rows[s].update(jaw=0.05, contact=1.0)
    rows["_"].update(jaw=0.0)
    table = pd.DataFrame.from_dict(rows, orient="index")
    table["notes"] = "toy"            # non-numeric columns are ignored
    return table


def segs(phones, dur, lead=0.3):
    """Segments: lead silence, then phones of equal duration, then silence."""
    starts = [0.0] + [lead + i * dur for i in range(len(phones))] + [lead + len(phones) * dur]
    ends = starts[1:] + [starts[-1] + lead]
    return pd.DataFrame({"start": starts, "end": ends, "phoneme": ["_"] + list(phones) + ["_"]})


def test_frames_index_and_fps():
    seg = segs(["m", "aa"], 0.1)                     # 0.8 s
    track = activation_track(seg, toy_visemes(), fps=25)
    assert len(track) == math.ceil(0.8 * 25) and track.index.name == "time"
    assert track.attrs["fps"] == 25
    assert np.allclose(np.diff(track.index), 1 / 25)
    assert list(track.columns) == ["jaw", "orbicularis_oris", "closure", "contact", "risorius_left"]


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("fps", [24, 30, 60])
def test_lips_close_on_every_bilabial_at_15_phones_per_second(mode, fps):
    rng = np.random.default_rng(fps)
    consonants = ["p", "b", "m", "f", "v", "t", "s", "k", "w", "r"]
    vowels = ["aa", "iy", "uw", "ae", "ow", "ah"]
    phones = []
    for _ in range(40):
        phones += [str(rng.choice(consonants)), str(rng.choice(vowels))]
    phones += ["b", "m", "p", "aa", "m", "b", "iy", "f", "v", "b", "ae", "v", "p"]    # clusters
    seg = segs(phones, 1 / 15)
    track = activation_track(seg, toy_visemes(), fps=fps, mode=mode)
    t = track.index.to_numpy()
    n_checked = 0
    for s, e, p in zip(seg.start, seg.end, seg.phoneme):
        inside = (t >= s) & (t <= e)
        if p in ("p", "b", "m"):
            closed = (track["closure"][inside] == 1.0) & (track["jaw"][inside] == 0.0)
            assert closed.any(), f"lips never close on /{p}/ at {s:.3f}-{e:.3f} s ({mode}, {fps} fps)"
            n_checked += 1
        if p in ("f", "v"):
            assert (track["contact"][inside] == 1.0).any(), f"no lip-teeth contact on /{p}/ at {s:.3f} s"
    assert n_checked >= 12


def test_plain_cohen_massaro_would_not_close_in_fast_speech():
    # The guarantee is needed: at 15 phones/s a /b/ between open vowels is undershot by the
    # dominance blend itself. Compare against the closure guaranteed in the track.
    from visemeface.speech import timeline
    seg = segs(["aa", "b", "aa"], 1 / 15)
    start, end = seg.start.to_numpy(), seg.end.to_numpy()
    table = toy_visemes()
    targets = table.select_dtypes("number").loc[list(seg.phoneme)].to_numpy()
    times = np.arange(0, end[-1], 1 / 30)
    raw = timeline._coarticulation(times, start, end, list(seg.phoneme), targets, 0.06)
    assert raw[:, 2].max() < 0.9                                       # closure undershot
    assert activation_track(seg, table, fps=30)["closure"].max() == 1.0


def _onset(track, column, before, fraction=0.1):
    """First time the column exceeds `fraction` of its value at `before`."""
    goal = track[column].asof(before)
    above = track.index[(track[column] >= fraction * goal) & (track.index <= before)]
    return float(above[0])


def test_anticipatory_rounding_starts_earlier_than_linear():
    # "s t uw": the lips round during /s t/ in anticipation of /uw/.
    seg = segs(["iy", "s", "t", "uw"], 0.1)
    table = toy_visemes()
    uw_centre = float(seg.start[4] + 0.05)
    co = activation_track(seg, table, fps=200, mode="coarticulation")
    lin = activation_track(seg, table, fps=200, mode="linear")
    t_co = _onset(co, "orbicularis_oris", uw_centre)
    t_lin = _onset(lin, "orbicularis_oris", uw_centre)
    assert t_co < t_lin - 0.05, (t_co, t_lin)
    assert t_co < float(seg.end[2])          # rounding visible before /t/ has ended
    # Linear interpolation only starts leaving /t/ at its centre.
    assert t_lin >= float(seg.start[3] + 0.05) - 1e-9


@pytest.mark.parametrize("mode", MODES)
def test_constant_column_stays_constant_and_values_stay_within_targets(mode):
    table = toy_visemes()
    table["constant"] = 0.37
    seg = segs(["w", "iy", "p", "uw", "f", "ae", "k"], 0.07)
    track = activation_track(seg, table, fps=50, mode=mode)
    assert np.allclose(track["constant"], 0.37, atol=1e-12)          # weights sum to one
    numeric = table.select_dtypes("number")
    assert (track.min() >= numeric.min() - 1e-12).all() and (track.max() <= numeric.max() + 1e-12).all()


@pytest.mark.parametrize("mode", MODES)
def test_long_segment_holds_its_target(mode):
    seg = pd.DataFrame({"start": [0.0, 0.5, 1.1], "end": [0.5, 1.1, 1.6], "phoneme": ["_", "aa", "_"]})
    track = activation_track(seg, toy_visemes(), fps=100, mode=mode)
    middle = track.loc[0.7:0.9, "jaw"]
    # Keyed modes hold exactly; Cohen-Massaro keeps the neighbours' exponential tails,
    # here alpha_ = 1 against alpha_aa = 0.8 at 0.26 s with theta = 15/s: ~2%.
    assert np.allclose(middle, 0.6, atol=1e-9 if mode != "coarticulation" else 0.02)
    assert np.allclose(track.loc[0.0:0.15, "jaw"], 0.0, atol=5e-3)


def test_linear_mode_is_linear_between_short_segment_centres():
    seg = segs(["t", "aa"], 0.1)                       # centres 0.35 (jaw 0.2) and 0.45 (jaw 0.6)
    track = activation_track(seg, toy_visemes(), fps=1000, mode="linear")
    assert track["jaw"].iloc[400] == pytest.approx(0.4, abs=1e-9)
    cos = activation_track(seg, toy_visemes(), fps=1000, mode="cosine")
    assert cos["jaw"].iloc[375] == pytest.approx(0.2 + 0.4 * (1 - math.cos(math.pi / 4)) / 2, abs=1e-9)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(DECTALK), st.floats(0.02, 0.4)), min_size=1, max_size=25),
       st.sampled_from(MODES), st.sampled_from([15, 24, 30, 60]))
def test_property_track_is_finite_bounded_and_closes(phones, mode, fps):
    starts = np.concatenate([[0.0], np.cumsum([d for _, d in phones])[:-1]])
    ends = starts + [d for _, d in phones]
    seg = pd.DataFrame({"start": starts, "end": ends, "phoneme": [p for p, _ in phones]})
    table = toy_visemes()
    track = activation_track(seg, table, fps=fps, mode=mode)
    values = track.to_numpy()
    assert np.isfinite(values).all()
    numeric = table.select_dtypes("number")
    assert (values >= numeric.min().to_numpy() - 1e-12).all()
    assert (values <= numeric.max().to_numpy() + 1e-12).all()
    t = track.index.to_numpy()
    for s, e, p in zip(starts, ends, seg.phoneme):
        if p in ("p", "b", "m") and e - s >= 1 / fps:
            inside = (t >= s) & (t <= e)
            assert (track["closure"][inside] == 1.0).any()


@pytest.mark.parametrize("mode", MODES)
def test_a_long_labiodental_after_a_short_pause_does_not_reopen_the_closure_before_it(mode):
    # /p/ 1.5 frames long, a 1.5-frame pause, a long /f/: the /f/'s ramp (half its length) reaches back over
    # the pause into the /p/'s one exact frame, which must stay shut
    seg = pd.DataFrame({"start": [0.0, 0.0625, 0.125], "end": [0.0625, 0.125, 0.5], "phoneme": ["p", "_", "f"]})
    track = activation_track(seg, toy_visemes(), fps=24, mode=mode)
    assert (track["closure"].loc[0.0:0.0625] == 1.0).any()
    assert (track["contact"].loc[0.125:0.5] == 1.0).any()


def expressions():
    table = toy_visemes().select_dtypes("number")
    expr = pd.DataFrame(0.0, index=["happiness", "anger", "surprise"], columns=table.columns)
    expr.loc["happiness", "risorius_left"] = 0.5
    expr.loc["anger", "orbicularis_oris"] = 0.4
    expr.loc["surprise", "jaw"] = 0.3
    expr["zygomatic_major_left"] = [0.8, 0.0, 0.0]          # a column the visemes do not use
    return expr


def test_global_emotion_adds_weighted_vector_and_clamps():
    seg = segs(["aa", "iy"], 0.2)
    plain = activation_track(seg, toy_visemes(), fps=30)
    happy = activation_track(seg, toy_visemes(), fps=30, emotions={"happiness": 0.5}, expressions=expressions())
    assert np.allclose(happy["zygomatic_major_left"], 0.4)
    expected = np.clip(plain["risorius_left"] + 0.25, 0, 1)
    assert np.allclose(happy["risorius_left"], expected)
    strong = activation_track(seg, toy_visemes(), fps=30, emotions={"happiness": 3.0}, expressions=expressions())
    assert strong.to_numpy().max() <= 1.0 and strong["zygomatic_major_left"].iloc[0] == 1.0


@pytest.mark.parametrize("mode", MODES)
def test_lips_still_close_under_an_emotion_that_drops_the_jaw(mode):
    seg = segs(["aa", "b", "iy", "m", "ae", "p", "uw", "f", "aa"], 1 / 15)
    track = activation_track(seg, toy_visemes(), fps=30, mode=mode, emotions={"surprise": 1.0},
                             expressions=expressions())
    t = track.index.to_numpy()
    for s, e, p in zip(seg.start, seg.end, seg.phoneme):
        if p in ("p", "b", "m"):
            inside = (t >= s) & (t <= e)
            assert ((track["jaw"][inside] == 0.0) & (track["closure"][inside] == 1.0)).any(), p
    # Away from the closures the surprise still opens the jaw (by its 0.3, up to rounding of the ramp).
    plain = activation_track(seg, toy_visemes(), fps=30, mode=mode)
    assert track["jaw"].max() >= plain["jaw"].max() + 0.25


def test_emotion_key_track_ramps_smoothly():
    seg = segs(["aa"] * 10, 0.1)                           # 1.6 s
    keys = pd.DataFrame({"time": [0.5, 1.2], "emotion": ["anger", "neutral"], "weight": [1.0, 0.0]})
    track = activation_track(seg, toy_visemes(), fps=100, emotions=keys, expressions=expressions(),
                             emotion_ramp=0.2)
    anger = track["orbicularis_oris"]                     # visemes have 0 rounding for /aa/
    assert np.allclose(anger.loc[:0.39], 0.0) and np.allclose(anger.loc[0.61:1.09], 0.4)
    assert np.allclose(anger.loc[1.31:], 0.0)
    steps = np.abs(np.diff(anger.to_numpy()))
    # No jump: the cosine ramp's steepest step is (pi/2) * change * frame / ramp.
    assert steps.max() <= 0.4 * (math.pi / 2) * 0.01 / 0.2 + 1e-9
    assert anger.loc[0.5] == pytest.approx(0.2, abs=1e-9)  # half way at the key time


def test_emotion_keys_of_an_utterance_are_used():
    from visemeface.speech.utterance import Utterance

    keys = pd.DataFrame({"time": [0.0], "emotion": ["surprise"], "weight": [1.0]})
    utt = Utterance(segs(["aa"] * 6, 0.1), emotion_keys=keys)
    track = activation_track(utt, toy_visemes(), fps=50, expressions=expressions())
    plain = activation_track(segs(["aa"] * 6, 0.1), toy_visemes(), fps=50)
    assert np.allclose(track["jaw"].loc[0.3:0.8], np.clip(plain["jaw"].loc[0.3:0.8] + 0.3, 0, 1))


def test_emotion_weights_function():
    w = emotion_weights(np.array([0.0, 1.0, 2.0, 3.0]), ["anger", "fear"], {"fear": 0.2},
                        pd.DataFrame({"time": [1.0], "emotion": ["anger"], "weight": [0.6]}), ramp=0.0)
    assert np.allclose(w, [[0, 0.2], [0.6, 0.2], [0.6, 0.2], [0.6, 0.2]])


def test_bad_inputs():
    seg = segs(["aa"], 0.1)
    with pytest.raises(InputError, match="unknown emotion 'happyness'.*happiness"):
        activation_track(seg, toy_visemes(), emotions={"happyness": 0.5}, expressions=expressions())
    with pytest.raises(InputError, match="unknown emotion 'joy'; known: happiness, anger, surprise$"):   # nothing close: all
        activation_track(seg, toy_visemes(), emotions={"joy": 0.5}, expressions=expressions())
    with pytest.raises(InputError, match="must be finite and >= 0"):
        activation_track(seg, toy_visemes(), emotions={"anger": -1}, expressions=expressions())
    with pytest.raises(InputError, match="must be finite"):
        activation_track(seg, toy_visemes(), emotions={"anger": float("nan")}, expressions=expressions())
    with pytest.raises(InputError, match="no row for phoneme.*zh"):
        activation_track(segs(["zh"], 0.1), toy_visemes().drop(index="zh"))
    with pytest.raises(InputError, match="unknown interpolation mode 'cubic'"):
        activation_track(seg, toy_visemes(), mode="cubic")
    with pytest.raises(InputError, match="frame rate"):
        activation_track(seg, toy_visemes(), fps=0)
    overlapping = pd.DataFrame({"start": [0.0, 0.1], "end": [0.2, 0.3], "phoneme": ["aa", "b"]})
    with pytest.raises(InputError, match="non-overlapping"):
        activation_track(overlapping, toy_visemes())


def test_save_load_round_trip(tmp_path):
    track = activation_track(segs(["b", "uw", "f"], 0.09), toy_visemes(), fps=29.97)
    path = tmp_path / "track.csv"
    save_track(track, path)
    back = load_track(path)
    assert back.attrs["fps"] == 29.97
    pd.testing.assert_frame_equal(back, track, check_exact=True, check_freq=False)
    with pytest.raises(InputError, match="output exists"):
        save_track(track, path)
    save_track(track * 0.5, path, force=True)
    assert np.allclose(load_track(path).to_numpy(), track.to_numpy() * 0.5)


def test_load_track_infers_fps_and_reports_bad_cells(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("time,jaw\n0,0.1\n0.04,0.2\n0.08,0.3\n")
    assert load_track(p).attrs["fps"] == pytest.approx(25)
    p.write_text("# fps=25\ntime,jaw\n0,0.1\n0.04,oops\n")
    with pytest.raises(InputError) as e:
        load_track(p)
    assert e.value.line == 4 and "'oops'" in str(e.value)
    p.write_text("jaw\n0.1\n")
    with pytest.raises(InputError, match="no 'time' column"):
        load_track(p)
    # an fps= line its times contradict, and a slice that kept its old rate, are refused (played at the
    # wrong speed before)
    p.write_text("# fps=30\ntime,jaw\n0,0.1\n0.04,0.2\n0.08,0.3\n")
    with pytest.raises(InputError, match=r"attrs\['fps'\] \(30\) disagrees with its time step \(25 fps\)"):
        load_track(p)
    from visemeface.track import track_fps
    track = activation_track(segs(["aa", "m", "aa"], 0.2), toy_visemes(), fps=30)
    assert track_fps(track) == 30
    with pytest.raises(InputError, match="disagrees"):
        track_fps(track.iloc[::2])


def test_closure_holds_only_the_lip_opening_functions():
    """While /m/ is forced, disgust's nose wrinkler (levator labii superioris *alaeque nasi*) still acts;
    the lip raiser (levator labii superioris) and the jaw do not."""
    seg = segs(["aa", "m", "aa"], 0.2)
    expr = expressions()
    expr["levator_labii_superioris_alaeque_nasi_left"] = [0.0, 0.0, 0.6]
    expr["levator_labii_superioris_left"] = [0.0, 0.0, 0.6]
    track = activation_track(seg, toy_visemes(), fps=30, emotions={"surprise": 1.0}, expressions=expr)
    t = track.index.to_numpy()
    centre = int(np.argmin(np.abs(t - (0.3 + 0.2 + 0.1))))
    assert track["jaw"].iloc[centre] == 0.0
    assert track["levator_labii_superioris_left"].iloc[centre] == 0.0
    assert track["levator_labii_superioris_alaeque_nasi_left"].iloc[centre] == pytest.approx(0.6)


@pytest.mark.parametrize("mode", ["coarticulation", "linear", "cosine"])
def test_class_track_blends_the_phones_classes_as_the_visemes_are_blended(mode):
    """Oculus's visemes from the timeline: rows add up to 1, each phone's centre is its class, a /p/ (its
    contact forced, as the visemes') is PP at 1, and a keyed track holds every phone at its class."""
    from visemeface.retarget.recipes import OCULUS, phoneme_classes
    from visemeface.speech.timeline import class_track

    classes = {s: c[0] for s, c in phoneme_classes().items()}
    seg = segs(["p", "aa", "t", "uw"], 0.25)                   # after 0.3 s of silence
    w = class_track(seg, classes, OCULUS, fps=100, mode=mode)
    assert list(w.columns) == list(OCULUS)
    np.testing.assert_allclose(w.sum(axis=1), 1.0, atol=1e-9)
    for centre, cls in ((0.425, "PP"), (0.675, "aa"), (0.925, "DD"), (1.175, "ou"), (0.1, "sil")):
        row = w.iloc[int(round(centre * 100))]
        assert row.idxmax() == cls and row[cls] > (0.99 if mode != "coarticulation" or cls == "PP" else 0.5), \
            (mode, cls, row.idxmax(), row[cls])
    assert (w[["FF", "TH", "CH", "SS", "RR"]] == 0).all().all()              # classes no phone has stay 0
    with pytest.raises(InputError, match="no class among"):
        class_track(seg, {**classes, "t": "XX"}, OCULUS, fps=100, mode=mode)


@pytest.mark.parametrize("keys", [[(float("nan"), "happiness", 1.0)], [(-0.5, "happiness", 1.0)],
                                  pd.DataFrame({"time": ["soon"], "emotion": ["anger"], "weight": [1.0]})])
def test_emotion_keys_at_no_time_are_refused(keys):
    """A NaN key time used to give a track of NaN (an error far away, or a blank face)."""
    from visemeface.postures.library import load_visemes

    with pytest.raises(InputError, match="emotion key times must be finite seconds >= 0"):
        activation_track(segs(["aa"], 0.2), load_visemes(), emotions=keys)
