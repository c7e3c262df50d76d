"""The console script's module stays light: processes that multiprocessing starts import it again."""

from __future__ import annotations

import subprocess
import sys


def test_importing_the_entry_module_loads_no_cli_library() -> None:
    code = "import sys, kintsugi.__main__; print(sorted(m for m in ('typer', 'rich', 'kintsugi.cli') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "[]"


def test_python_dash_m_kintsugi_runs_the_cli() -> None:
    out = subprocess.run([sys.executable, "-m", "kintsugi", "--help"], capture_output=True, text=True, check=True)
    assert "Usage" in out.stdout
