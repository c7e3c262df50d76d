#!/usr/bin/env bash
# A tool venv for the real servers (kintsugi/testing/servers.py), once per machine: the `gguf` package (runs
# kintsugi/testing/tiny_gguf.py, which writes the tiny model) and
# llama-cpp-python's own OpenAI-compatible server from the same pinned source package as llama-server, without
# compiling llama.cpp again: its Python package is installed with LLAMA_BUILD=OFF and loads the shared libraries
# build_llama_server.sh made (linked into llama_cpp/lib). About half a minute after llama-server's build.
# KINTSUGI_LLAMA_CPP_PYTHON=0 leaves llama-cpp-python out.
# Usage: build_tools.sh [PYTHON]  -> prints the venv's python on its last line.
set -euo pipefail
VERSION="${LLAMA_CPP_PYTHON_VERSION:-0.3.36}"
GGUF_VERSION="${GGUF_VERSION:-0.19.0}"
PY="${1:-python3}"
CACHE="${KINTSUGI_CACHE:-$HOME/.cache/kintsugi}/llama-cpp-python-$VERSION"
VENV="$CACHE/venv"
DONE="$VENV/.kintsugi-llama-cpp-python-ok"
WANT_SERVER="${KINTSUGI_LLAMA_CPP_PYTHON:-1}"
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
LIBS="${KINTSUGI_LLAMA_LIBS:-$CACHE/bin}"
if [ ! -f "$LIBS/libllama.so" ]; then
  echo "build_tools.sh: $LIBS/libllama.so is missing; run build_llama_server.sh first" >&2; exit 1
fi
SDIST="$CACHE/llama_cpp_python-$VERSION.tar.gz"
SRC="llama-cpp-python[server]==$VERSION"
[ -f "$SDIST" ] && SRC="llama-cpp-python[server] @ file://$SDIST"
CMAKE_ARGS="-DLLAMA_BUILD=OFF -DLLAVA_BUILD=OFF" \
  "$VENV/bin/pip" install --quiet --disable-pip-version-check "$SRC" >&2
PKG="$("$VENV/bin/python" -c 'import importlib.util, pathlib; print(pathlib.Path(importlib.util.find_spec("llama_cpp").origin).parent)')"
mkdir -p "$PKG/lib"
for lib in "$LIBS"/*.so*; do ln -sfn "$lib" "$PKG/lib/$(basename "$lib")"; done
"$VENV/bin/python" -c "import llama_cpp; llama_cpp.llama_backend_init()" >&2
touch "$DONE"
echo "$VENV/bin/python"
