"""CampaignConfig validation and paired expansion."""

import pytest
from pydantic import ValidationError

from kintsugi.campaign.plan import CampaignConfig, expand


def cfg(**kw):
    base = dict(task="fake-coin", methods=["plain", "recover"], variants=["fair"],
                conditions=["easy", "hard"], trials=3, base_seed=10)
    return CampaignConfig(**{**base, **kw})


def test_expand_pairs_seeds_across_methods():
    specs = expand(cfg())
    assert len(specs) == 2 * 1 * 2 * 3
    by_cell = {}
    for s in specs:
        by_cell.setdefault((s.method, s.variant, s.condition), []).append(s.seed)
    assert all(seeds == [10, 11, 12] for seeds in by_cell.values())
    assert list(by_cell) == [("plain", "fair", "easy"), ("plain", "fair", "hard"),
                             ("recover", "fair", "easy"), ("recover", "fair", "hard")]
    assert len({s.key for s in specs}) == len(specs)


def test_expand_carries_overrides_reasoner_and_videos(tmp_path):
    c = cfg(overrides={"hole.friction": 2.0}, reasoner={"backend": "openai", "model": "m"}, videos_per_cell=1)
    specs = expand(c, video_dir=tmp_path)
    assert all(s.overrides == {"hole.friction": 2.0} and s.reasoner.model == "m" for s in specs)
    with_video = [s for s in specs if s.video]
    assert len(with_video) == 4 and all(s.seed == 10 for s in with_video)
    assert "/" not in with_video[0].video.removeprefix(str(tmp_path) + "/")


@pytest.mark.parametrize("bad", [
    {"unknown_key": 1},
    {"methods": []},
    {"methods": ["a", "a"]},
    {"conditions": ["x/y"]},
    {"trials": 0},
])
def test_config_rejects(bad):
    with pytest.raises(ValidationError):
        cfg(**bad)
