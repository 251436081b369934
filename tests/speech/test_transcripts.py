"""Transcript readers: every format on hand-written files, real-world quirks, property tests."""

import json
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from praatio import textgrid

from visemeface.errors import InputError
from visemeface.postures.phonemes import DECTALK
from visemeface.resources import transcripts_path
from visemeface.speech.transcripts import FORMATS, detect_format, read_transcript, read_utterance

SENTENCE = "_ b aa b m uw v z f ay v b ow t s _".split()


def write(tmp_path, name, content, encoding="utf-8"):
    p = tmp_path / name
    if isinstance(content, bytes):
        p.write_bytes(content)
    else:
        p.write_bytes(content.encode(encoding))
    return p


def assert_valid(seg):
    """The Segments contract of docs/conventions.md."""
    assert list(seg.columns) == ["start", "end", "phoneme"]
    s, e = seg.start.to_numpy(), seg.end.to_numpy()
    assert len(seg) > 0 and s[0] == 0.0
    assert np.isfinite(s).all() and np.isfinite(e).all()
    assert (e > s).all() and np.array_equal(s[1:], e[:-1])          # contiguous, no overlap
    assert set(seg.phoneme) <= set(DECTALK)
    assert not any(a == b == "_" for a, b in zip(seg.phoneme[:-1], seg.phoneme[1:]))


# ----------------------------------------------------------------------------- shipped examples

EXAMPLES = {
    "bob_moves_five_boats.txt": "timed", "bob_moves_five_boats.lab": "lab",
    "bob_moves_five_boats.PHN": "phn", "bob_moves_five_boats_long.TextGrid": "textgrid",
    "bob_moves_five_boats_short.TextGrid": "textgrid", "bob_moves_five_boats.json": "mfa-json",
    "bob_moves_five_boats.csv": "mfa-csv", "bob_moves_five_boats_dectalk.txt": "dectalk",
}


@pytest.mark.parametrize("name,fmt", EXAMPLES.items())
def test_every_example_reads_to_the_same_sentence(name, fmt):
    utt = read_utterance(transcripts_path(name))
    assert utt.source_format == fmt
    seg = utt.segments
    assert_valid(seg)
    phones = list(seg.phoneme)
    expected = SENTENCE if fmt != "mfa-csv" else SENTENCE[:-1]     # MFA CSV leaves final silence out
    assert phones == expected
    # /m/ of "moves" is at 0.47-0.53 s in every format (TIMIT: sample-exact).
    m = seg[seg.phoneme == "m"].iloc[0]
    assert m.start == pytest.approx(0.47, abs=1e-6) and m.end == pytest.approx(0.53, abs=1e-6)
    # The same phones, whichever format: selected explicitly too.
    assert list(read_transcript(transcripts_path(name), fmt=fmt).phoneme) == phones


def test_seed_example_one_five_zero_zero_six():
    seg = read_transcript(transcripts_path("one_five_zero_zero_six.txt"))
    assert_valid(seg)
    words = " ".join(seg.phoneme).split(" _ ")
    assert words == ["_ w ah n", "f ay v", "z ih r ow", "z ih r ow", "s ih k s _"]


def test_text_example_with_emotion_tags():
    utt = read_utterance(transcripts_path("bob_moves_five_boats_angry.txt"))
    assert utt.source_format == "text"
    seg = utt.segments
    assert_valid(seg)
    keys = utt.emotion_keys
    assert list(keys.emotion) == ["anger", "happiness"] and list(keys.weight) == [0.8, 0.6]
    assert keys.time.iloc[0] == 0.0 and keys.time.iloc[1] > 1.0


# ----------------------------------------------------------------------------- timed text

def test_timed_text_with_comments_crlf_bom_and_trailing_blank_lines(tmp_path):
    content = "\ufeff# a comment\r\n0.0 0.1 _\r\n0.1 0.2 m  ; closure\r\n\r\n0.2 0.45 aa\r\n0.45 0.6 _\r\n\r\n\r\n"
    seg = read_transcript(write(tmp_path, "t.txt", content))
    assert_valid(seg)
    assert list(seg.phoneme) == ["_", "m", "aa", "_"] and seg.end.iloc[-1] == 0.6


