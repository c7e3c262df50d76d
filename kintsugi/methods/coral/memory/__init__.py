"""Retrieval memory of successful episodes (CoRAL): SQLite storage, lexical/parametric or embedding similarity."""

from kintsugi.methods.coral.memory.store import Embedder, Episode, EpisodeMemory, Match

__all__ = ["Embedder", "Episode", "EpisodeMemory", "Match"]
