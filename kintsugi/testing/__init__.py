"""Tools for checking your own reasoner backend, method or model server against kintsugi.

- `peg_requests`, `pour_requests`, `push_requests`: hand-built, realistic requests of the reasoner roles of
  systems A, B and C (no simulator);
- `role_requests`: one such request per registered role (`build(role)`, `system_roles()`);
- `servers`: real OpenAI-compatible servers on 127.0.0.1 (llama.cpp's `llama-server`, llama-cpp-python's
  server; `make servers` builds them) serving a tiny random-weight GGUF model that `tiny_gguf.py` writes
  (a script, run with the servers' tool venv).

Nothing else in the package imports this subpackage, and importing it imports none of its modules.
"""