def test_timed_start_phone_lines(tmp_path):
    seg = read_transcript(write(tmp_path, "t.txt", "0 sil\n0.1 HH\n0.18 AH0\n0.25 L\n0.3 OW1\n0.55\n"))
    assert list(seg.phoneme) == ["_", "hx", "ax", "l", "ow"]          # ARPAbet detected
    assert seg.end.iloc[-1] == 0.55 and seg.start.iloc[2] == 0.18
    # Without a final time, the last phone lasts its inherent duration (ow: 220 ms).
    seg = read_transcript(write(tmp_path, "u.txt", "0 sil\n0.1 OW1\n"))
    assert seg.end.iloc[-1] == pytest.approx(0.32)


def test_timed_alphabets_detected(tmp_path):
    timit = read_transcript(write(tmp_path, "a.txt", "0 0.1 h#\n0.1 0.2 hh\n0.2 0.3 er\n0.3 0.4 ng\n"))
    assert list(timit.phoneme) == ["_", "hx", "rr", "nx"]
    ipa = read_transcript(write(tmp_path, "b.txt", "0 0.1 ɹ\n0.1 0.2 ɛ\n0.2 0.3 d\n"))
    assert list(ipa.phoneme) == ["r", "eh", "d"]
    forced = read_transcript(write(tmp_path, "c.txt", "0 0.1 er\n"), alphabet="timit")
    assert list(forced.phoneme) == ["rr"]
    assert list(read_transcript(write(tmp_path, "d.txt", "0 0.1 er\n")).phoneme) == ["er"]   # DECtalk first


def test_leading_and_inner_gaps_become_silence_with_a_warning(tmp_path):
    p = write(tmp_path, "g.txt", "0.2 0.3 m\n0.3 0.4 aa\n0.6 0.7 p\n")
    with pytest.warns(UserWarning, match=r"g.txt:3: gap of 0.2 s before 'p'"):
        seg = read_transcript(p)
    assert list(seg.phoneme) == ["_", "m", "aa", "_", "p"]
    assert seg.start.iloc[3] == pytest.approx(0.4) and seg.end.iloc[3] == pytest.approx(0.6)


