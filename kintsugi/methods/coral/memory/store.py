"""CoRAL's retrieval memory: successful episodes in a SQLite file, found again by similarity.

An episode keeps what a later task can reuse instead of asking the reasoner again: the
instruction and objects (to match on), the refined physics beliefs, the cost code and the
contact strategy. One file per memory, named by the user, shared by every trial of a campaign:
SQLite in WAL mode lets parallel workers read while one writes, and each write is a single
transaction, so a killed worker never leaves half an episode. Reproducible memory effects need
trials to run in a stated order; that is the campaign's job.
"""

from __future__ import annotations

import json
import sqlite3
import time
from pathlib import Path
from typing import Callable, Sequence

from pydantic import Field, ValidationError

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import ConfigError
from kintsugi.methods.coral.memory.similarity import cosine, object_similarity, tfidf_cosine
from kintsugi.methods.coral.types import ObjectPrior, ObjectView, RegionSpec

SCHEMA_VERSION = 1
Embedder = Callable[[Sequence[str]], list[list[float]]]
"""Texts -> one vector each (e.g. the endpoint's embeddings API)."""


class Episode(StrictModel):
    task: str = Field(description="registered task name, e.g. push-pick-board")
    instruction: str
    objects: list[ObjectView]
    beliefs: dict[str, ObjectPrior] = Field(description="physics beliefs the episode ended with (after refinement)")
    cost_source: str = ""
    regions: list[RegionSpec] = Field(default_factory=list)
    success: bool = True
    notes: str = ""


class Match(StrictModel):
    episode: Episode
    score: float
    lexical: float
    objects: float
    id: int


class EpisodeMemory:
    """Episodes in one SQLite file; `search` ranks them by instruction and object similarity."""

    def __init__(self, path: str | Path, embedder: Embedder | None = None, embedder_name: str = "",
                 lexical_weight: float = 0.5) -> None:
        self.path = Path(path)
        if self.path.exists() and self.path.is_dir():
            raise ConfigError(f"memory file {self.path} is a directory; name a file, e.g. runs/memory.sqlite")
        if not self.path.parent.exists():
            raise ConfigError(f"memory file {self.path}: its folder {self.path.parent} does not exist")
        self.embedder, self.embedder_name = embedder, embedder_name
        self.lexical_weight = lexical_weight
        try:
            self._db = sqlite3.connect(self.path, timeout=30.0)
            self._db.execute("PRAGMA journal_mode=WAL")
            self._create()
        except sqlite3.DatabaseError as exc:
            raise ConfigError(f"memory file {self.path} is not a usable SQLite database ({exc}); "
                              f"move it away or name another file") from None

    def _create(self) -> None:
        with self._db:
            self._db.execute("CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT)")
            self._db.execute("""CREATE TABLE IF NOT EXISTS episodes (
                id INTEGER PRIMARY KEY AUTOINCREMENT, created REAL, task TEXT, instruction TEXT,
                episode TEXT, embedding TEXT, embedder TEXT)""")
            row = self._db.execute("SELECT value FROM meta WHERE key='schema'").fetchone()
            if row is None:
                self._db.execute("INSERT INTO meta VALUES ('schema', ?)", (str(SCHEMA_VERSION),))
            elif row[0] != str(SCHEMA_VERSION):
                raise ConfigError(f"memory file {self.path} has schema {row[0]}, this kintsugi reads "
                                  f"{SCHEMA_VERSION}; name a new file")

    def close(self) -> None:
        self._db.close()

    def __enter__(self) -> "EpisodeMemory":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def add(self, episode: Episode) -> int:
        """Store one episode (only successful ones are worth retrieving; failures are refused)."""
        if not episode.success:
            raise ConfigError("only successful episodes go into memory")
        embedding = json.dumps(self.embedder([episode.instruction])[0]) if self.embedder else None
        with self._db:
            cur = self._db.execute(
                "INSERT INTO episodes (created, task, instruction, episode, embedding, embedder) VALUES (?,?,?,?,?,?)",
                (time.time(), episode.task, episode.instruction, episode.model_dump_json(), embedding,
                 self.embedder_name if self.embedder else None))
        return int(cur.lastrowid)

    def __len__(self) -> int:
        return int(self._db.execute("SELECT COUNT(*) FROM episodes").fetchone()[0])

    def episodes(self) -> list[tuple[int, Episode]]:
        """Every stored episode in insertion order; rows that no longer parse are skipped, not fatal."""
        out = []
        for row_id, text in self._db.execute("SELECT id, episode FROM episodes ORDER BY id"):
            try:
                out.append((int(row_id), Episode.model_validate_json(text)))
            except ValidationError:
                continue
        return out

    def search(self, instruction: str, objects: Sequence[ObjectView], k: int = 3) -> list[Match]:
        """The k most similar episodes, best first: a weighted sum of instruction similarity (embeddings when
        an embedder is set and the episode was embedded by the same one, else TF-IDF) and object similarity."""
        rows = self.episodes()
        if not rows:
            return []
        lexical = tfidf_cosine(instruction, [e.instruction for _, e in rows])
        if self.embedder is not None:
            stored = dict(self._db.execute("SELECT id, embedding FROM episodes WHERE embedder = ?",
                                           (self.embedder_name,)).fetchall())
            if stored:
                query = self.embedder([instruction])[0]
                for i, (row_id, _) in enumerate(rows):
                    if stored.get(row_id):
                        lexical[i] = max(cosine(query, json.loads(stored[row_id])), 0.0)
        w = self.lexical_weight
        matches = [Match(episode=e, id=row_id, lexical=float(lex), objects=(obj := object_similarity(objects, e.objects)),
                         score=w * float(lex) + (1 - w) * obj)
                   for (row_id, e), lex in zip(rows, lexical)]
        matches.sort(key=lambda m: (-m.score, m.id))
        return matches[:k]

    def best(self, instruction: str, objects: Sequence[ObjectView], threshold: float) -> Match | None:
        """The most similar episode if it scores at least `threshold`: a warm start that skips formulation."""
        found = self.search(instruction, objects, k=1)
        return found[0] if found and found[0].score >= threshold else None
