# Real model servers for tests/servers: llama.cpp's llama-server and llama-cpp-python's own server, built once
# per machine from the pinned llama-cpp-python source package into ~/.cache/kintsugi (KINTSUGI_CACHE). A fresh
# machine spends about 10 minutes of 2 cores here (llama-server ~6, llama-cpp-python ~4); later runs, seconds.
servers: setup
	tests/servers/prepare.sh $(abspath $(BIN))/python

.PHONY: servers