def test_tiny_rounding_gaps_and_overlaps_are_closed_silently(tmp_path):
    p = write(tmp_path, "r.txt", "0 0.1 m\n0.1004 0.2 aa\n0.1996 0.3 b\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        seg = read_transcript(p)
    assert_valid(seg)
    assert list(seg.phoneme) == ["m", "aa", "b"]


@pytest.mark.parametrize("content,line,match", [
    ("0 0.2 m\n0.1 0.3 aa\n", 2, r"overlaps the previous one \(line 1"),
    ("0 0.2 m\n0.3 0.4 aa\n0.1 0.2 b\n", 3, "before the previous one"),
    ("0 0.2 m\n-0.5 0.3 aa\n", 2, "negative"),
    ("0 0.2 m\n0.2 nan aa\n", 2, "not finite"),
    ("0 0.2 m\n0.2 0.1 aa\n", 2, "ends .* before it starts"),
    ("0 0.2 m\n0.2 0.3 qq\n", 2, "unknown .* phone 'qq'"),
    ("0 0.2 m\n0.2 x aa\n", 2, "'x' is not a number"),
    ("0 0.2 m\n0.2 0.3 aa extra stuff\n", 2, "expected 'start end phone'"),
])
@pytest.mark.filterwarnings("ignore:.*gap of")
def test_timed_errors_name_file_and_line(tmp_path, content, line, match):
    p = write(tmp_path, "bad.txt", content)
    with pytest.raises(InputError, match=match) as e:
        read_transcript(p, fmt="timed")
    assert e.value.path == str(p) and e.value.line == line
    assert str(e.value).startswith(f"{p}:{line}: ")


# ----------------------------------------------------------------------------- HTK / xwaves

def test_htk_lab_100ns_units(tmp_path):
    seg = read_transcript(write(tmp_path, "a.lab", "0 1500000 pau\n1500000 2200000 b -3.2\n"
                                                   "2200000 4000000 aa\n4000000 5000000 sil\n"))
    assert list(seg.phoneme) == ["_", "b", "aa", "_"]
    assert seg.end.tolist() == pytest.approx([0.15, 0.22, 0.40, 0.50])


def test_hts_full_context_labels(tmp_path):
    lab = ("0 2000000 x^x-pau+hh=ax@x_x/A:0_0_0/B:x-x-x@x-x&x-x\n"
           "2000000 2800000 x^pau-hh+ax=l@1_2/A:0_0_0\n"
           "2800000 3500000 pau^hh-ax+l=ow@2_1/A:0_0_0\n"
           "3500000 4200000 hh^ax-l+ow=pau@1_2/A:1_0_2\n"
           "4200000 6000000 ax^l-ow+pau=x@2_1/A:1_0_2\n"
           "6000000 8000000 l^ow-pau+x=x@x_x/A:1_0_2\n")
    seg = read_transcript(write(tmp_path, "hts.lab", lab))
    assert list(seg.phoneme) == ["_", "hx", "ax", "l", "ow", "_"]


def test_xwaves_lab_of_cmu_arctic(tmp_path):
    lab = ("separator ;\nnfields 1\n#\n    0.16500 125 pau\n    0.24000 125 ao\n    0.31500 125 th\n"
           "    0.40500 125 er\n")
    utt = read_utterance(write(tmp_path, "arctic_a0001.lab", lab))
    assert utt.source_format == "lab"
    seg = utt.segments
    assert list(seg.phoneme) == ["_", "ao", "th", "rr"]
    assert seg.end.tolist() == pytest.approx([0.165, 0.24, 0.315, 0.405])


# ----------------------------------------------------------------------------- TIMIT

def test_timit_closures_merge_with_release_and_sample_rate(tmp_path):
    phn = "0 3050 h#\n3050 4559 sh\n4559 5723 ix\n5723 6642 hv\n6642 8772 eh\n8772 9190 dcl\n" \
          "9190 10337 jh\n10337 11517 ih\n11517 12500 pcl\n12500 12900 p\n12900 14000 h#\n"
    p = write(tmp_path, "SA1.PHN", phn)
    seg = read_transcript(p)
    assert list(seg.phoneme) == ["_", "sh", "ix", "hx", "eh", "d", "jh", "ih", "p", "_"]
    p_row = seg[seg.phoneme == "p"].iloc[0]
    assert p_row.start == pytest.approx(11517 / 16000) and p_row.end == pytest.approx(12900 / 16000)
    slow = read_transcript(p, sample_rate=8000)
    assert slow.end.iloc[-1] == pytest.approx(14000 / 8000)


def test_timit_non_integer_samples(tmp_path):
    with pytest.raises(InputError, match="not an integer") as e:
        read_transcript(write(tmp_path, "x.PHN", "0 100 h#\n100 2.5 aa\n"))
    assert e.value.line == 2


# ----------------------------------------------------------------------------- TextGrid

LONG_TG = '''File type = "ooTextFile"
Object class = "TextGrid"

xmin = 0
xmax = 0.9
tiers? <exists>
size = 2
item []:
    item [1]:
        class = "IntervalTier"
        name = "words"
        xmin = 0
        xmax = 0.9
        intervals: size = 3
        intervals [1]:
            xmin = 0
            xmax = 0.1
            text = ""
        intervals [2]:
            xmin = 0.1
            xmax = 0.6
            text = "hello"
        intervals [3]:
            xmin = 0.6
            xmax = 0.9
            text = ""
    item [2]:
        class = "IntervalTier"
        name = "phones"
        xmin = 0
        xmax = 0.9
        intervals: size = 7
        intervals [1]:
            xmin = 0
            xmax = 0.1
            text = ""
        intervals [2]:
            xmin = 0.1
            xmax = 0.2
            text = "h"
        intervals [3]:
            xmin = 0.2
            xmax = 0.3
            text = "ə"
        intervals [4]:
            xmin = 0.3
            xmax = 0.4
            text = "l"
        intervals [5]:
            xmin = 0.4
            xmax = 0.6
            text = "ow"
        intervals [6]:
            xmin = 0.6
            xmax = 0.75
            text = "sp"
        intervals [7]:
            xmin = 0.75
            xmax = 0.9
            text = "spn"
'''


def test_textgrid_long_with_empty_intervals_bom_crlf(tmp_path):
    p = write(tmp_path, "a.TextGrid", "\ufeff" + LONG_TG.replace("\n", "\r\n"))
    seg = read_transcript(p)
    assert list(seg.phoneme) == ["_", "hx", "ax", "l", "ow", "_"]
    assert seg.end.tolist() == pytest.approx([0.1, 0.2, 0.3, 0.4, 0.6, 0.9])
    with pytest.raises(InputError, match="unknown ipa phone 'hello'"):
        read_transcript(p, tier="words")           # a word tier is not phones


def test_textgrid_short_written_by_praatio_and_tier_choice(tmp_path):
    tg = textgrid.Textgrid()
    tg.addTier(textgrid.IntervalTier("speaker1 - words", [(0.0, 0.5, "bob")], 0, 0.8))
    tg.addTier(textgrid.IntervalTier("speaker1 - phones", [(0.05, 0.15, "B"), (0.15, 0.4, "AA1"),
                                                           (0.4, 0.5, "B"), (0.5, 0.8, "sil")], 0, 0.8))
    tg.addTier(textgrid.IntervalTier("other", [(0.0, 0.8, "OW1")], 0, 0.8))
    p = tmp_path / "short.TextGrid"
    tg.save(str(p), format="short_textgrid", includeBlankSpaces=True)
    seg = read_transcript(p)
    assert list(seg.phoneme) == ["_", "b", "aa", "b", "_"]
    assert list(read_transcript(p, tier="other").phoneme) == ["ow"]
    with pytest.raises(InputError, match="no tier 'phone'.*did you mean") as e:
        read_transcript(p, tier="phone")
    assert e.value.path == str(p)


def test_textgrid_two_speakers_needs_tier(tmp_path):
    tg = textgrid.Textgrid()
    for spk in ("a", "b"):
        tg.addTier(textgrid.IntervalTier(f"{spk} - phones", [(0.0, 0.5, "AA1")], 0, 0.5))
    p = tmp_path / "two.TextGrid"
    tg.save(str(p), format="long_textgrid", includeBlankSpaces=True)
    with pytest.raises(InputError, match="several phone tiers"):
        read_transcript(p)
    assert list(read_transcript(p, tier="b - phones").phoneme) == ["aa"]


def test_textgrid_bad_label_reports_the_interval_line(tmp_path):
    p = write(tmp_path, "bad.TextGrid", LONG_TG.replace('text = "l"', 'text = "ʘ"'))
    with pytest.raises(InputError, match="unknown ipa phone 'ʘ'") as e:
        read_transcript(p)
    assert e.value.line == LONG_TG.splitlines().index('        intervals [4]:') + 1


def test_short_textgrid_bad_label_reports_its_line(tmp_path):
    tg = textgrid.Textgrid()
    tg.addTier(textgrid.IntervalTier("words", [(0.0, 0.5, "bob")], 0, 0.8))
    tg.addTier(textgrid.IntervalTier("phones", [(0.05, 0.15, "b"), (0.15, 0.4, "ʘ"), (0.4, 0.5, "b")], 0, 0.8))
    p = tmp_path / "short.TextGrid"
    tg.save(str(p), format="short_textgrid", includeBlankSpaces=True)
    with pytest.raises(InputError, match="unknown ipa phone 'ʘ'") as e:
        read_transcript(p)
    lines = p.read_text(encoding="utf-8").splitlines()
    assert lines[e.value.line - 1:e.value.line + 2] == ["0.15", "0.4", '"ʘ"']   # xmin, xmax, text


def test_garbage_textgrid(tmp_path):
    p = write(tmp_path, "bad.TextGrid", 'File type = "ooTextFile"\nObject class = "TextGrid"\nxmin = zero\n')
    with pytest.raises(InputError, match="not a readable TextGrid") as e:
        read_transcript(p)
    assert e.value.path == str(p)


# ----------------------------------------------------------------------------- MFA JSON / CSV

def test_mfa_json_list_form_and_end_silence(tmp_path):
    data = {"start": 0, "end": 1.0, "tiers": {"words": {"type": "interval", "entries": [[0.1, 0.5, "hi"]]},
                                              "phones": {"type": "interval",
                                                         "entries": [[0.1, 0.2, "h"], [0.2, 0.5, "aj"]]}}}
    seg = read_transcript(write(tmp_path, "a.json", json.dumps(data)))
    assert list(seg.phoneme) == ["_", "hx", "ay", "_"] and seg.end.iloc[-1] == 1.0


def test_mfa_json_errors(tmp_path):
    with pytest.raises(InputError, match="not valid JSON") as e:
        read_transcript(write(tmp_path, "a.json", '{"tiers": {\n  "phones": [1, 2,\n'))
    assert e.value.line is not None
    with pytest.raises(InputError, match="no 'tiers'"):
        read_transcript(write(tmp_path, "b.json", '{"x": 1}'))


def test_mfa_csv_speakers_and_types(tmp_path):
    csv_text = ("Begin,End,Label,Type,Speaker\r\n0.1,0.5,hi,words,anna\r\n0.1,0.2,h,phones,anna\r\n"
                "0.2,0.5,aj,phones,anna\r\n0.0,0.3,ow,phones,ben\r\n\r\n")
    p = write(tmp_path, "a.csv", csv_text)
    with pytest.raises(InputError, match="several phone tiers"):
        read_transcript(p)
    seg = read_transcript(p, tier="anna - phones")
    assert list(seg.phoneme) == ["_", "hx", "ay"]
    with pytest.raises(InputError, match="overlaps") as e:
        read_transcript(write(tmp_path, "b.csv", "Begin,End,Label,Type,Speaker\n0,0.3,h,phones,a\n"
                                                 "0.2,0.5,aj,phones,a\n"))
    assert e.value.line == 3


# ----------------------------------------------------------------------------- DECtalk

def test_dectalk_string_with_durations_pauses_and_no_spaces(tmp_path):
    seg = read_transcript(write(tmp_path, "d.txt", "[:phoneme on]\n[hx<80> eh<120> l ow<200> _<300>]\n"))
    assert list(seg.phoneme) == ["hx", "eh", "l", "ow", "_"]
    # /l/ has no duration: its inherent one (80 ms).
    assert (seg.end - seg.start).tolist() == pytest.approx([0.08, 0.12, 0.08, 0.2, 0.3])
    packed = read_transcript(write(tmp_path, "e.txt", "[hxeh<120,90>'low<200>]"))
    assert list(packed.phoneme) == ["hx", "eh", "l", "ow"]
    assert packed.end.iloc[-1] == pytest.approx(0.08 + 0.12 + 0.08 + 0.2)


def test_dectalk_errors(tmp_path):
    with pytest.raises(InputError, match="unknown DECtalk phoneme") as e:
        read_transcript(write(tmp_path, "d.txt", "[hx eh\n l ooo]"))
    assert e.value.line == 2
    with pytest.raises(InputError, match="duration .* follows no phoneme"):
        read_transcript(write(tmp_path, "e.txt", "[<100> aa]"))
    with pytest.raises(InputError, match="text outside"):
        read_transcript(write(tmp_path, "f.txt", "[aa] hello"), fmt="dectalk")


# ----------------------------------------------------------------------------- plain text, misc

def test_plain_text_goes_through_g2p(tmp_path):
    utt = read_utterance(write(tmp_path, "s.txt", "Bob moves five boats.\n"))
    assert utt.source_format == "text"
    seg = utt.segments
    assert [p for p in seg.phoneme] == SENTENCE


def test_detect_format_by_content():
    assert detect_format("0 0.1 aa\n") == "timed"
    assert detect_format("0 1000000 aa\n1000000 2500000 b\n") == "lab"
    assert detect_format("0 1600 aa\n1600 4000 b\n") == "phn"
    assert detect_format("[aa<100>]") == "dectalk"
    assert detect_format("[happiness] hello") == "text"
    assert detect_format('{"tiers": {}}') == "mfa-json"
    assert detect_format("Begin,End,Label,Type,Speaker\n") == "mfa-csv"
    assert detect_format('File type = "ooTextFile"\n') == "textgrid"
    assert detect_format("separator ;\nnfields 1\n#\n 0.1 125 pau\n") == "lab"
    assert detect_format("#\n# my phones\n0 0.1 aa\n") == "timed"        # a bare comment is not xwaves


def test_file_errors(tmp_path):
    with pytest.raises(InputError, match="transcript not found"):
        read_transcript(tmp_path / "missing.txt")
    with pytest.raises(InputError, match="empty"):
        read_transcript(write(tmp_path, "empty.txt", "\n\n  \n"))
    with pytest.raises(InputError, match="not UTF-8") as e:
        read_transcript(write(tmp_path, "latin.txt", b"0 0.1 aa\n0.1 0.2 \xe9\n"))
    assert e.value.line == 2
    with pytest.raises(InputError, match="unknown transcript format 'textgird'.*textgrid"):
        read_transcript(write(tmp_path, "x.txt", "0 0.1 aa\n"), fmt="textgird")


def test_utf16_textgrid(tmp_path):
    p = write(tmp_path, "u16.TextGrid", LONG_TG, encoding="utf-16")
    assert list(read_transcript(p).phoneme) == ["_", "hx", "ax", "l", "ow", "_"]


# ----------------------------------------------------------------------------- properties

NUMBER = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=32).map(lambda x: f"{x:g}"),
                   st.integers(-5, 10**8).map(str), st.sampled_from(["0", "0.1", "1e400", "-0", "x", ""]))
