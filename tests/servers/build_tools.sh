#!/usr/bin/env bash
# A tool venv for the real-server tests, once per machine: the `gguf` package (writes the tiny model) and,
# with KINTSUGI_LLAMA_CPP_PYTHON=1, llama-cpp-python's own OpenAI-compatible server, built from the same
# pinned source package as llama-server (about 4 more minutes on 2 cores).
# Usage: build_tools.sh [PYTHON]  -> prints the venv's python on its last line.
set -euo pipefail
VERSION="${LLAMA_CPP_PYTHON_VERSION:-0.3.36}"
GGUF_VERSION="${GGUF_VERSION:-0.19.0}"
PY="${1:-python3}"
CACHE="${KINTSUGI_CACHE:-$HOME/.cache/kintsugi}/llama-cpp-python-$VERSION"
VENV="$CACHE/venv"
DONE="$VENV/.kintsugi-tools-ok"
WANT_SERVER="${KINTSUGI_LLAMA_CPP_PYTHON:-0}"
if [ -f "$DONE" ] || { [ "$WANT_SERVER" != 1 ] && [ -f "$VENV/.kintsugi-gguf-ok" ]; }; then
  echo "$VENV/bin/python"; exit 0
fi
mkdir -p "$CACHE"
exec 9>"$CACHE/.tools.lock"
flock 9
if [ -f "$DONE" ]; then echo "$VENV/bin/python"; exit 0; fi
[ -x "$VENV/bin/python" ] || "$PY" -m venv "$VENV"
[ -f "$VENV/.kintsugi-gguf-ok" ] || { "$VENV/bin/pip" install --quiet --disable-pip-version-check \
  "gguf==$GGUF_VERSION" >&2 && touch "$VENV/.kintsugi-gguf-ok"; }
if [ "$WANT_SERVER" != 1 ]; then echo "$VENV/bin/python"; exit 0; fi
SDIST="$CACHE/llama_cpp_python-$VERSION.tar.gz"
SRC="llama-cpp-python[server]==$VERSION"
[ -f "$SDIST" ] && SRC="llama-cpp-python[server] @ file://$SDIST"
CMAKE_ARGS="-DGGML_NATIVE=OFF -DLLAVA_BUILD=OFF -DLLAMA_BUILD_TESTS=OFF -DLLAMA_BUILD_EXAMPLES=OFF" \
  nice -n "${KINTSUGI_BUILD_NICE:-10}" "$VENV/bin/pip" install --quiet --disable-pip-version-check "$SRC" >&2
touch "$DONE"
echo "$VENV/bin/python"
