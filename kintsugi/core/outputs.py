"""Where results go, checked before a trial runs: a bad path must never cost a trial (or a paid model's tokens)."""

from __future__ import annotations

import os
from pathlib import Path

from kintsugi.core.errors import ConfigError


def check_output_file(path: Path, what: str, suffixes: tuple[str, ...] = ()) -> Path:
    """Raise ConfigError unless `path` can be written as a file with one of `suffixes`.

    Missing parent directories are fine (they are created when the file is written),
    as long as the nearest existing one is a writable directory.
    """
    path = Path(path)
    if suffixes and path.suffix.lower() not in suffixes:
        raise ConfigError(f"{what} path {path} must end in {' or '.join(suffixes)}")
    if path.is_dir():
        raise ConfigError(f"{what} path {path} is a directory; give a file name")
    _check_writable_dir(path.parent, what)
    if path.exists() and not os.access(path, os.W_OK):
        raise ConfigError(f"cannot write {what} {path}: the file is not writable")
    return path


def check_output_dir(path: Path, what: str) -> Path:
    """Raise ConfigError unless `path` is (or can be created as) a writable directory."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ConfigError(f"{what} {path} exists and is not a directory; choose another path")
    _check_writable_dir(path, what)
    return path


def _check_writable_dir(directory: Path, what: str) -> None:
    probe = Path(os.path.abspath(directory))
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    if not probe.is_dir():
        raise ConfigError(f"cannot write {what} under {directory}: {probe} is a file, not a directory")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise ConfigError(f"cannot write {what} under {directory}: {probe} is not writable")