LABEL = st.one_of(st.sampled_from(list(DECTALK) + ["AH0", "sil", "sp", "h#", "bcl", "ɑː", "tʰ", "", "?"]),
                  st.text(max_size=4))
SEP = st.sampled_from([" ", "\t", "  "])
LINE_FORMATS = ["timed", "lab", "phn", "dectalk", "mfa-csv"]


@st.composite
def lines(draw, fields):
    n = draw(st.integers(0, 8))
    out = []
    t = 0.0
    for _ in range(n):
        if draw(st.booleans()):                  # plausible, increasing line
            t1 = t + draw(st.floats(0.0, 0.3))
            scale = {"lab": 1e7, "phn": 16000}.get(fields, 1)
            a, b = (str(int(t * scale)), str(int(t1 * scale))) if scale > 1 else (f"{t:.3f}", f"{t1:.3f}")
            out.append(f"{a} {b} {draw(LABEL)}")
            t = t1
        else:
            parts = draw(st.lists(st.one_of(NUMBER, LABEL), max_size=4))
            out.append(draw(SEP).join(parts))
    eol = draw(st.sampled_from(["\n", "\r\n"]))
    return draw(st.sampled_from(["", "\ufeff"])) + eol.join(out) + draw(st.sampled_from(["", eol, eol * 3]))


