"""pkm_pin's compiled code (numba): a notice while it compiles, and whether it is ready.

numba compiles a function the first time it is called with new argument types and
caches the machine code on disk (``cache=True``), so only the first run on a machine
pays for it. A first run must not sit silent: :func:`install_notice` registers a numba
event listener that prints one line on stderr when a compilation of pkm_pin's code has
lasted :data:`NOTICE_AFTER` seconds (what is compiled, and that it happens once), and
the time it took when it ends.

:func:`is_ready` tells whether a compiled function can run now without compiling (it
has run in this process, or numba's cache holds it), which lets a caller take a
plain-Python path for a one-off call rather than compile (see
:func:`pkm_pin.engine.analyse`).

numba's cache of a function is stamped with the file that defines it only, not with
the files of the functions it compiles in: an edit of ``engine/linalg.py`` would leave
``engine/core.py``'s cached machine code running the old algebra. pkm_pin's functions
are therefore cached by locators of their own (:func:`install_stamp`) whose stamp also
holds :func:`package_stamp`, a hash of every module of the package that numba compiles
code from: an edit of any of them recompiles pkm_pin's cached functions on their next
call (with the notice).
"""

from __future__ import annotations

import functools
import hashlib
import os
import sys
import threading
import time
from pathlib import Path

from numba import typeof
from numba.core import event

#: Seconds of compilation after which the notice is printed.
NOTICE_AFTER = 2.0


class _Notice(event.Listener):
    """Prints the notice for compilations of pkm_pin's functions that last."""

    def __init__(self, stream=None):
        self.stream = stream
        self._lock = threading.Lock()
        self._depth = 0
        self._timer = None
        self._started = 0.0
        self._printed = False

    def _print(self, text: str) -> None:
        stream = self.stream or sys.stderr
        print(text, file=stream, flush=True)

    def on_start(self, event_):
        data = event_.data or {}
        dispatcher = data.get("dispatcher")
        name = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
        with self._lock:
            self._depth += 1
            if self._depth > 1 or not name.startswith("pkm_pin"):
                return
            qualname = getattr(dispatcher.py_func, "__qualname__", "?")
            what = f"{name.removeprefix('pkm_pin.')}.{qualname}"
            self._started = time.perf_counter()
            self._printed = False

            def notice():
                with self._lock:
                    self._printed = True
                self._print(f"pkm_pin: compiling {what} to machine code (numba; once per "
                            "installation: later runs load it from numba's cache)...")

            self._timer = threading.Timer(NOTICE_AFTER, notice)
            self._timer.daemon = True
            self._timer.start()

    def on_end(self, event_):
        with self._lock:
            self._depth -= 1
            if self._depth > 0 or self._timer is None:
                return
            self._timer.cancel()
            self._timer = None
            printed = self._printed
        if printed:
            self._print(f"pkm_pin: compiled in {time.perf_counter() - self._started:.1f} s")


_INSTALLED: list = []


def install_notice(stream=None) -> None:
    """Register the compile notice (once per process; ``stream``: default stderr)."""
    if not _INSTALLED:
        listener = _Notice(stream)
        event.register("numba:compile", listener)
        _INSTALLED.append(listener)


def compiled_sources(root: Path) -> list[Path]:
    """The modules under ``root`` that numba compiles code from: those that import numba,
    and ``tolerances.py`` (its constants are written into compiled code)."""
    out = []
    for path in sorted(root.rglob("*.py")):
        text = path.read_bytes()
        if path.name == "tolerances.py" or b"from numba" in text or b"import numba" in text:
            out.append(path)
    return out


def source_stamp(root: Path) -> str:
    """SHA-256 of the names and contents of :func:`compiled_sources` under ``root``."""
    digest = hashlib.sha256()
    for path in compiled_sources(root):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


@functools.cache
def package_stamp() -> str:
    """:func:`source_stamp` of pkm_pin's own modules (computed once per process)."""
    return source_stamp(Path(__file__).resolve().parent)


