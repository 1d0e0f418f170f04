"""Every file Ramure writes goes through here: temporary file in the same folder, fsync, rename.
Files from others are read through here too (:func:`read_regular`): regular files only, size
checked before reading; SQLite files through :func:`open_sqlite_readonly`, which writes nothing.

A crash, a ``kill -9`` or a full disk at any moment leaves either the previous
file or the new one, complete, and never a partial file: the data goes to a
hidden temporary file next to the target (``.NAME.XXXX.tmp``, same file system
so the rename is atomic), is flushed and fsynced, then ``os.replace`` puts it
in place and the folder is fsynced so the rename itself survives a power cut.
Any failure removes the temporary file and raises :class:`RamureError` with one
line naming the file and the cause ("No space left on device", "Permission
denied", ...): never a traceback, never a half-written file.

Writers that only know how to write to a path (VTK, matplotlib, Qt, PIL) use
:func:`write_with`, which hands them the temporary path.  A writer that would
abort the process on a full disk (VTK's C++ writers do) should serialise to
bytes in memory first and use :func:`write_bytes` (see :func:`save_mesh`).

>>> import tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> write_text(folder / "a.txt", "hello").read_text()
'hello'
>>> sorted(p.name for p in folder.iterdir())  # no temporary file left behind
['a.txt']
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import pathlib
import sqlite3
import stat
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

from ramure.errors import RamureError

if TYPE_CHECKING:
    import pyvista as pv


def _refuse(path: pathlib.Path, exc: OSError) -> RamureError:
    reason = exc.strerror or str(exc)
    return RamureError(f"cannot write {path}: {reason}; the previous file, if any, is unchanged")


def _check_target(path) -> pathlib.Path:
    path = pathlib.Path(path)
    if path.is_dir():
        raise RamureError(f"cannot write {path}: it is a folder")
    if not path.parent.is_dir():
        raise RamureError(f"cannot write {path}: the folder {path.parent} does not exist")
    return path


def _fsync_folder(folder: pathlib.Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return  # some file systems do not open folders: the rename is still atomic
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _commit(tmp: str, path: pathlib.Path) -> None:
    with open(tmp, "rb+") as f:
        os.fsync(f.fileno())
    try:  # keep the previous file's permissions (mkstemp makes 0600)
        os.chmod(tmp, path.stat().st_mode & 0o7777)
    except FileNotFoundError:
        os.chmod(tmp, 0o666 & ~_umask())
    os.replace(tmp, path)
    _fsync_folder(path.parent)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_with(path: str | os.PathLike, writer: Callable[[str], object]) -> pathlib.Path:
    """Call ``writer(tmp_path)``, then fsync and rename the temporary file onto ``path``.

    The temporary file keeps ``path``'s suffix at the end of its name
    (``.NAME.XXXX.tmpSUFFIX``), so a writer that picks its format from the suffix
    (pyvista, matplotlib) writes the right format.
    """
    path = _check_target(path)
    with _replacing(path, suffix=f".tmp{path.suffix}") as tmp:
        writer(tmp)
        if os.path.getsize(tmp) == 0 and not _allow_empty(writer):
            raise RamureError(f"cannot write {path}: the writer produced an empty file")
    return path


@contextlib.contextmanager
def _replacing(path: pathlib.Path, suffix: str = ".tmp") -> Iterator[str]:
    """Yield a temporary path beside ``path``; on success commit it onto ``path``, else discard it."""
    try:
        import tempfile  # here: the readers (the grammar parser's includes) need not import it

        remove_stale_temporaries(path)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.{os.getpid()}.", suffix=suffix)
        os.close(fd)
    except OSError as exc:
        raise _refuse(path, exc) from None
    try:
        yield tmp
        _commit(tmp, path)
    except OSError as exc:
        _discard(tmp)
        raise _refuse(path, exc) from None
    except BaseException:
        _discard(tmp)
        raise


#: A temporary file of ``path`` without its writer's pid (written before the pid was in the
#: name) is stale after this many seconds.
STALE_SECONDS = 24 * 3600


def remove_stale_temporaries(path: str | os.PathLike) -> list[pathlib.Path]:
    """Remove the temporary files a killed writer of ``path`` left beside it; return them.

    A writer's temporary file is ``.NAME.PID.XXXX.tmp...``: one whose process ``PID`` is gone
    (a ``kill -9``, a crash) is stale; a live writer's, another process's running write
    included, is left.  Called before each write of ``path``, so no kill leaves debris for
    long.  Only names of that pattern are touched (and, from before the pid was in the name,
    ``.NAME.XXXX.tmp...`` files a day old).
    """
    path = pathlib.Path(path)
    removed = []
    for tmp in path.parent.glob(f".{glob.escape(path.name)}.*.tmp*"):
        middle = tmp.name[len(path.name) + 2 :].split(".")
        if middle[0].isdigit() and len(middle) >= 3:
            stale = int(middle[0]) != os.getpid() and not _alive(int(middle[0]))
        else:
            stale = _age(tmp) > STALE_SECONDS
        if stale:
            with contextlib.suppress(OSError):
                tmp.unlink()
                removed.append(tmp)
    return removed


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True  # another user's process, or not a pid: not ours to judge
    return True


def _age(path: pathlib.Path) -> float:
    import time

    try:
        return time.time() - path.stat().st_mtime
    except OSError:
        return 0.0


def _allow_empty(writer) -> bool:
    return getattr(writer, "allow_empty", False)


def _discard(tmp: str) -> None:
    with contextlib.suppress(OSError):
        os.unlink(tmp)


def write_bytes(path: str | os.PathLike, data: bytes) -> pathlib.Path:
    """Write ``data`` to ``path`` atomically (see the module docstring)."""
    with open_atomic(path, "wb") as out:
        out.write(data)
    return pathlib.Path(path)


def write_text(path: str | os.PathLike, text: str, encoding: str = "utf-8") -> pathlib.Path:
    """Write ``text`` to ``path`` atomically; line endings are written as given."""
    with open_atomic(path, "w", encoding=encoding, newline="") as out:
        out.write(text)
    return pathlib.Path(path)


@contextlib.contextmanager
def open_atomic(path: str | os.PathLike, mode: str = "w", **kwargs: Any) -> Iterator:
    """``with open_atomic(path, "w") as f:`` — a file object whose content replaces ``path``
    only if the block finishes without an exception."""
    if mode not in ("w", "wb", "wt"):
        raise ValueError(f"open_atomic writes whole files: mode 'w' or 'wb', not {mode!r}")
    path = _check_target(path)
    with _replacing(path) as tmp, open(tmp, mode, **kwargs) as out:
        yield out
        out.flush()


def save_mesh(mesh: pv.DataSet, path: str | os.PathLike) -> pathlib.Path:
    """Save a pyvista mesh (``.vtu``, ``.vtp``, ``.vtk``, ...) atomically.

    XML formats are serialised in memory by VTK and written by Python, so a full
    disk is a clear :class:`RamureError` (VTK's own file output aborts the
    process on a write error); other formats go through :func:`write_with`.
    """
    path = pathlib.Path(path)
    data = _vtk_xml_bytes(mesh, path.suffix.lower())
    if data is None:
        return write_with(path, lambda tmp: mesh.save(tmp))
    return write_bytes(path, data)


def _vtk_xml_bytes(mesh, suffix: str):
    try:
        from vtkmodules.vtkIOXML import (
            vtkXMLPolyDataWriter,
            vtkXMLUnstructuredGridWriter,
            vtkXMLImageDataWriter,
            vtkXMLMultiBlockDataWriter,
        )
    except ImportError:  # pragma: no cover - vtk is a dependency of the 3D features
        return None
    writers = {
        ".vtu": vtkXMLUnstructuredGridWriter,
        ".vtp": vtkXMLPolyDataWriter,
        ".vti": vtkXMLImageDataWriter,
        ".vtm": vtkXMLMultiBlockDataWriter,
    }
    if suffix not in writers or suffix == ".vtm":
        return None
    writer = writers[suffix]()
    writer.SetInputData(mesh)
    writer.SetDataModeToBinary()  # inline base64: the in-memory string is ASCII, not raw bytes
    writer.WriteToOutputStringOn()
    if not writer.Write():
        raise RamureError(f"VTK could not serialise the mesh as {suffix}")
    return writer.GetOutputString().encode("ascii")  # binary mode is base64: plain ASCII


def read_regular(path: str | os.PathLike, limit: int, what: str = "file") -> bytes:
    """The bytes of ``path``, refused unless it is a regular file of at most ``limit`` bytes.

    A device (``/dev/zero``), a named pipe or a folder is refused without reading a byte: the
    file is opened non-blocking (a pipe with no writer would otherwise block for good) and
    checked with ``fstat`` on that very descriptor, so a file swapped in between a check and
    the read cannot slip through.  The size is checked before reading and again while
    reading (a file that grows).  Errors are :class:`RamureError` naming ``what`` and the path.

    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "g.lsys"
    >>> _ = f.write_text("n: 1")
    >>> read_regular(f, 100)
    b'n: 1'
    >>> read_regular("/dev/zero", 100, "grammar")
    Traceback (most recent call last):
    ramure.io.FileRefused: cannot read grammar /dev/zero: it is a device, not a regular file
    """
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    except OSError as exc:
        raise FileRefused(what, path, exc.strerror or type(exc).__name__) from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise FileRefused(what, path, _not_regular(info.st_mode))
        if info.st_size > limit:
            raise FileRefused(what, path, f"{info.st_size:,} bytes, more than the limit of {limit:,}")
        with os.fdopen(os.dup(fd), "rb") as f:
            data = f.read(limit + 1)
    finally:
        os.close(fd)
    if len(data) > limit:
        raise FileRefused(what, path, f"more than the limit of {limit:,} bytes")
    return data


def _not_regular(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return os.strerror(errno.EISDIR)  # "Is a directory", as the system words it
    if stat.S_ISFIFO(mode):
        return "it is a named pipe, not a regular file"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "it is a device, not a regular file"
    return "it is not a regular file"


def read_json(path: str | os.PathLike, limit: int, what: str = "file") -> object:
    """The JSON document in ``path``, read by :func:`read_regular` (regular file, at most
    ``limit`` bytes); text that is not UTF-8, not JSON or nested too deeply is a RamureError
    naming the file and where."""
    import json

    data = read_regular(path, limit, what)
    try:
        return json.loads(data.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise RamureError(f"{path}: not UTF-8 text (byte {exc.start})") from None
    except json.JSONDecodeError as exc:
        raise RamureError(f"{path}: not valid JSON ({exc.msg}, line {exc.lineno})") from None
    except RecursionError:
        raise RamureError(f"{path}: nested too deeply") from None


class FileRefused(RamureError):
    """A file :func:`read_regular` does not read; ``reason`` says why in a few words."""

    def __init__(self, what: str, path: str | os.PathLike, reason: str) -> None:
        self.path, self.reason = path, reason
        super().__init__(f"cannot read {what} {path}: {reason}")


def inside(path: str | os.PathLike, folder: str | os.PathLike) -> bool:
    """Whether ``path``, with every symbolic link and ``..`` resolved, lies in ``folder``.

    >>> inside("/tmp/a/../b.lsys", "/tmp"), inside("/tmp/../etc/passwd", "/tmp")
    (True, False)
    """
    return pathlib.Path(path).resolve().is_relative_to(pathlib.Path(folder).resolve())


#: ``PRAGMA application_id`` of every SQLite file Ramure creates ("RAMU"): studies and qualifier
#: stores.  A file holding another id belongs to another application and is never written.
APPLICATION_ID = 0x52414D55


def open_sqlite_readonly(path: str | os.PathLike) -> sqlite3.Connection:
    """A read-only connection to SQLite file ``path`` that writes nothing, not even beside it.

    SQLite's ``mode=ro`` alone creates ``-wal`` and ``-shm`` files beside a WAL-mode
    file and leaves them there.  When no ``-wal`` file exists no writer has the file
    open in WAL mode, so it is opened ``immutable=1`` (no locks, no side files);
    otherwise ``mode=ro`` reads it alongside the live writer.  The caller closes it, soon: a
    writer arriving later writes its WAL, which an immutable reader does not see, and the
    main file changes only when that WAL is checkpointed (at 1000 pages, or its last close).
    """
    path = pathlib.Path(path)
    live = path.with_name(path.name + "-wal").exists()
    return sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro{'' if live else '&immutable=1'}", uri=True, timeout=10.0)
