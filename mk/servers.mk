# Real model servers for tests/servers: llama.cpp's llama-server and llama-cpp-python's own server, built once
# per machine from the pinned llama-cpp-python source package into ~/.cache/kintsugi (KINTSUGI_CACHE). A fresh
# machine spends about 10 minutes of 2 cores here (llama-server ~6, llama-cpp-python ~4); later runs, seconds.
servers: setup
	tests/servers/prepare.sh $(abspath $(BIN))/python

# The real-server conformance suite (tests/servers): every reasoner role of every system through the openai
# backend against llama-server and llama-cpp-python's server, and one short trial per system.
test-servers: servers
	KINTSUGI_REAL_SERVERS=1 $(BIN)/pytest tests/servers -q

.PHONY: servers test-servers
