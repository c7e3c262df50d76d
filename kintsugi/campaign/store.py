"""A campaign's out dir: results.jsonl (one line per finished trial) and campaign.json.

Each record is appended as one line and fsync'd before the next trial is counted
as done, so a kill at any moment loses at most the line being written. Reading
tolerates that torn last line; opening for append cuts the file back to the last
complete line, so the next append starts on a clean line.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
from pathlib import Path
from typing import Any, Iterator

from pydantic import ValidationError

import kintsugi
from kintsugi.campaign.plan import RESUMABLE_FIELDS, CampaignConfig
from kintsugi.core.errors import KintsugiError
from kintsugi.core.outputs import check_output_dir
from kintsugi.core.record import TrialRecord

RESULTS = "results.jsonl"
MANIFEST = "campaign.json"


class ResultStore:
    """The files of one campaign out dir."""

    def __init__(self, out_dir: str | Path) -> None:
        self.out_dir = Path(out_dir)
        self.results_path = self.out_dir / RESULTS
        self.manifest_path = self.out_dir / MANIFEST

    # ----- manifest -------------------------------------------------------------------
    def load_config(self) -> CampaignConfig:
        """The config recorded in campaign.json."""
        if not self.manifest_path.exists():
            raise KintsugiError(f"{self.manifest_path} not found; is {self.out_dir} a campaign out dir?")
        try:
            return CampaignConfig.model_validate(json.loads(self.manifest_path.read_text())["config"])
        except (OSError, ValueError, KeyError, TypeError) as exc:  # ValidationError is a ValueError
            raise KintsugiError(f"{self.manifest_path} is not a readable campaign manifest "
                                f"({type(exc).__name__}: {str(exc).splitlines()[0]})") from None

    def ensure_manifest(self, cfg: CampaignConfig) -> None:
        """Write campaign.json on first start; on a later start, refuse a different config.

        Only `trials` (and `videos_per_cell`) may differ; the manifest is then updated.
        An out dir that cannot be written is a KintsugiError, raised before any trial runs.
        """
        check_output_dir(self.out_dir, "campaign directory")
        try:
            self._ensure_manifest(cfg)
        except OSError as exc:
            raise KintsugiError(f"cannot write campaign directory {self.out_dir}: {exc}") from None

    def _ensure_manifest(self, cfg: CampaignConfig) -> None:
        self.out_dir.mkdir(parents=True, exist_ok=True)
        new = cfg.model_dump(mode="json")
        if self.manifest_path.exists():
            old = self.load_config().model_dump(mode="json")
            diffs = [
                k for k in sorted(set(old) | set(new))
                if k not in RESUMABLE_FIELDS and old.get(k) != new.get(k)
            ]
            if diffs:
                detail = "; ".join(f"{k}: {old.get(k)!r} -> {new.get(k)!r}" for k in diffs)
                raise KintsugiError(
                    f"{self.out_dir} holds a campaign with a different config ({detail}). "
                    "Rerun with the original config to resume it, or choose a new out dir; "
                    "only the number of trials may change between runs."
                )
            if old == new:
                return
        elif self.results_path.exists() and self.results_path.stat().st_size > 0:
            raise KintsugiError(
                f"{self.results_path} exists but {self.manifest_path} does not, so its config is unknown. "
                "Move results.jsonl away or choose a new out dir."
            )
        manifest = {
            "kintsugi_version": kintsugi.__version__,
            "updated": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "config": new,
        }
        tmp = self.manifest_path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(manifest, indent=2) + "\n")
        os.replace(tmp, self.manifest_path)

    # ----- results --------------------------------------------------------------------
    def _scan(self) -> tuple[list[TrialRecord], int, bool]:
        """Parse results.jsonl -> (records, byte length of the good prefix, needs newline).

        A torn last line (no trailing newline) is kept if it parses (the kill came
        just before the newline), else dropped. A bad line in the middle is an error.
        """
        if not self.results_path.exists():
            return [], 0, False
        data = self.results_path.read_bytes()
        records: list[TrialRecord] = []
        good = 0
        lines = data.split(b"\n")  # the last element is b"" when the file ends with a newline
        for lineno, raw in enumerate(lines, start=1):
            is_last = lineno == len(lines)
            if not raw.strip():
                good += len(raw) + (0 if is_last else 1)
                continue
            try:
                records.append(TrialRecord.model_validate_json(raw))
            except (ValidationError, ValueError) as exc:
                if is_last:  # torn write from a killed process: drop it, the trial reruns
                    return records, good, False
                raise KintsugiError(
                    f"{self.results_path} line {lineno} is not a valid trial record ({exc.__class__.__name__}). "
                    "Only the last line can be torn by a kill; fix or delete that line, then rerun."
                ) from None
            if is_last:
                return records, good + len(raw), True
            good += len(raw) + 1
        return records, good, False

    def read(self) -> list[TrialRecord]:
        """All complete records, first occurrence of each key only; never modifies the file."""
        records, _, _ = self._scan()
        seen: set[str] = set()
        unique = []
        for r in records:
            if r.key not in seen:
                seen.add(r.key)
                unique.append(r)
        return unique

    def done_keys(self) -> set[str]:
        """Keys of trials already recorded (resume skips them)."""
        return {r.key for r in self.read()}

    def repair(self) -> None:
        """Cut a torn last line (or complete a parsable one) so appends start on a fresh line."""
        _, good, needs_newline = self._scan()
        if not self.results_path.exists():
            return
        size = self.results_path.stat().st_size
        if needs_newline:
            with open(self.results_path, "ab") as f:
                f.write(b"\n")
                f.flush()
                os.fsync(f.fileno())
        elif good < size:
            with open(self.results_path, "r+b") as f:
                f.truncate(good)
                f.flush()
                os.fsync(f.fileno())

    def appender(self) -> "Appender":
        """Repair the file, then open it for durable appends (use as a context manager)."""
        self.out_dir.mkdir(parents=True, exist_ok=True)
        self.repair()
        return Appender(self.results_path)


class Appender:
    """Appends one JSON line per record, flushed and fsync'd before returning."""

    def __init__(self, path: Path) -> None:
        self._file = open(path, "ab")

    def append(self, record: TrialRecord) -> None:
        line = record.model_dump_json().encode() + b"\n"
        self._file.write(line)
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> "Appender":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def iter_records(out_dir: str | Path) -> Iterator[TrialRecord]:
    """Convenience for readers (report, notebooks): the records of an out dir."""
    yield from ResultStore(out_dir).read()
