"""What the batch process knows of a file without reading it: its stat key, and the SHA-256
the ledger remembers for that key.

A file's :class:`~pipeline.hashing.FileKey` — device, inode, size, modification and
status-change times in nanoseconds — stands for its content while it holds: writing a file
moves its ``ctime``, which no program can set back. The batch process never reads an input:
it stats it (O(1)), and a worker hashes it; the ledger's ``file_hashes`` table
(:class:`HashCache`) keeps the hash a worker found for the key the batch process saw, so the
next batch knows the hash of an untouched file from its stat alone. Hard links share an
inode, hence one entry. The key is read through a descriptor opened for it (nothing is
read): on NFS, opening a file makes the client check its attributes with the server
(close-to-open consistency), where a plain ``stat`` may answer from the attribute cache
(``acregmax``, 60 s by default) and miss a write made on another machine meanwhile.

A hash is remembered only when the batch process saw the same key before the worker hashed
the file and after its result came back, and the file's last change lay at least
:data:`SETTLED_S` before the first look: a file changed again within the same timestamp tick
could otherwise keep its key with other bytes. Keys never decide alone what a file holds
when they are unknown or differ: the file is then hashed again, in a worker.
"""

from __future__ import annotations

import re
import sqlite3
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from pipeline.hashing import FileKey, file_key

SETTLED_S = 2.0
"""a file whose ``ctime`` is younger than this when first seen is hashed again next time"""
SHA256 = re.compile(r"^[0-9a-f]{64}\Z")
INT64 = 2**63

SCHEMA = """
CREATE TABLE IF NOT EXISTS file_hashes (
    path TEXT NOT NULL,
    dev INTEGER NOT NULL,
    ino INTEGER NOT NULL,
    size INTEGER NOT NULL,
    mtime_ns INTEGER NOT NULL,
    ctime_ns INTEGER NOT NULL,
    sha256 TEXT NOT NULL,
    PRIMARY KEY (dev, ino)
)
"""


@dataclass(frozen=True)
class Seen:
    """A file as the batch process saw it: its key (None: it could not be stat'ed, or is not
    a regular file) at ``at`` (POSIX seconds)."""

    path: str
    key: FileKey | None
    at: float

    def settled(self, after: FileKey | None) -> bool:
        """Whether a hash taken between this look and one that saw ``after`` is the hash of
        this key (module docstring)."""
        key = self.key
        return (
            key is not None
            and key == after
            and key.ctime_ns < (self.at - SETTLED_S) * 1e9
            and 0 <= key.dev < INT64
            and 0 <= key.ino < INT64
        )


def look(path: Path | str) -> tuple[Seen, OSError | None]:
    """``path`` as seen now, and why it cannot be read if it cannot (from its stat alone)."""
    now = time.time()
    try:
        return Seen(str(path), file_key(path), now), None
    except OSError as exc:
        return Seen(str(path), None, now), exc


class HashCache:
    """The ledger's ``file_hashes`` table on an open connection (module docstring). Writes
    belong in the caller's transaction."""

    def __init__(self, db: sqlite3.Connection) -> None:
        self._db = db

    def get(self, key: FileKey) -> str | None:
        """The SHA-256 remembered for ``key``; None if none (or the row is damaged)."""
        if not (0 <= key.dev < INT64 and 0 <= key.ino < INT64):
            return None
        row = self._db.execute(
            "SELECT sha256 FROM file_hashes WHERE dev = ? AND ino = ? AND size = ? AND "
            "mtime_ns = ? AND ctime_ns = ?",
            key,
        ).fetchone()
        digest = row[0] if row is not None else None
        return digest if isinstance(digest, str) and SHA256.match(digest) else None

    def forget(self, paths: Iterable[str]) -> None:
        """Drop what is remembered of the files at ``paths`` (replaced: a well published
        again)."""
        self._db.executemany("DELETE FROM file_hashes WHERE path = ?", [(p,) for p in paths])

    def put(self, entries: Iterable[tuple[str, FileKey, str]]) -> None:
        """Remember (path, key, sha256) for each entry (one row per device and inode)."""
        self._db.executemany(
            "INSERT OR REPLACE INTO file_hashes (path, dev, ino, size, mtime_ns, ctime_ns, "
            "sha256) VALUES (?, ?, ?, ?, ?, ?, ?)",
            [(path, *key, digest) for path, key, digest in entries if SHA256.match(digest)],
        )
