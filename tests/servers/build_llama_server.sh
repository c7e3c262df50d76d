#!/usr/bin/env bash
# Build llama.cpp's llama-server and its shared libraries (libllama, libggml*) from the pinned llama-cpp-python
# source package, once per machine. The same libraries serve llama-cpp-python (build_tools.sh installs its Python
# package without compiling llama.cpp again and points LLAMA_CPP_LIB_PATH at them).
# Usage: build_llama_server.sh [PYTHON]   -> prints the path of the binary on its last line (PYTHON has pip).
# Cache: ${KINTSUGI_CACHE:-~/.cache/kintsugi}/llama-cpp-python-$VERSION/ (sdist, sources, build-shared, bin).
set -euo pipefail
VERSION="${LLAMA_CPP_PYTHON_VERSION:-0.3.36}"
PY="${1:-python3}"
CACHE="${KINTSUGI_CACHE:-$HOME/.cache/kintsugi}/llama-cpp-python-$VERSION"
BIN="$CACHE/bin/llama-server"
LIB="$CACHE/bin/libllama.so"
if [ -x "$BIN" ] && [ -f "$LIB" ]; then echo "$BIN"; exit 0; fi
mkdir -p "$CACHE"
exec 9>"$CACHE/.lock"
flock 9
if [ -x "$BIN" ] && [ -f "$LIB" ]; then echo "$BIN"; exit 0; fi
SDIST="$CACHE/llama_cpp_python-$VERSION.tar.gz"
if [ ! -f "$SDIST" ]; then
  "$PY" -m pip download --quiet --disable-pip-version-check --no-binary :all: --no-deps \
    "llama-cpp-python==$VERSION" -d "$CACHE" >&2
fi
if [ ! -d "$CACHE/src" ]; then
  rm -rf "$CACHE/src.tmp" && mkdir -p "$CACHE/src.tmp"
  tar -xzf "$SDIST" -C "$CACHE/src.tmp" --strip-components=1
  mv "$CACHE/src.tmp" "$CACHE/src"
fi
BUILD="$CACHE/build-shared"
JOBS="${KINTSUGI_BUILD_JOBS:-$(nproc)}"
# Shared libraries with an $ORIGIN run path: the binary and the libraries find each other wherever they are copied.
nice -n "${KINTSUGI_BUILD_NICE:-10}" cmake -S "$CACHE/src/vendor/llama.cpp" -B "$BUILD" -G Ninja \
  -DCMAKE_BUILD_TYPE=Release -DGGML_NATIVE=OFF -DLLAMA_BUILD_TESTS=OFF -DLLAMA_BUILD_EXAMPLES=OFF \
  -DLLAMA_BUILD_UI=OFF -DLLAMA_USE_PREBUILT_UI=OFF -DLLAMA_OPENSSL=OFF -DLLAMA_CURL=OFF \
  -DBUILD_SHARED_LIBS=ON -DCMAKE_BUILD_WITH_INSTALL_RPATH=ON '-DCMAKE_INSTALL_RPATH=$ORIGIN' >&2
nice -n "${KINTSUGI_BUILD_NICE:-10}" cmake --build "$BUILD" --target llama-server llama -j "$JOBS" >&2
mkdir -p "$CACHE/bin.tmp"
cp -P "$BUILD"/bin/*.so* "$BUILD/bin/llama-server" "$CACHE/bin.tmp/"
rm -rf "$CACHE/bin.old" "$CACHE/build"
[ -d "$CACHE/bin" ] && mv "$CACHE/bin" "$CACHE/bin.old"
mv "$CACHE/bin.tmp" "$CACHE/bin" && rm -rf "$CACHE/bin.old"
echo "$BIN"
