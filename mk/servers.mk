# Real model servers for tests/servers, built once per machine from the pinned llama-cpp-python source package
# into ~/.cache/kintsugi (KINTSUGI_CACHE): llama.cpp's llama-server (about 6 minutes of 2 cores the first time,
# seconds later) for `make test`; llama-cpp-python's own server too (about 4 more) for `make test-servers`.
servers: setup
	tests/servers/prepare.sh $(abspath $(BIN))/python

# The real-server conformance suite (tests/servers): every reasoner role of every system through the openai
# backend against llama-server and llama-cpp-python's server, and one short trial per system.
test-servers: setup
	KINTSUGI_LLAMA_CPP_PYTHON=1 tests/servers/prepare.sh $(abspath $(BIN))/python
	KINTSUGI_REAL_SERVERS=1 $(BIN)/pytest tests/servers -q

.PHONY: servers test-servers
