"""Regressions from a hostile user's batch runs (issue 20, second round)."""

import json

from visemeface.batch.clip import CLIP_RECORD, clip_state
from visemeface.batch.manifest import Job


def test_a_clip_record_that_is_not_an_object_means_other_settings(tmp_path):
    """``clip.json`` holding ``[]`` (hand-edited, another tool's file) crashed --resume with AttributeError."""
    job = Job(clip="c1", text="one")
    (tmp_path / "c1").mkdir()
    for text in ("[]", "5", '"settings"', "null"):
        (tmp_path / "c1" / CLIP_RECORD).write_text(text)
        assert clip_state(job, tmp_path) == "other"
    (tmp_path / "c1" / CLIP_RECORD).write_text(json.dumps({"settings": job.settings()}))
    assert clip_state(job, tmp_path) == "done"
