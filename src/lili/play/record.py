"""Each session's shots as CSV, like the paper's study: one row per shot.

Columns: ``session, shot, aim`` (radians, see :mod:`lili.play.striker`), ``mode`` (the mode
whose aim is nearest: left, middle or right), ``blocked`` (0/1), ``reward`` (the blocker's
return for the shot), ``puck_x`` and ``paddle_x`` (metres, where the shot ended).

With a folder every session gets its own file ``<session>.csv``; with one file (``--record``)
all sessions of the server append to it. Nothing is written before a session's first shot.
The folder (or the file's folder) is checked writable when the :class:`Recorder` is made, so
``lili play`` stops at start-up rather than at a visitor's first shot. Each row is written,
flushed and synced before the shot counts; a row that cannot be written raises
:class:`RecordError` and leaves the rows before it as they were.
"""

from __future__ import annotations

import csv
import io
import os
import time
from pathlib import Path
from typing import Any

__all__ = ["Recorder", "SessionRecord", "RecordError", "COLUMNS"]

COLUMNS = ("session", "shot", "aim", "mode", "blocked", "reward", "puck_x", "paddle_x")


class RecordError(Exception):
    """A shot that could not be written to its CSV file (the message says which and why)."""


class SessionRecord:
    """Appends one session's rows to a CSV file (header when the file is new)."""

    def __init__(self, path: Path, session: str) -> None:
        self.path, self.session = path, session

    def write(self, row: dict[str, Any]) -> None:
        """Append ``row`` (flushed and synced); RecordError when it cannot be written."""
        text = io.StringIO()
        w = csv.DictWriter(text, fieldnames=COLUMNS)
        try:
            new = not self.path.exists()
            if new:
                w.writeheader()
            w.writerow({"session": self.session, **{k: row[k] for k in COLUMNS[1:]}})
            self.path.parent.mkdir(parents=True, exist_ok=True)
            # One write call per row, so a failure leaves at most this row incomplete.
            with self.path.open("a", newline="") as f:
                f.write(text.getvalue())
                f.flush()
                os.fsync(f.fileno())
        except OSError as e:
            raise RecordError(f"could not record shot {row.get('shot')} in {str(self.path)!r}: "
                              f"{e.strerror or e}") from None


class Recorder:
    """Hands out a :class:`SessionRecord` per session, into ``folder`` or all into ``file``."""

    def __init__(self, folder: str | Path | None = None, file: str | Path | None = None) -> None:
        from lili.runs import check_out_dir  # the one writability rule (lili.runs is heavy)

        if (folder is None) == (file is None):
            raise ValueError("a Recorder needs exactly one of folder or file")
        self.folder = None if folder is None else Path(folder)
        self.file = None if file is None else Path(file)
        if self.file is not None:
            if self.file.exists():
                raise ValueError(f"--record {str(self.file)!r} already exists; allowed: a new "
                                 "file (nothing is overwritten)")
            if not self.file.parent.is_dir():
                raise ValueError(f"--record {str(self.file)!r}: the folder "
                                 f"{str(self.file.parent)!r} does not exist")
            check_out_dir(self.file.parent, "--record's folder")
        else:
            check_out_dir(self.folder, "the recording folder")  # type: ignore[arg-type]
        self._count = 0

    @property
    def where(self) -> Path:
        """The folder or file the sessions go to."""
        return self.file if self.file is not None else self.folder  # type: ignore[return-value]

    def session(self) -> SessionRecord:
        """A record for a new session, named by the time and a counter."""
        self._count += 1
        name = f"{time.strftime('%Y%m%d-%H%M%S')}-{self._count}"
        if self.file is not None:
            return SessionRecord(self.file, name)
        return SessionRecord(self.folder / f"session-{name}.csv", name)  # type: ignore[operator]
