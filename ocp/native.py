"""C source built at run time into shared libraries, cached on disk: one place for the compiler, the cache and the
builds in flight (used by :mod:`ocp.simulate.compiled` and :mod:`ocp.optimize.native_nlp`).

* A library is named by a key its user computes (a hash of what the source does, with the flags and CasADi's
  version) and kept in a sub-folder of the cache directory (``$THRUSTSHAPE_CACHE_DIR``, else
  ``$XDG_CACHE_HOME/thrustshape``, else ``~/.cache/thrustshape``), so another process or a later run loads it at
  once. A sub-folder keeps at most :data:`MAX_LIBRARIES`; the oldest go first.
* A library not on disk is built by the C compiler on the ``PATH`` (``$CC``, ``cc``, ``gcc`` or ``clang``) in a
  background thread (or at once when asked to wait), at the lowest CPU priority (``nice`` 19: it takes what the
  solves leave). The file appears by an atomic rename, so a concurrent reader never sees half of it; a claim file
  beside it keeps other processes from building the same library at once. A failed build is remembered and never
  retried in the process.
* The source is made in the build (by the callable the user passes): it is only paid when the library is missing.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import threading
import time
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


def _build(key: str, source: Callable[[], str], library: Path, flags: tuple[str, ...]) -> None:
    """Compile ``source()`` into ``library`` (atomic rename); a failure is remembered under ``key``."""
    cc = compiler()
    ok = False
    try:
        library.parent.mkdir(parents=True, exist_ok=True)
        _prune(library.parent, MAX_LIBRARIES - 1)
        with tempfile.TemporaryDirectory(dir=library.parent) as tmp:
            c_file = Path(tmp) / f"{key}.c"
            c_file.write_text(source(), encoding="utf-8")
            out = Path(tmp) / library.name
            nice = shutil.which("nice")
            run = subprocess.run([*([nice, "-n", "19"] if nice else []), str(cc), *flags, str(c_file), "-o", str(out),
                                  "-lm"], capture_output=True, timeout=BUILD_TIMEOUT_S, check=False)
            if run.returncode == 0:
                os.replace(out, library)
                ok = True
    except (OSError, subprocess.SubprocessError, RuntimeError):
        ok = False
    _claim(library).unlink(missing_ok=True)
    with _LOCK:
        _THREADS.pop(key, None)
        if not ok:
            _FAILED.add(key)


def _claim(library: Path) -> Path:
    """The file that says a process is building ``library`` (so the other workers wait for it)."""
    return library.with_suffix(".building")


def _claimed_elsewhere(library: Path) -> bool:
    """Whether another process claimed the build of ``library`` less than :data:`BUILD_TIMEOUT_S` ago; else claim
    it (an older claim is a build that died)."""
    claim = _claim(library)
    try:
        library.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(claim, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        try:
            if time.time() - claim.stat().st_mtime < BUILD_TIMEOUT_S:
                return True
        except OSError:
            return True
        claim.touch()
        return False
    except OSError:
        return False
    os.close(fd)
    return False


def library(key: str, sub: str, source: Callable[[], str], flags: tuple[str, ...], wait: bool = False) -> Path | None:
    """The path of the library ``key`` in the sub-folder ``sub`` when it is on disk; else None after starting its
    build from ``source()`` with the compiler ``flags`` in the background (``wait``: build it now, or wait for the
    build in flight), unless another process is building it (then it appears later). None too when its build
    failed in this process."""
    path = cache_dir(sub) / f"{key}.so"
    with _LOCK:
        if key in _FAILED:
            return None
        if path.exists():
            return path
        thread = _THREADS.get(key)
        if thread is None:
            if _claimed_elsewhere(path) and not wait:
                return None
            thread = threading.Thread(target=_build, args=(key, source, path, flags), daemon=True, name=f"cc-{key}")
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