def check_reader(tmp_path, name, content, fmt, line_required):
    p = tmp_path / name
    p.write_text(content, encoding="utf-8")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            seg = read_transcript(p, fmt=fmt)
    except InputError as e:
        assert e.path == str(p)
        if line_required and "empty" not in e.reason:
            assert e.line is not None, str(e)
        return
    assert_valid(seg)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.sampled_from(["timed", "lab", "phn"]), st.data())
def test_property_line_readers(tmp_path, fmt, data):
    content = data.draw(lines(fmt))
    check_reader(tmp_path, f"p.{fmt}", content, fmt, True)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.one_of(st.sampled_from(list(DECTALK) + ["<80>", "<120,90>", "<x>", "<-5>", "'", ",", " ",
                                                           "\n", "[", "]", "[:rate 200]"]),
                          st.text(max_size=3)), max_size=20))
def test_property_dectalk_reader(tmp_path, parts):
    check_reader(tmp_path, "d.txt", "[" + " ".join(parts) + "]", "dectalk", True)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(NUMBER, NUMBER, LABEL, st.sampled_from(["phones", "words", "x"])), max_size=6),
       st.booleans())
def test_property_mfa_readers(tmp_path, rows, as_json):
    if as_json:
        entries = []
        for a, b, lab, _ in rows:
            try:
                entries.append([float(a), float(b), lab])
            except ValueError:
                entries.append([a, b, lab])
        content = json.dumps({"tiers": {"phones": {"type": "interval", "entries": entries}}})
        check_reader(tmp_path, "m.json", content, "mfa-json", False)
    else:
        content = "Begin,End,Label,Type,Speaker\n" + "\n".join(f"{a},{b},{lab.replace(',', '')},{t},s"
                                                               for a, b, lab, t in rows)
        check_reader(tmp_path, "m.csv", content, "mfa-csv", True)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.floats(-1, 2), st.floats(-1, 2), LABEL), max_size=6), st.booleans())
