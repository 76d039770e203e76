"""One place that fixes the numba options of every compiled kernel, and where they are cached.

``nogil=True`` lets the threaded runner call kernels concurrently, ``error_model="numpy"``
drops the per-division Python exception checks (a division by zero gives inf/nan, which the
kernels flag).  No blanket ``fastmath``: it would delete the NaN and infinity checks that flag
unstable simulations.

Compiled machine code is cached on disk in a user cache directory shared by every checkout and
installation of the same source: ``$POUND_MC_CACHE_DIR``, else ``$XDG_CACHE_HOME/pound-mc``,
else ``~/.cache/pound-mc``; numba's own ``NUMBA_CACHE_DIR``, when set and no
``$POUND_MC_CACHE_DIR`` is, moves it to ``$NUMBA_CACHE_DIR/pound-mc`` (numba's own keys there,
each function's own file, would keep a kernel whose inlined helpers changed in another file).
Entries are keyed by a hash of the package's compiled sources, so a fresh clone, a reinstall or
a new Dask worker of the same version finds the kernels already compiled, while any edit of a
kernel source compiles afresh.  Where that directory cannot be written, numba's default (a
``__pycache__`` beside the source) is used.  The helpers' versions that only compiled code
calls (no Python wrapper, :class:`_Dispatcher`) are kept under ``calls/`` in the user cache
directory; where numba's own place is used instead, they are not cached (their file names
would clash there), which costs nothing once the kernels that call them are cached.

What survives: a fresh clone, a reinstall (editable or not) and a new Dask worker of the same
source on the same machine, or with the same cache directory mounted, find the kernels
compiled; so does a different Python environment with the same numba version.  Any edit of a
module that imports this one (by ``from pound_mc._jit import``) compiles every kernel again,
as does another numba version or CPU.  ``pound-mc compile [--methods ...] [--laws ...]``
fills the cache ahead of a run (cluster images, Dask workers); a study run compiles what it
needs in one warm-up simulation before its progress bar starts
(:mod:`pound_mc.study.warmup`).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
from pathlib import Path

try:
    import fcntl
except ImportError:  # Windows: numba's own, unlocked index update
    fcntl = None

#: numba's optimisation level for every kernel: 2 (LLVM's -O2), unless ``NUMBA_OPT`` is set.
#: Measured in one session on 2 cores (a fresh cache each, idle machine): the cold warm-up of
#: ``studies/shear_spectrum.toml`` 31.7 s at -O3 against 28.8 s, ``inelastic_spectrum`` 33.2
#: against 21.6 s, ``yielding_shear`` about 31 against 28.8 s; the general kernels run as fast,
#: the SDOF pair 2.8 % slower (the benchmark study, one thread, alternated processes) and B1
#: 0.5 % (``docs/performance.md``).  numba reads it when it next compiles
#: (``config.reload_config``), so it holds though ``numba`` was imported first; it is the
#: process's setting, so other numba code compiled in the same process gets it too.
os.environ.setdefault("NUMBA_OPT", "2")

from numba.core import caching, config, sigutils, types
from numba.core.compiler_lock import global_compiler_lock
from numba.core.registry import CPUDispatcher

#: ``no_cfunc_wrapper``: no kernel is passed to compiled code as a first-class function.
#: ``forceinline`` is set either way: numba would otherwise pass a caller's own on to the
#: helpers first compiled for it (see :func:`jit`, ``llvm_inline``).
_OPTIONS = {"nogil": True, "error_model": "numpy", "no_cfunc_wrapper": True, "forceinline": False}

_PACKAGE = Path(__file__).resolve().parent


def cache_root() -> Path:
    """Directory of the shared kernel cache (see the module docstring)."""
    explicit = os.environ.get("POUND_MC_CACHE_DIR")
    if explicit:
        return Path(explicit)
    if config.CACHE_DIR:  # the user gave numba a place: ours is in it, keyed our way
        return Path(config.CACHE_DIR) / "pound-mc"
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "pound-mc"


@functools.lru_cache(maxsize=1)
def source_key() -> str:
    """Hash of every package source that defines compiled functions (16 hex digits).

    A kernel inlines helpers from other modules, so one hash over all of them keys the cache:
    an edit anywhere in the compiled code invalidates every entry, never a stale mix.
    """
    digest = hashlib.sha256()
    for path in sorted(_PACKAGE.rglob("*.py")):
        text = path.read_bytes()
        if b"pound_mc._jit import" in text or path.name == "_jit.py":
            digest.update(str(path.relative_to(_PACKAGE)).encode())
            digest.update(text)
    return digest.hexdigest()[:16]


class _SharedCacheLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
    """Cache files under ``cache_root()/numba/<source key>/<module folder>``."""

    #: Folders between the source key and the module folder.
    _folders: tuple[str, ...] = ()

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        relative = Path(py_file).resolve().parent.relative_to(_PACKAGE)
        self._cache_path = str(
            cache_root().joinpath("numba", source_key(), *self._folders, relative)
        )

    def get_cache_path(self):
        return self._cache_path

    def get_source_stamp(self):
        return source_key()

    @classmethod
    def from_function(cls, py_func, py_file):
        try:
            Path(py_file).resolve().relative_to(_PACKAGE)
        except ValueError:
            return None
        return super().from_function(py_func, py_file)


class _CallsCacheLocator(_SharedCacheLocator):
    """The compiled callers' versions (:class:`_Dispatcher`) under ``<source key>/calls``."""

    _folders = ("calls",)


