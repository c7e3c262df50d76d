"""Embeddings from an OpenAI-compatible endpoint's embeddings API, for the memory's instruction similarity.

Optional: offline, the memory uses TF-IDF (similarity.py). Errors (unreachable server, a model
without embeddings) are one EndpointError naming the URL and model; the caller may then fall
back to lexical similarity.
"""

from __future__ import annotations

import os
from typing import Sequence

from kintsugi.reasoning.structured import EndpointError


class OpenAIEmbedder:
    def __init__(self, model: str, base_url: str | None = None, api_key_env: str = "OPENAI_API_KEY",
                 timeout_s: float = 30.0) -> None:
        from openai import OpenAI

        key = os.environ.get(api_key_env) or ("not-needed" if base_url else None)
        if key is None:
            raise EndpointError(f"embeddings need an API key in ${api_key_env} or a --base-url for a local server")
        self.model, self.base_url = model, base_url
        self.name = f"{base_url or 'openai'}:{model}"
        self._client = OpenAI(api_key=key, base_url=base_url, timeout=timeout_s, max_retries=2)

    def __call__(self, texts: Sequence[str]) -> list[list[float]]:
        import openai

        try:
            reply = self._client.embeddings.create(model=self.model, input=list(texts))
        except openai.OpenAIError as exc:
            raise EndpointError(f"embeddings from {self.base_url or 'api.openai.com'} ({self.model}) failed: "
                                f"{type(exc).__name__}: {exc}"[:300]) from None
        vectors = [d.embedding for d in sorted(reply.data, key=lambda d: d.index)]
        if len(vectors) != len(texts):
            raise EndpointError(f"embeddings endpoint returned {len(vectors)} vectors for {len(texts)} texts")
        return vectors