def test_property_textgrid_reader(tmp_path, intervals, short):
    body = "".join(f'{a:g}\n{b:g}\n"{lab.replace(chr(34), "")}"\n' for a, b, lab in intervals)
    if short:
        content = ('File type = "ooTextFile short"\n"TextGrid"\n\n0\n2\n<exists>\n1\n"IntervalTier"\n"phones"\n'
                   f"0\n2\n{len(intervals)}\n" + body)
    else:
        items = "".join(f'        intervals [{k + 1}]:\n            xmin = {a:g}\n            xmax = {b:g}\n'
                        f'            text = "{lab.replace(chr(34), "")}"\n' for k, (a, b, lab) in enumerate(intervals))
        content = ('File type = "ooTextFile"\nObject class = "TextGrid"\n\nxmin = 0\nxmax = 2\ntiers? <exists>\n'
                   'size = 1\nitem []:\n    item [1]:\n        class = "IntervalTier"\n        name = "phones"\n'
                   f'        xmin = 0\n        xmax = 2\n        intervals: size = {len(intervals)}\n' + items)
    check_reader(tmp_path, "t.TextGrid", content, "textgrid", False)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.text(max_size=60))
def test_property_any_text_with_detection(tmp_path, content):
    # Whatever the content, detection plus the chosen reader give Segments or an InputError.
    check_reader(tmp_path, "any.txt", content, None, False)


