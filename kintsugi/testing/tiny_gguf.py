"""Write a tiny, seeded, random-weight llama model as GGUF (about 1 MB), for serving with llama.cpp in
conformance checks.

Run as a script with a Python that has the `gguf` package (the servers' tool venv, see
`tests/servers/build_tools.sh`; `servers.tiny_model` does); nothing in the package imports it:
    python tiny_gguf.py OUT.gguf [--context 32768] [--seed 0] [--words FILE ...]

The model knows nothing; it exists so real server software can be driven end to end. Its tokenizer is
SentencePiece-style (`llama`): the 256 byte tokens, printable ASCII, and the words (with their prefixes)
of the given text files, so English and JSON cost roughly what they cost a real tokenizer (a few
characters per token). The chat template is ChatML with tools as <tool_call> JSON (the widely used Qwen2.5 layout, which
llama.cpp's server parses).
"""

from __future__ import annotations

import argparse
import re
import string
from collections import Counter
from pathlib import Path

import numpy as np
from gguf import GGUFWriter, TokenType

EMBED, BLOCKS, FFN, HEADS, KV_HEADS = 64, 2, 128, 4, 4
ROPE_DIM = EMBED // HEADS
SPACE = "\u2581"  # SentencePiece's word boundary
MAX_WORDS = 3000

CHAT_TEMPLATE = r"""{%- if tools %}
{{- '<|im_start|>system\n' }}
{%- if messages[0]['role'] == 'system' %}{{- messages[0]['content'] }}{%- else %}{{- 'You are a helpful assistant.' }}{%- endif %}
{{- "\n\n# Tools\n\nYou may call one or more functions.\n\nFunction signatures within <tools></tools> XML tags:\n<tools>" }}
{%- for tool in tools %}{{- "\n" }}{{- tool | tojson }}{%- endfor %}
{{- "\n</tools>\n\nFor each call, return a JSON object with the function name and arguments within <tool_call></tool_call> XML tags:\n<tool_call>\n{\"name\": <function-name>, \"arguments\": <args-json-object>}\n</tool_call><|im_end|>\n" }}
{%- else %}
{%- if messages[0]['role'] == 'system' %}{{- '<|im_start|>system\n' + messages[0]['content'] + '<|im_end|>\n' }}{%- endif %}
{%- endif %}
{%- for message in messages %}
{%- if (message.role == "user") or (message.role == "system" and not loop.first) or (message.role == "assistant" and not message.tool_calls) %}
{{- '<|im_start|>' + message.role + '\n' + message.content + '<|im_end|>' + '\n' }}
{%- elif message.role == "assistant" %}
{{- '<|im_start|>' + message.role }}
{%- if message.content %}{{- '\n' + message.content }}{%- endif %}
{%- for tool_call in message.tool_calls %}
{%- if tool_call.function is defined %}{%- set tool_call = tool_call.function %}{%- endif %}
{{- '\n<tool_call>\n{"name": "' }}{{- tool_call.name }}{{- '", "arguments": ' }}{{- tool_call.arguments | tojson }}{{- '}\n</tool_call>' }}
{%- endfor %}
{{- '<|im_end|>\n' }}
{%- elif message.role == "tool" %}
{%- if (loop.index0 == 0) or (messages[loop.index0 - 1].role != "tool") %}{{- '<|im_start|>user' }}{%- endif %}
{{- '\n<tool_response>\n' }}{{- message.content }}{{- '\n</tool_response>' }}
{%- if loop.last or (messages[loop.index0 + 1].role != "tool") %}{{- '<|im_end|>\n' }}{%- endif %}
{%- endif %}
{%- endfor %}
{%- if add_generation_prompt %}{{- '<|im_start|>assistant\n' }}{%- endif %}"""


