"""Retrieval memory: episodes survive reopening, the most similar one is found first (by words and by
objects, or by the endpoint's embeddings), concurrent writers lose nothing, and bad files are one clear error."""

from __future__ import annotations

import multiprocessing as mp
from pathlib import Path

import pytest

from kintsugi.core.errors import ConfigError
from kintsugi.methods.coral.memory import Episode, EpisodeMemory
from kintsugi.methods.coral.memory.embed import OpenAIEmbedder
from kintsugi.methods.coral.memory.similarity import object_similarity, tfidf_cosine
from kintsugi.methods.coral.types import ObjectPrior, ObjectView, RegionSpec
from kintsugi.reasoning.structured import EndpointError
from tests.fake_openai_server import FakeOpenAIServer

BOARD = ObjectView(label="cutting board", size_m=(0.35, 0.25, 0.02))
BOX = ObjectView(label="box", size_m=(0.2, 0.15, 0.1))
BIG_BOX = ObjectView(label="box", size_m=(0.4, 0.3, 0.2))


def episode(task: str, text: str, obj: ObjectView, mass: float = 1.0) -> Episode:
    return Episode(task=task, instruction=text, objects=[obj], beliefs={obj.label: ObjectPrior(mass_kg=mass,
                   friction=0.5)}, cost_source="def cost(tcp):\n    return 0",
                   regions=[RegionSpec(object=obj.label, center=(0, 0, 0), normal=(1, 0, 0), radius=0.02)])


def test_lexical_similarity_prefers_shared_rare_words() -> None:
    docs = ["pick up the box", "flip the box against the wall", "push the cutting board over the edge"]
    sims = tfidf_cosine("flip the box", docs)
    assert sims.argmax() == 1 and sims[2] == 0.0 and 0 <= sims.min() and sims.max() <= 1 + 1e-12


def test_object_similarity_by_label_then_size() -> None:
    assert object_similarity([BOX], [BOX]) == pytest.approx(1.0)
    assert object_similarity([BOX], [BIG_BOX]) == pytest.approx(0.5)  # twice as large on every side
    assert object_similarity([BOX], [BOARD]) == 0.0
    turned = ObjectView(label="box", size_m=(0.1, 0.2, 0.15))
    assert object_similarity([BOX], [turned]) == pytest.approx(1.0)
    assert object_similarity([BOX], [BOX, BOARD]) == pytest.approx(0.5)  # an extra object lowers the score


def test_episodes_persist_and_the_nearest_comes_first(tmp_path: Path) -> None:
    path = tmp_path / "memory.sqlite"
    with EpisodeMemory(path) as mem:
        mem.add(episode("pick-box", "pick up the box", BIG_BOX, mass=3.0))
        mem.add(episode("push-pick-board", "push the cutting board until the handle overhangs, then pick it",
                        BOARD))
        mem.add(episode("flip-box", "flip the box over", BOX))
    with EpisodeMemory(path) as mem:
        assert len(mem) == 3
        found = mem.search("pick the box up", [BOX], k=3)
        assert [m.episode.task for m in found][0] == "pick-box"
        assert found[0].score >= found[1].score >= found[2].score
        assert found[0].episode.beliefs["box"].mass_kg == 3.0
        assert mem.best("push the board to the edge and pick it", [BOARD], threshold=0.5).episode.task == \
            "push-pick-board"
        assert mem.best("stack the cups", [ObjectView(label="cup", size_m=(0.08, 0.08, 0.1))], 0.3) is None


def test_failed_episodes_are_not_stored(tmp_path: Path) -> None:
    with EpisodeMemory(tmp_path / "m.sqlite") as mem, pytest.raises(ConfigError, match="only successful"):
        mem.add(episode("pick-box", "pick", BOX).model_copy(update={"success": False}))


def _writer(path: str, worker: int) -> None:
    with EpisodeMemory(path) as mem:
        for i in range(10):
            mem.add(episode("pick-box", f"pick box {worker}-{i}", BOX))


@pytest.mark.slow
def test_parallel_writers_lose_nothing(tmp_path: Path) -> None:
    path = tmp_path / "shared.sqlite"
    EpisodeMemory(path).close()
    ctx = mp.get_context("spawn")
    procs = [ctx.Process(target=_writer, args=(str(path), w)) for w in range(3)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(60)
    assert [p.exitcode for p in procs] == [0, 0, 0]
    with EpisodeMemory(path) as mem:
        texts = sorted(e.instruction for _, e in mem.episodes())
    assert texts == sorted(f"pick box {w}-{i}" for w in range(3) for i in range(10))


def test_bad_files_are_one_clear_error(tmp_path: Path) -> None:
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(b"not a database at all" * 100)
    with pytest.raises(ConfigError, match="not a usable SQLite database"):
        EpisodeMemory(junk)
    with pytest.raises(ConfigError, match="is a directory"):
        EpisodeMemory(tmp_path)
    with pytest.raises(ConfigError, match="does not exist"):
        EpisodeMemory(tmp_path / "nope" / "m.sqlite")


def test_embeddings_from_the_endpoint_rank_episodes(tmp_path: Path) -> None:
    with FakeOpenAIServer() as server:
        embed = OpenAIEmbedder("fake-embed", base_url=server.base_url)
        with EpisodeMemory(tmp_path / "m.sqlite", embedder=embed, embedder_name=embed.name) as mem:
            mem.add(episode("flip-box", "flip box against wall", BOX))
            mem.add(episode("pick-box", "pick box", BOX))
            found = mem.search("flip box against wall", [BOX], k=2)
        assert found[0].episode.task == "flip-box" and found[0].lexical == pytest.approx(1.0)
        assert sum(1 for r in server.requests if r.get("model") == "fake-embed") == 3


def test_unreachable_embeddings_endpoint_is_an_endpoint_error() -> None:
    embed = OpenAIEmbedder("x", base_url="http://127.0.0.1:9/v1", timeout_s=0.5)
    with pytest.raises(EndpointError, match="embeddings from http://127.0.0.1:9/v1"):
        embed(["pick the box"])
