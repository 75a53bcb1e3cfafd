"""C source built at run time into shared libraries, cached on disk: one place for the compiler, the cache and the
builds in flight (used by :mod:`ocp.simulate.compiled` and :mod:`ocp.optimize.native_nlp`).

* A library is named by a key its user computes (a hash of what the source does, with the flags and CasADi's
  version) and kept in a sub-folder of the cache directory (``$THRUSTSHAPE_CACHE_DIR``, else
  ``$XDG_CACHE_HOME/thrustshape``, else ``~/.cache/thrustshape``), so another process or a later run loads it at
  once. A sub-folder keeps at most :data:`MAX_LIBRARIES`; the oldest go first.
* A library not on disk is built by the C compiler on the ``PATH`` (``$CC``, ``cc``, ``gcc`` or ``clang``),
  started from a background thread (or at once when asked to wait), at the lowest CPU priority (``nice`` 19: it
  takes what the solves leave), in a process of its own that holds the sub-folder's lock: one build at a time on
  the machine (a compiler takes 0.3-0.7 GB for a flat program's source), none started twice, and one started by
  a worker that is then stopped still lands its library (or gives up after :data:`BUILD_TIMEOUT_S`). The file
  appears by an atomic rename, so a concurrent reader never sees half of it. A failed build is remembered and
  never retried in the process; one that found the lock taken is tried again by a later call.
* The source is made in the build (by the callable the user passes): it is only paid when the library is missing.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import subprocess
import sys
import tempfile
import threading
from collections.abc import Callable
from functools import cache
from pathlib import Path

import casadi as ca

BUILD_TIMEOUT_S = 600.0
MAX_LIBRARIES = 64  # per sub-folder: the flat program's libraries are ~3 MB each
#: IEEE arithmetic as CasADi's virtual machine does it: no fast-math, no contraction into fused multiply-adds
SAFE_MATH = ("-fPIC", "-shared", "-ffp-contract=off", "-fno-fast-math")

_LOCK = threading.Lock()
_FAILED: set[str] = set()  # keys whose build failed in this process
_THREADS: dict[str, threading.Thread] = {}  # keys being built in the background


@cache
def compiler() -> str | None:
    """Path of the C compiler (``$CC``, else ``cc``, ``gcc``, ``clang``), None when there is none."""
    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        path = shutil.which(name) if name else None
        if path:
            return path
    return None


def enabled(switch: str) -> bool:
    """Whether compiled code may be used: the environment variable ``switch`` is not ``0`` and a C compiler is on
    the PATH."""
    return os.environ.get(switch, "1") != "0" and compiler() is not None


def cache_dir(sub: str) -> Path:
    """The folder of the libraries of one kind (see the module doc)."""
    root = os.environ.get("THRUSTSHAPE_CACHE_DIR")
    if root:
        return Path(root) / sub
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "thrustshape" / sub


def version_tag() -> str:
    """What, besides the source, makes a library: CasADi's version (its generated C and runtime)."""
    return str(ca.CasadiMeta.version())


def _prune(folder: Path, keep: int) -> None:
    """Remove the oldest libraries of ``folder`` beyond ``keep`` (by modification time)."""
    try:
        libs = sorted(folder.glob("*.so"), key=lambda p: p.stat().st_mtime)
        for old in libs[: max(0, len(libs) - keep)]:
            old.unlink(missing_ok=True)
    except OSError:
        pass


#: the build, a process of its own in a session of its own: it holds the sub-folder's lock (one build at a time
#: on the machine), compiles into a temporary folder and renames the library into place, so it ends cleanly even
#: when the worker that started it is gone; exit 75: another build holds the lock (try again later)
_CHILD = r"""
import fcntl, os, shutil, signal, subprocess, sys
tmp, library, lock, timeout, wait = sys.argv[1:6]
with open(lock, "a") as fh:
    try:
        fcntl.flock(fh, fcntl.LOCK_EX | (0 if wait == "1" else fcntl.LOCK_NB))
    except BlockingIOError:
        shutil.rmtree(tmp, ignore_errors=True)
        sys.exit(75)
    try:
        if not os.path.exists(library):
            out = os.path.join(tmp, "out.so")
            try:
                run = subprocess.run(sys.argv[6:] + ["-o", out], timeout=float(timeout), capture_output=True)
            except subprocess.TimeoutExpired:
                shutil.rmtree(tmp, ignore_errors=True)
                os.killpg(0, signal.SIGKILL)
            if run.returncode:
                sys.stderr.buffer.write(run.stderr[-4000:])
                sys.exit(1)
            os.replace(out, library)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
"""
BUSY = 75


def _lock_file(folder: Path) -> Path:
    return folder / "builds.lock"


def _busy(folder: Path) -> bool:
    """Whether a build holds the sub-folder's lock now (checked before a source is made for nothing)."""
    try:
        with open(_lock_file(folder), "a") as fh:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            fcntl.flock(fh, fcntl.LOCK_UN)
    except BlockingIOError:
        return True
    except OSError:
        return False
    return False


def _build(key: str, source: Callable[[], str], library: Path, flags: tuple[str, ...], wait: bool) -> None:
    """Compile ``source()`` into ``library`` in a build process (:data:`_CHILD`); a failure is remembered under
    ``key``, a busy lock is not (a later call tries again)."""
    ok = busy = False
    try:
        folder = library.parent
        folder.mkdir(parents=True, exist_ok=True)
        busy = not wait and _busy(folder)
        if not busy:
            _prune(folder, MAX_LIBRARIES - 1)
            tmp = Path(tempfile.mkdtemp(dir=folder))
            c_file = tmp / f"{key}.c"
            c_file.write_text(source(), encoding="utf-8")
            nice = shutil.which("nice")
            compile_ = [*([nice, "-n", "19"] if nice else []), str(compiler()), *flags, str(c_file), "-lm"]
            run = subprocess.run([sys.executable, "-c", _CHILD, str(tmp), str(library), str(_lock_file(folder)),
                                  str(BUILD_TIMEOUT_S), "1" if wait else "0", *compile_], capture_output=True,
                                 start_new_session=True, check=False)
            busy, ok = run.returncode == BUSY, run.returncode == 0 and library.exists()
    except (OSError, subprocess.SubprocessError, RuntimeError):
        ok = False
    with _LOCK:
        _THREADS.pop(key, None)
        if not ok and not busy:
            _FAILED.add(key)


def library(key: str, sub: str, source: Callable[[], str], flags: tuple[str, ...], wait: bool = False) -> Path | None:
    """The path of the library ``key`` in the sub-folder ``sub`` when it is on disk; else None after starting its
    build from ``source()`` with the compiler ``flags`` in the background (``wait``: build it now, or wait for the
    build in flight). None too when its build failed in this process; a build that found another one running is
    started again by a later call."""
    path = cache_dir(sub) / f"{key}.so"
    with _LOCK:
        if key in _FAILED:
            return None
        if path.exists():
            return path
        thread = _THREADS.get(key)
        if thread is None:
            thread = threading.Thread(target=_build, args=(key, source, path, flags, wait), daemon=True,
                                      name=f"cc-{key}")
            _THREADS[key] = thread
            thread.start()
    if wait:
        thread.join()
        return path if path.exists() else None
    return None


def mark_failed(key: str) -> None:
    """Never build or load the library ``key`` again in this process."""
    with _LOCK:
        _FAILED.add(key)
