"""Real file-system faults for tests: a read-only directory and a full one.

Where the test process may mount (root with CAP_SYS_ADMIN, as on a developer's container),
each is a small tmpfs of its own (``mount -o ro``: EROFS even for root; a few KiB filled to
the last byte: ENOSPC). A read-only directory is otherwise ``chmod 0555`` where that binds
(not root). Where neither works the fixture skips, saying so; the same code paths are also
driven everywhere by tests that inject the errno (their docstrings say where)."""

from __future__ import annotations

import contextlib
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest


@contextlib.contextmanager
def tmpfs(where: Path, options: str) -> Iterator[bool]:
    """Mount a tmpfs with ``options`` at ``where`` for the block; yields whether it could."""
    where.mkdir(parents=True, exist_ok=True)
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(where)], capture_output=True
    )
    try:
        yield done.returncode == 0
    finally:
        if done.returncode == 0:
            subprocess.run(["umount", "-l", str(where)], check=True)


@contextlib.contextmanager
def read_only(where: Path) -> Iterator[Path]:
    """A read-only directory ``where``: a read-only tmpfs, else chmod (not root), else skip."""
    if os.geteuid() != 0:
        where.mkdir(parents=True)
        where.chmod(0o555)
        try:
            yield where
        finally:
            where.chmod(0o755)
        return
    with tmpfs(where, "ro,size=64k") as mounted:
        if not mounted:
            pytest.skip("root here, so chmod does not bind, and no tmpfs can be mounted")
        yield where


@contextlib.contextmanager
def full(where: Path) -> Iterator[Path]:
    """A directory ``where`` on a file system with no space left (a filled tmpfs), else skip."""
    with tmpfs(where, "size=64k") as mounted:
        if not mounted:
            pytest.skip("no tmpfs can be mounted here (needs CAP_SYS_ADMIN)")
        with contextlib.suppress(OSError), open(where / "filler", "wb", buffering=0) as fh:
            while True:
                fh.write(b"\0" * 4096)
        yield where