def vocabulary(texts: list[str]) -> tuple[list[str], list[float], list[int]]:
    tokens = ["<unk>", "<s>", "</s>", "<|im_start|>", "<|im_end|>"]
    types = [TokenType.UNKNOWN, TokenType.CONTROL, TokenType.CONTROL, TokenType.CONTROL, TokenType.CONTROL]
    tokens += [f"<0x{b:02X}>" for b in range(256)]
    types += [TokenType.BYTE] * 256
    pieces: list[str] = [SPACE] + [c for c in string.printable if c not in string.whitespace] + ["\n"]
    words = Counter(w for text in texts for w in re.findall(r"[A-Za-z_]+|[0-9]+|[^\sA-Za-z0-9]{1,3}", text))
    for word, _ in words.most_common(MAX_WORDS):
        for prefix in (SPACE, ""):
            full = prefix + word
            pieces += [full[:i] for i in range(2, len(full) + 1)]
    seen = set(tokens)
    for piece in pieces:
        if piece not in seen:
            seen.add(piece)
            tokens.append(piece)
            types.append(TokenType.NORMAL)
    # Longer pieces merge first (SentencePiece merges the best-scoring pair).
    scores = [0.0] * len(tokens)
    for i, (tok, kind) in enumerate(zip(tokens, types)):
        if kind == TokenType.NORMAL:
            scores[i] = float(len(tok)) - i * 1e-6
        elif kind == TokenType.BYTE:
            scores[i] = -1000.0
    return tokens, scores, [int(t) for t in types]


def write(out: Path, context: int, seed: int, texts: list[str]) -> None:
    tokens, scores, types = vocabulary(texts)
    rng = np.random.default_rng(seed)

    def mat(rows: int, cols: int) -> np.ndarray:
        return (rng.standard_normal((rows, cols)) * 0.02).astype(np.float32)

    w = GGUFWriter(str(out), "llama")
    w.add_name("kintsugi-tiny")
    w.add_context_length(context)
    w.add_embedding_length(EMBED)
    w.add_block_count(BLOCKS)
    w.add_feed_forward_length(FFN)
    w.add_head_count(HEADS)
    w.add_head_count_kv(KV_HEADS)
    w.add_rope_dimension_count(ROPE_DIM)
    w.add_layer_norm_rms_eps(1e-5)
    w.add_vocab_size(len(tokens))
    w.add_file_type(0)  # all F32
    w.add_tokenizer_model("llama")
    w.add_token_list(tokens)
    w.add_token_scores(scores)
    w.add_token_types(types)
    w.add_unk_token_id(0)
    w.add_bos_token_id(1)
    w.add_eos_token_id(tokens.index("<|im_end|>"))
    w.add_add_bos_token(True)
    w.add_add_space_prefix(False)
    w.add_chat_template(CHAT_TEMPLATE)
    w.add_tensor("token_embd.weight", mat(len(tokens), EMBED))
    w.add_tensor("output_norm.weight", np.ones(EMBED, dtype=np.float32))
    w.add_tensor("output.weight", mat(len(tokens), EMBED))
    for b in range(BLOCKS):
        p = f"blk.{b}."
        w.add_tensor(p + "attn_norm.weight", np.ones(EMBED, dtype=np.float32))
        w.add_tensor(p + "attn_q.weight", mat(EMBED, EMBED))
        w.add_tensor(p + "attn_k.weight", mat(EMBED // HEADS * KV_HEADS, EMBED))
        w.add_tensor(p + "attn_v.weight", mat(EMBED // HEADS * KV_HEADS, EMBED))
        w.add_tensor(p + "attn_output.weight", mat(EMBED, EMBED))
        w.add_tensor(p + "ffn_norm.weight", np.ones(EMBED, dtype=np.float32))
        w.add_tensor(p + "ffn_gate.weight", mat(FFN, EMBED))
        w.add_tensor(p + "ffn_up.weight", mat(FFN, EMBED))
        w.add_tensor(p + "ffn_down.weight", mat(EMBED, FFN))
    w.write_header_to_file()
    w.write_kv_data_to_file()
    w.write_tensors_to_file()
    w.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--context", type=int, default=32768)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--words", type=Path, nargs="*", default=[], help="text files whose words join the vocabulary")
    args = parser.parse_args()
    texts = [p.read_text(encoding="utf-8") for p in args.words]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_suffix(".tmp")
    write(tmp, args.context, args.seed, texts)
    tmp.replace(args.out)
    print(args.out)


if __name__ == "__main__":
    main()
