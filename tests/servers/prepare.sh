#!/usr/bin/env bash
# Build the real servers kintsugi/testing/servers.py starts (for tests/servers and bench/bench_reasoner_latency.py),
# once per machine; see mk/servers.mk.
# Where the build is impossible (no C++ compiler or cmake), write the reason for the tests to skip with.
# Usage: prepare.sh [PYTHON]
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
PY="${1:-python3}"
VERSION="${LLAMA_CPP_PYTHON_VERSION:-0.3.36}"
CACHE="${KINTSUGI_CACHE:-$HOME/.cache/kintsugi}/llama-cpp-python-$VERSION"
mkdir -p "$CACHE"
rm -f "$CACHE/unavailable.txt"
missing=()
for tool in cmake c++ cc; do command -v "$tool" >/dev/null 2>&1 || missing+=("$tool"); done
command -v ninja >/dev/null 2>&1 || "$PY" -c "import ninja" 2>/dev/null || missing+=("ninja")
if [ ${#missing[@]} -gt 0 ]; then
  echo "no ${missing[*]} on this machine (needed to build llama.cpp)" > "$CACHE/unavailable.txt"
  echo "servers: skipped, $(cat "$CACHE/unavailable.txt")" >&2
  exit 0
fi
start=$(date +%s)
"$HERE/build_llama_server.sh" "$PY" >/dev/null
"$HERE/build_tools.sh" "$PY" >/dev/null
echo "servers: llama-server and llama-cpp-python $VERSION (one llama.cpp build) ready in $CACHE ($(( $(date +%s) - start )) s)" >&2
