"""Toy plugins: each module is one file a user could write, registered in one line, loaded with
`--plugin tests.plugins.<name>` (or `load_plugins([...])`), and held to the same task contract as
the built-ins (tests/contract/test_task_contract.py)."""
