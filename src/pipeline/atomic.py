"""Atomic file output: write to a temporary name in the same directory, fsync, rename.

A reader of the final name sees either nothing or the complete file, never a truncated one,
even if the process is killed mid-write. A failing file operation (disk full, read-only,
permission) is raised as :class:`~pipeline.errors.FileSystemError` naming the final file
or directory and what was being done.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import functools
import os
import shutil
import sys
import uuid
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

from pipeline.errors import file_errors

TEMP_PREFIX = ".gyropipe-tmp-"
TRASH_SUFFIX = ".trash"


@contextlib.contextmanager
def atomic_path(final: Path) -> Iterator[Path]:
    """Yield a temporary path next to ``final``; on success it replaces ``final``. An
    ``OSError`` while it is written (inside the block) or published is a
    :class:`~pipeline.errors.FileSystemError` "cannot write ``final``"."""
    with file_errors("create directory", final.parent):
        final.parent.mkdir(parents=True, exist_ok=True)
    tmp = final.parent / f"{TEMP_PREFIX}{uuid.uuid4().hex}{final.suffix}"
    try:
        with file_errors("write", final):
            yield tmp
            fsync_file(tmp)
            os.replace(tmp, final)
            fsync_dir(final.parent)
    finally:
        with contextlib.suppress(OSError):  # e.g. read-only: there is nothing to remove
            tmp.unlink(missing_ok=True)


def atomic_write_bytes(final: Path, data: bytes) -> None:
    """Write ``data`` to ``final`` atomically."""
    with atomic_path(final) as tmp:
        tmp.write_bytes(data)


def write_synced(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` and fsync it, for a file of a private directory that is
    published whole (:func:`replace_dir` makes its entries durable before the rename): a
    temporary name and a rename of its own would add nothing there."""
    with file_errors("write", path), open(path, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())


def fsync_file(path: Path) -> None:
    with open(path, "rb") as fh:
        os.fsync(fh.fileno())


def fsync_files(paths: Sequence[Path], named: Callable[[Path], Path]) -> None:
    """fsync each of ``paths``, a failure a :class:`~pipeline.errors.FileSystemError`
    "cannot write ``named(path)``". Where the OS can (Linux ``sync_file_range``), the
    writeback of them all is started first, so that their fsyncs wait on it together rather
    than each start its own: a continuous well's 15 files took 15–30 % less CPU time
    (benchmarks/README.md). Every file is still fsynced: the start is a hint only."""
    _start_writeback(paths)
    for path in paths:
        with file_errors("write", named(path)):
            fsync_file(path)


def _start_writeback(paths: Sequence[Path]) -> None:
    """Start writing the files' dirty pages to disk without waiting (errors ignored: the
    fsync that follows reports them)."""
    start = _sync_file_range()
    if start is None:
        return
    for path in paths:
        try:
            fd = os.open(path, os.O_RDONLY)
        except OSError:
            continue
        try:
            start(fd, 0, 0, _SYNC_FILE_RANGE_WRITE)
        finally:
            os.close(fd)


_SYNC_FILE_RANGE_WRITE = 2
"""``sync_file_range``'s flag: start writeback of the range's dirty pages, do not wait"""


@functools.cache
def _sync_file_range() -> Callable[[int, int, int, int], int] | None:
    """Linux's ``sync_file_range`` (from 0 to the end with lengths 0), None elsewhere."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        call = ctypes.CDLL(None, use_errno=True).sync_file_range
    except AttributeError:
        return None
    call.argtypes = [ctypes.c_int, ctypes.c_int64, ctypes.c_int64, ctypes.c_uint]
    call.restype = ctypes.c_int
    return call


def fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def replace_dir(staging: Path, final: Path) -> None:
    """Put the complete directory ``staging`` at ``final`` (same filesystem) and delete what
    was there. Where the OS can swap two paths in one step (Linux ``renameat2`` with
    ``RENAME_EXCHANGE``) a reader sees the old complete directory or the new one, never
    neither and never a mixture; elsewhere the old one is first renamed away, so for a moment
    neither exists. Several publishers of one ``final`` leave the last one's directory. The
    old directory goes to ``<staging>.trash`` before it is deleted, so whoever cleans up
    dead staging directories finds it too. Raises
    :class:`~pipeline.errors.FileSystemError` "cannot publish ``final``"."""
    with file_errors("publish", final):
        _replace_dir(staging, final)


def _replace_dir(staging: Path, final: Path) -> None:
    fsync_dir(staging)
    trash = staging.with_name(staging.name + TRASH_SUFFIX)  # cleaned up like its staging
    while True:
        try:
            os.rename(staging, final)
            break
        except OSError as exc:
            if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST, errno.ENOTDIR):
                raise
        if _exchange(staging, final):
            os.rename(staging, trash)  # ``staging`` now holds the old directory
            break
        try:
            os.rename(final, trash)
        except FileNotFoundError:
            continue  # another publisher moved it away first: try again
    fsync_dir(final.parent)
    if staging.parent != final.parent:
        fsync_dir(staging.parent)
    discard(trash)


def discard(path: Path) -> None:
    """Delete ``path``, whatever it is, never following a link: a directory tree, or the
    symlink itself (an old well directory that was a link to a user's directory: the link
    goes, what it points to stays). Errors are ignored, as for leftovers of a dead run."""
    if path.is_symlink() or (path.exists() and not path.is_dir()):
        with contextlib.suppress(OSError):
            path.unlink()
        return
    shutil.rmtree(path, ignore_errors=True)


def _exchange(a: Path, b: Path) -> bool:
    """Swap two existing paths atomically; False where the OS or filesystem cannot."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except AttributeError:  # glibc < 2.28
        return False
    at_fdcwd, rename_exchange = -100, 2
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p]
    renameat2.argtypes += [ctypes.c_uint]
    done = renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange)
    if done == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False
    raise OSError(code, os.strerror(code), str(b))