class _SharedCacheImpl(caching.CompileResultCacheImpl):
    _locator_classes = [_SharedCacheLocator, *caching.CompileResultCacheImpl._locator_classes]


class _CallsCacheImpl(caching.CompileResultCacheImpl):
    _locator_classes = [_CallsCacheLocator]  # never numba's places: their file names clash


class _SharedFunctionCache(caching.FunctionCache):
    """numba's function cache under a lock while an entry is saved.

    numba writes each file atomically, but adds a signature to a function's index by reading
    the index, choosing a free data file name and writing both back: two processes saving two
    signatures of one function at once (parallel test workers, Dask workers) could both take
    the same name, and the index could then point one signature at the other's machine code.
    An advisory lock on ``<index>.lock`` serialises the saves; loading takes no lock.
    """

    _impl_class = _SharedCacheImpl

    def save_overload(self, sig, data):
        """Save the compiled ``data`` of ``sig`` with the function's index locked."""
        with self._index_lock():
            super().save_overload(sig, data)

    @contextlib.contextmanager
    def _index_lock(self):
        if fcntl is None or not self._enabled:
            yield
            return
        try:
            self._impl.locator.ensure_cache_path()
            handle = open(self._cache_file._index_path + ".lock", "ab")
        except OSError:  # an unwritable cache: numba's save reports or skips it
            yield
            return
        with handle:
            fcntl.flock(handle, fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(handle, fcntl.LOCK_UN)


class _CallsFunctionCache(_SharedFunctionCache):
    _impl_class = _CallsCacheImpl


def _enable_cache(dispatcher, func):
    if not hasattr(dispatcher, "enable_caching"):  # NUMBA_DISABLE_JIT: a plain function
        return dispatcher
    try:
        dispatcher._cache = _SharedFunctionCache(func)
    except Exception:  # noqa: BLE001  (numba's own cache beside the source instead)
        dispatcher.enable_caching()
    if dispatcher._called is not None:
        with contextlib.suppress(Exception):  # no place of its own: compiled in every process
            dispatcher._called._cache = _CallsFunctionCache(func)
    return dispatcher


class _Dispatcher(CPUDispatcher):
    """numba's CPU dispatcher, compiling the calls from compiled code for plain types only.

    A constant argument (the ``0`` of a variable's first value, a ``which`` flag) is a literal
    type of its own: without this, a kernel compiled most of its helpers twice (the
    contact-law family for the literal ``phase = 0`` and again for ``int64``).  The arithmetic
    is the same (LLVM propagates the constants after linking), so results are bitwise
    unchanged.

    A helper (``jit`` without ``entry``) has a twin, ``_called``, that the calls from compiled
    code type as: it compiles without the Python wrapper, which a helper never needs (building
    the wrappers took about a third of a first run's compile), and takes over a version
    already compiled for Python.  Its cache entries live apart (:class:`_CallsCacheLocator`).
    """

    _called = None

    def get_call_template(self, args, kws):
        """The call template of numba's dispatcher, for the arguments' non-literal types."""
        args = tuple(types.unliteral(a) for a in args)
        kws = {k: types.unliteral(a) for k, a in kws.items()}
        return super().get_call_template(args, kws)

    @property
    def _numba_type_(self):
        return types.Dispatcher(self if self._called is None else self._called)


class _CalledDispatcher(_Dispatcher):
    """The twin of a helper's dispatcher that compiled callers call (no Python wrapper)."""

    def __init__(self, python, options):
        super().__init__(python.py_func, python.locals, options)
        self._python = python

    def compile(self, sig):
        """Compile ``sig``, or take over the Python side's version of it."""
        with global_compiler_lock:
            args = tuple(sigutils.normalize_signature(sig)[0])
            shared = self._python.overloads.get(args)
            if shared is not None and args not in self.overloads:
                self.add_overload(shared)
            return super().compile(sig)


def jit(
    func=None,
    *,
    parallel: bool = False,
    inline: bool = False,
    entry: bool = False,
    llvm_inline: bool = False,
):
    """Compile ``func`` with the project's numba options (usable with or without arguments).

    ``inline=True`` or ``llvm_inline=True``: numba's ``forceinline``, the compiled helper
    marked ``alwaysinline`` for LLVM, which inlines it into every caller once linked; it still
    works when called from Python.  ``entry=True``: a kernel that Python calls as well as
    compiled code (one version, with its Python wrapper, for both; see :class:`_Dispatcher`).

    Why LLVM's inlining and not numba's own (IR-level, which copies the helper's typed IR into
    each caller): the IR's size sets the cold compile time.  Measured in one session (2 cores,
    load 1-3, a fresh cache each): the general ``adaptive`` kernel of
    ``studies/shear_spectrum.toml`` compiled in 56 s with its helpers IR-inlined, 29 s with
    them called and 32 s inlined by LLVM; ``adaptive_rk`` (``studies/yielding_shear.toml``)
    43, 32 and 35 s.  Called, the general kernels ran 1.1-1.9 times slower; inlined by LLVM
    they run as fast as IR-inlined or faster (shear 0.12-0.13 against 0.17-0.23 s for 40
    simulations, yielding 0.78-0.81 against 0.78-0.79 s, the benchmark study's SDOF pairs
    0.09-0.10 s for 1,000 either way, interleaved runs).  Inlining leaves the arithmetic as it
    is (no fast-math: nothing is reassociated), so results are bitwise the same.  Numba would
    pass the flag on to the helpers first compiled for such a helper; :data:`_OPTIONS` sets it
    for every function, so only the marked ones are inlined, whichever caller compiles them
    first.
    """
    options = dict(_OPTIONS)
    if parallel:
        options["parallel"] = True
    if inline or llvm_inline:
        options["forceinline"] = True

    def decorate(f):
        if config.DISABLE_JIT:
            return f
        dispatcher = _Dispatcher(f, {}, options)
        if not entry:
            options_called = {**options, "no_cpython_wrapper": True}
            dispatcher._called = _CalledDispatcher(dispatcher, options_called)
        return _enable_cache(dispatcher, f)

    if func is None:
        return decorate
    return decorate(func)
