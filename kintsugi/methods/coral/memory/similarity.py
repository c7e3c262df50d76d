"""How alike two tasks are, offline: words of the instruction, and the objects' kinds and sizes.

Lexical: TF-IDF cosine of the instructions over the memory's own corpus (written here in a few
lines of numpy; scikit-learn would add a large dependency for the same twenty lines).
Parametric: objects matched by label, each pair scored by how close their sizes are on a log
scale. With an embeddings endpoint configured, the lexical part is replaced by the cosine of
the endpoint's embeddings (see embed.py).
"""

from __future__ import annotations

import math
import re
from collections import Counter
from typing import Sequence

import numpy as np

from kintsugi.methods.coral.types import ObjectView

STOPWORDS = frozenset("a an the it its to of on in into onto and then with by from until up so that is as at".split())


def tokens(text: str) -> list[str]:
    return [w for w in re.findall(r"[a-z0-9]+", text.lower()) if w not in STOPWORDS]


def tfidf_cosine(query: str, documents: Sequence[str]) -> np.ndarray:
    """Cosine similarity in [0, 1] of `query` to each document, TF-IDF weighted over the documents + query."""
    docs = [Counter(tokens(d)) for d in documents]
    q = Counter(tokens(query))
    if not docs:
        return np.zeros(0)
    vocab = sorted(set(q).union(*docs))
    index = {w: i for i, w in enumerate(vocab)}
    n = len(docs) + 1
    df = np.zeros(len(vocab))
    for c in (*docs, q):
        for w in c:
            df[index[w]] += 1
    idf = np.log((1 + n) / (1 + df)) + 1.0

    def vec(c: Counter) -> np.ndarray:
        v = np.zeros(len(vocab))
        for w, k in c.items():
            v[index[w]] = k * idf[index[w]]
        norm = np.linalg.norm(v)
        return v / norm if norm > 0 else v

    qv = vec(q)
    return np.array([float(vec(d) @ qv) for d in docs])


def cosine(a: Sequence[float], b: Sequence[float]) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    denom = np.linalg.norm(a) * np.linalg.norm(b)
    return float(a @ b / denom) if denom > 0 and a.shape == b.shape else 0.0


def object_similarity(a: Sequence[ObjectView], b: Sequence[ObjectView]) -> float:
    """In [0, 1]: each object of `a` paired with the best-matching of `b` (same label words, then size),
    averaged over the larger set so a scene with extra objects scores lower."""
    if not a or not b:
        return 0.0
    total = 0.0
    for x in a:
        total += max(_pair(x, y) for y in b)
    return total / max(len(a), len(b))


def _pair(x: ObjectView, y: ObjectView) -> float:
    wx, wy = set(tokens(x.label)), set(tokens(y.label))
    label = len(wx & wy) / len(wx | wy) if wx | wy else 0.0
    if label == 0.0:
        return 0.0
    # Sizes compared sorted (a box turned on its side is the same box), on a log scale: x2 apart -> ~0.5.
    sx, sy = sorted(x.size_m), sorted(y.size_m)
    spread = sum(abs(math.log(p / q)) for p, q in zip(sx, sy)) / 3
    return label * math.exp(-spread)