# ----------------------------------------------------------------------------- wrong input that used to pass

def test_a_transcript_of_comments_only_is_empty_not_english(tmp_path):
    with pytest.raises(InputError, match="transcript is empty \\(only comments\\)"):
        read_transcript(write(tmp_path, "c.txt", "# nothing here\n; nor here\n"))


def test_a_speaking_rate_for_a_timed_transcript_is_refused(tmp_path):
    with pytest.raises(InputError, match="--rate applies to plain text only"):
        read_transcript(transcripts_path("bob_moves_five_boats.lab"), rate_wpm=120)


def test_a_lab_file_read_as_timit_samples_is_refused_not_stretched_to_minutes():
    with pytest.raises(InputError, match="wrong time units"):
        read_transcript(transcripts_path("bob_moves_five_boats.lab"), fmt="phn")


def test_a_lab_file_in_seconds_is_refused_not_squeezed_into_one_frame(tmp_path):
    # HTK .lab counts 100 ns units: seconds read as those make every phone 10^7 times too short
    seconds = "".join(line + "\n" for line in transcripts_path("bob_moves_five_boats.txt").read_text().splitlines()
                      if line and not line.startswith("#"))
    with pytest.raises(InputError, match=r"secs.lab:\d+: the median phone lasts .*e-0\d s.*wrong time units"):
        read_transcript(write(tmp_path, "secs.lab", seconds))


def test_textgrid_with_an_absurd_interval_count_is_a_one_line_error(tmp_path):
    # Short format; praatio reads it (it ignores the count), the line finder must not overflow.
    text = ('File type = "ooTextFile"\nObject class = "TextGrid"\n\n0\n1\n<exists>\n1\n"IntervalTier"\n'
            '"phones"\n0\n1\n1e309\n0\n1\n"aa"\n')
    seg = read_transcript(write(tmp_path, "big.TextGrid", text))
    assert list(seg.phoneme) == ["aa"]


def test_a_text_file_forced_to_textgrid_says_so_without_python_internals(tmp_path):
    with pytest.raises(InputError, match="not a readable TextGrid") as err:
        read_transcript(write(tmp_path, "t.txt", "hello there\n"), fmt="textgrid")
    assert "IndexError" not in str(err.value)


def test_dectalk_pauses_are_the_text_front_ends_pauses(tmp_path):
    from visemeface.speech.g2p import timing

    seg = read_transcript(write(tmp_path, "d.txt", "[aa<100> , aa<100> . aa<100>]"))
    t = timing()
    pauses = (seg.end - seg.start)[seg.phoneme == "_"].to_numpy()
    assert pauses == pytest.approx([t["pause_comma_ms"] / 1000, t["pause_sentence_ms"] / 1000])
