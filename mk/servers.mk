# Real model servers for tests/servers, built once per machine from the pinned llama-cpp-python source package
# into ~/.cache/kintsugi (KINTSUGI_CACHE): llama.cpp is compiled once, as shared libraries, for llama.cpp's
# llama-server (about 6 minutes of 2 cores the first time, seconds later) and llama-cpp-python's own server
# (installed on those libraries without compiling again: about half a minute more).
servers: setup
	tests/servers/prepare.sh $(abspath $(BIN))/python

# The real-server conformance suite alone (tests/servers; `make test` runs it too): every reasoner role of every
# system through the openai backend against llama-server and llama-cpp-python's server, one short trial per
# system, campaigns stopped or run by the preflight.
test-servers: servers
	KINTSUGI_REAL_SERVERS=1 $(BIN)/pytest tests/servers -q

.PHONY: servers test-servers