class _PackageStamped:
    """Mixin of a numba cache locator for pkm_pin's functions: the source stamp is the
    defining file's and :func:`package_stamp`; other functions are left to numba's own
    locators."""

    @classmethod
    def from_function(cls, py_func, py_file):
        if not (getattr(py_func, "__module__", "") or "").startswith("pkm_pin."):
            return None
        return super().from_function(py_func, py_file)

    def get_source_stamp(self):
        return (super().get_source_stamp(), package_stamp())


def install_stamp() -> bool:
    """Put a :class:`_PackageStamped` variant of each of numba's file-backed cache
    locators first in its list, in numba's order (once per process). Returns whether
    they are in place: numba's private caching layout may change, and another version
    keeps its own stamps (then delete ``pkm_pin``'s ``*.nbi``/``*.nbc`` files after an
    edit)."""
    try:
        from numba.core import caching

        impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl  # numba ≥ 0.68
        mixin = caching._SourceFileBackedLocatorMixin
        classes = list(impl._locator_classes)
    except (ImportError, AttributeError):
        return False
    if any(issubclass(c, _PackageStamped) for c in classes):
        return True
    ours = [type(f"PkmPin{c.__name__}", (_PackageStamped, c), {})
            for c in classes if issubclass(c, mixin)]
    impl._locator_classes = ours + classes
    return True


#: Calls a caller may make on a plain-Python path before :func:`prefer_compiled` says
#: to compile anyway (a process that keeps calling will soon profit from it).
PLAIN_CALLS = 8
_plain_calls: dict = {}


def prefer_compiled(dispatcher) -> bool:
    """Whether to call the numba ``dispatcher`` now rather than a plain-Python path:
    when it :func:`is_ready`, or after :data:`PLAIN_CALLS` calls of the process have
    asked (one-off work on a fresh installation does not wait for a compilation;
    repeated work compiles once, with the notice)."""
    if is_ready(dispatcher):
        return True
    key = id(dispatcher)
    _plain_calls[key] = _plain_calls.get(key, 0) + 1
    return _plain_calls[key] > PLAIN_CALLS


def is_ready(dispatcher) -> bool:
    """Whether the numba ``dispatcher`` can run without compiling: it already has
    machine code in this process, or numba's on-disk cache holds an index for it
    (loading it takes a fraction of a second)."""
    if dispatcher.overloads:
        return True
    try:  # numba's cache layout (private): a missing attribute means "not known"
        return os.path.exists(dispatcher._cache._cache_file._index_path)
    except AttributeError:
        return False


class SameTypes:
    """Calls of a numba function from a caller whose arguments keep their types: all but
    one are arrays and numbers the caller makes itself (canonical dtype, layout and
    dimension), and the ``key`` argument (at position ``key``) is an object of a
    mechanism made once and reused for every pose (an engine
    :class:`~pkm_pin.engine.Layout`, a kernel's :class:`~pkm_pin.kernels.Chains`: named
    tuples of a dozen arrays or more).

    numba types every argument of every call (for a named tuple of 20 arrays, ~3 µs:
    more than the analysis of a pose). The first call with a given key object goes
    through the dispatcher (compiling or loading the code if needed); the calls that
    follow with the same object go straight to the machine code of the signature that
    call was typed to. Only the key object's identity is checked, so the caller must
    keep its promise on the other arguments (the machine code converts them as its
    signature says and does not check). With ``plain``, the function runs as plain
    Python until its code is ready (:func:`prefer_compiled`: a one-off call on a fresh
    installation does not wait for a compilation).
    """

    __slots__ = ("dispatcher", "key", "plain", "_known")

    def __init__(self, dispatcher, key: int, plain: bool = False):
        self.dispatcher = dispatcher
        self.key = key
        self.plain = plain
        self._known = (_NOTHING, None)  # (key object, entry point), replaced as one

    def __call__(self, *args):
        obj, entry = self._known
        if args[self.key] is obj:
            return entry(*args)
        if self.plain and not prefer_compiled(self.dispatcher):
            return self.dispatcher.py_func(*args)
        result = self.dispatcher(*args)
        compiled = self.dispatcher.overloads.get(tuple(typeof(a) for a in args))
        if compiled is not None:
            self._known = (args[self.key], compiled.entry_point)
        return result


_NOTHING = object()
