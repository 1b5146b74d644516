"""The static solver's compiled programs: compiled ahead of time, kept in memory and on disk.

A solve runs a handful of compiled programs (the evaluation of the residual, the tangent, the spring
network, the loads: :func:`jaxnet.solve.statics.solve`). Compiling them is most of a first solve, several
times the Newton iteration itself on FEMNET's cases. JAX's persistent compilation cache keeps the XLA
executables, but a new process still traces and lowers every program before it can look one up, about half
of a second run's time (``benchmarks/femnet_cases.py`` times both). So the programs are kept here as whole
executables instead, keyed by everything that decides them:

* the program (a name) and its static arguments (the active terms and their options, the stiffness path;
  for a term declared outside jaxnet, the digest of its module's source);
* the structure, shapes and dtypes (weak types included) of its arguments;
* the jax and jaxlib versions, the backend and its devices, float64, and the jaxnet sources themselves (a
  digest of every ``.py`` file of the package, so an edited model never runs a stale program).

A program found in memory (this process) is reused as it is; one found on disk is loaded (no tracing); otherwise it is traced, compiled and, when a directory is set, written there by a thread
of its own while the solve goes on (atomically: a run that is stopped leaves no partial file), and not into
JAX's own cache as well. The directory is JAX's compilation cache directory when one
is configured (``jax_compilation_cache_dir``, which ``jaxnet run`` sets; ``--no-cache`` leaves it unset),
subdirectory ``jaxnet-programs``: one switch for both caches. A file that cannot be read or loaded (another
jaxlib, a truncated write) is compiled again and replaced, never trusted.

Programs holding a host callback (the jitted Newton loop's SuperLU) are not kept on disk: an executable
refers to its callbacks by address in the process that compiled it. A program file is a pickle, as JAX's
own cache entries are executables: the directory is trusted as much as the user's own files.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import pathlib
import pickle
import tempfile
import threading
import warnings

import jax
import numpy as np
from jax._src import config as _jax_config
from jax.experimental import serialize_executable


#: subdirectory of JAX's compilation cache directory where the programs are kept
SUBDIRECTORY = "jaxnet-programs"

#: XLA options every jaxnet program is compiled with on the CPU (:func:`compiler_options`). XLA's CPU
#: backend emits each fusion through its MLIR "fusion emitters" by default; its older elemental emitter
#: compiles jaxnet's programs (many small per-element fusions over (E, 3, 3) stacks) markedly faster, and
#: they run as fast: most of a first solve is compilation. And no YNNPACK fusions (an empty list of fusion
#: types): by default XLA hands the dots of the (E, 3, 3) stacks and the elementwise work around them to
#: YNNPACK, which is slower on such small matrices, for the same compile time.
#: ``docs/investigations.md`` (XLA's CPU options) has the solver's programs compiled and run with XLA's
#: defaults and with these, side by side. Options of the CPU backend only: a GPU backend refuses them ("No such compile option").
COMPILER_OPTIONS = {"xla_cpu_use_fusion_emitters": False, "xla_cpu_experimental_ynn_fusion_type": ""}


_ACCEPTED: dict = {}  # (backend, options asked for) -> the options that backend's compiler accepts


def compiler_options(backend=None):
    """The XLA options jaxnet's programs are compiled with for ``backend`` (a JAX platform name; default
    JAX's default backend): those of :data:`COMPILER_OPTIONS` that this JAX's compiler accepts on ``"cpu"``,
    none on the others. XLA refuses an option it does not know ("No such compile option": jax 0.11.2 no
    longer knows ``xla_cpu_use_fusion_emitters``), so they are tried once per process on a one-line program
    (all together, then one by one if refused) and one refused is left out with a warning: a JAX other than
    the pinned one still runs jaxnet, its compilation perhaps slower."""
    backend = backend or jax.default_backend()
    if backend != "cpu":
        return {}
    key = (backend, tuple(sorted(COMPILER_OPTIONS.items())))
    if key not in _ACCEPTED:
        accepted = dict(COMPILER_OPTIONS)
        if not _compiles(accepted, backend):
            accepted = {k: v for k, v in COMPILER_OPTIONS.items() if _compiles({k: v}, backend)}
            refused = sorted(set(COMPILER_OPTIONS) - set(accepted))
            warnings.warn(f"jaxnet: XLA's compiler in jax {jax.__version__} refuses the option(s) {refused}: "
                          f"jaxnet's programs are compiled without them (jaxnet is tested with the jax its "
                          f"pyproject.toml pins)", RuntimeWarning, stacklevel=3)
        _ACCEPTED[key] = accepted
    return dict(_ACCEPTED[key])


def _compiles(options, backend):
    """Whether XLA on ``backend`` compiles a one-line program with ``options``."""
    try:
        # compiled where its argument lies: a device of that backend
        argument = jax.device_put(np.float64(0.0), jax.devices(backend)[0])
        jax.jit(lambda v: v + 1.0, compiler_options=options).lower(argument).compile()
    except Exception as error:  # noqa: BLE001 -- XLA's refusal is a JaxRuntimeError (INVALID_ARGUMENT)
        if "compile option" in str(error):
            return False
        raise
    return True


class _Jit:
    """``jax.jit`` of a function, made at its first use with the options of the backend JAX compiles for
    then (:func:`compiler_options`, a caller's own ``compiler_options`` on top). Made late because the
    package's programs are declared at import, before a user may choose the platform
    (``jax.config.update("jax_platforms", ...)``), and asking JAX for its backend would fix it. Calls and
    attributes (``trace``, ``lower``, ...) are those of the ``jax.jit`` function."""

    def __init__(self, fun, kwargs):
        functools.update_wrapper(self, fun)
        self._fun, self._kwargs, self._jitted = fun, kwargs, None
        self._lock = threading.Lock()

    def _made(self):
        if self._jitted is None:
            with self._lock:
                if self._jitted is None:
                    kwargs = dict(self._kwargs)
                    options = {**compiler_options(), **(kwargs.pop("compiler_options", None) or {})}
                    self._jitted = jax.jit(self._fun, compiler_options=options, **kwargs)
        return self._jitted

    def __call__(self, *args, **kwargs):
        return self._made()(*args, **kwargs)

    def __getattr__(self, name):
        if name.startswith("_"):  # this object's own state, before __init__ has set it (copy, pickle)
            raise AttributeError(name)
        return getattr(self._made(), name)


def jit(fun=None, **kwargs):
    """``jax.jit`` with the package's XLA options for the backend it compiles for (:func:`compiler_options`;
    a caller's own ``compiler_options`` take precedence); usable as a decorator, with or without keywords."""
    if fun is None:
        return functools.partial(jit, **kwargs)
    return _Jit(fun, kwargs)


_MEMORY: dict = {}
_LOCK = threading.Lock()
_THREAD = threading.local()  # per compiling thread: did JAX's persistent cache answer its last compilation?
_LISTENING = []


def _on_jax_event(event, **_):
    if event == "/jax/compilation_cache/cache_hits":  # recorded in the thread that compiles
        _THREAD.jax_cache_hit = True


def _listen_to_jax_cache():
    with _LOCK:
        if not _LISTENING:
            jax.monitoring.register_event_listener(_on_jax_event)
            _LISTENING.append(True)


def sources_digest(root):
    """Digest (hex) of the ``.py`` files under ``root``, their paths and contents."""
    root = pathlib.Path(root)
    digest = hashlib.blake2b(digest_size=16)
    for path in sorted(root.rglob("*.py")):
        digest.update(str(path.relative_to(root)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


@functools.cache
def _package_digest():
    # a program compiled from other sources is another program (read once per process: milliseconds)
    return sources_digest(pathlib.Path(__file__).resolve().parents[1])


def _platform():
    import jaxlib

    devices = jax.devices()
    return (jax.__version__, jaxlib.__version__, devices[0].platform, devices[0].device_kind, len(devices),
            bool(jax.config.jax_enable_x64))


def _leaf_signature(leaf):
    if isinstance(leaf, (bool, int, float, complex)):  # a Python scalar is traced weakly typed
        return type(leaf).__name__
    return tuple(np.shape(leaf)), str(leaf.dtype), bool(getattr(getattr(leaf, "aval", None), "weak_type", False))


def _argument_signature(args):
    leaves, treedef = jax.tree.flatten(args)
    return str(treedef), tuple(_leaf_signature(leaf) for leaf in leaves)


def key(name, static, args):
    """The identity of a program: ``name``, its ``static`` arguments (a repr-stable tuple), its arguments'
    structure and shapes, the platform and the jaxnet sources. A hex digest (a file name)."""
    text = repr((name, static, _argument_signature(args), _platform(), _package_digest()))
    return hashlib.blake2b(text.encode(), digest_size=20).hexdigest()


def directory():
    """Where programs are kept between processes: ``<JAX compilation cache dir>/jaxnet-programs``, or None
    (memory only) when no compilation cache directory is configured."""
    base = jax.config.jax_compilation_cache_dir
    return None if not base else pathlib.Path(base) / SUBDIRECTORY


def _load(path, args):
    try:
        with open(path, "rb") as file:
            payload, out_tree = pickle.load(file)
        # the argument structure is the caller's own (an equinox module's tree does not survive pickling)
        return serialize_executable.deserialize_and_load(payload, jax.tree.structure((args, {})), out_tree)
    except Exception:  # another jaxlib, a truncated or foreign file: compile again, never trust it
        return None


def _store(path, compiled):
    # written to a temporary file then renamed: a stopped run or a concurrent one leaves no partial program
    temporary = None
    try:
        payload, _, out_tree = serialize_executable.serialize(compiled)
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, delete=False, suffix=".tmp") as file:
            temporary = file.name
            pickle.dump((payload, out_tree), file)
        os.replace(temporary, path)
    except Exception:  # a read-only or full disk costs the next process a compilation, not this solve
        if temporary is not None and os.path.exists(temporary):
            os.remove(temporary)


def identity(name, args, static_kwargs=None):
    """:func:`key` of the program ``name`` for positional ``args`` and ``static_kwargs`` (its static
    arguments by keyword, with a stable repr)."""
    static = tuple(sorted((n, _stable(v)) for n, v in (static_kwargs or {}).items()))
    return key(name, static, args)


def _identity(name, args, static_kwargs):
    k = identity(name, args, static_kwargs)
    where = directory()
    return k, None if where is None else where / f"{name}-{k}.jaxexe"


def lookup(name, args, static_kwargs=None):
    """The program ``name`` for positional ``args`` and ``static_kwargs`` (its static arguments by keyword,
    with a stable repr) if this process has it or it is on disk (then loaded, and kept in memory), else
    None. Nothing is traced or compiled."""
    k, path = _identity(name, args, static_kwargs)
    with _LOCK:
        program = _MEMORY.get(k)
    if program is None and path is not None and path.exists():
        program = _load(path, args)
        if program is not None:
            with _LOCK:
                _MEMORY[k] = program
    return program


def _without_jax_cache_writes():
    """A context in which JAX writes nothing to its own persistent cache (this thread only): a program
    jaxnet keeps on disk whole would be kept twice, and JAX's write is on the solve's path. JAX's setting is a thread-local state of its private config module; without it
    (another jax), JAX writes as usual."""
    state = getattr(_jax_config, "persistent_cache_min_compile_time_secs", None)
    return state(float("inf")) if callable(state) else contextlib.nullcontext()


def compile(name, jitted, args, static_kwargs=None, traced=None):  # noqa: A001 (the module's verb)
    """Compile ``jitted`` (a ``jax.jit`` function) for ``args`` and ``static_kwargs``, keep the program in
    memory and, when a directory is set, on disk (written by a thread of its own while the caller goes on),
    and return it: a callable taking ``args`` only (same structure, shapes and dtypes).
    ``traced``: ``jitted.trace(*args, **static_kwargs)`` if the caller has it already (not traced again).
    Thread-safe: the solver compiles its programs in parallel threads."""
    k, path = _identity(name, args, static_kwargs)
    _listen_to_jax_cache()
    _THREAD.jax_cache_hit = False
    if traced is None:
        traced = jitted.trace(*args, **(static_kwargs or {}))
    with _without_jax_cache_writes() if path is not None else contextlib.nullcontext():
        program = traced.lower().compile()
    # an executable JAX took from its own persistent cache serialises without its kernels on CPU: the file
    # would load, then fail at its first call (jax 0.10.2: "Function convert_bitcast_fusion not found").
    # Such a program serves this process only; the next one gets it from JAX's cache again.
    if path is not None and not _THREAD.jax_cache_hit:
        # serialising and writing take a noticeable part of a solve: done beside it,
        # which needs only the program in memory. Not a daemon thread: the interpreter waits for it at exit.
        threading.Thread(target=_store, args=(path, program), name=f"jaxnet-store-{name}").start()
    with _LOCK:
        _MEMORY[k] = program
    return program


def obtain(name, jitted, args, static_kwargs=None):
    """:func:`lookup`, else :func:`compile`."""
    return lookup(name, args, static_kwargs) or compile(name, jitted, args, static_kwargs)


def _stable(value):
    """A repr-stable stand-in for a static argument: the solver's model (active terms) by names and options, and
    for a term declared outside jaxnet (a user's, a test's: its code is not in the package's digest) the digest
    of the module that declares its element function."""
    if isinstance(value, tuple) and value and hasattr(value[0], "term"):
        return tuple((t.name, t.options, _outside_source(t.term.element)) for t in value)
    return value


@functools.cache
def _module_digest(filename):
    try:
        return hashlib.blake2b(pathlib.Path(filename).read_bytes(), digest_size=16).hexdigest()
    except OSError:  # no source file (an interactive session): the program is this process's only
        return f"unreadable {filename} {os.getpid()}"


def _outside_source(function):
    """None for a function of jaxnet's own modules; else the digest of its module's source file."""
    module = getattr(function, "__module__", "") or ""
    if module == "jaxnet" or module.startswith("jaxnet."):
        return None
    code = getattr(function, "__code__", None)
    return _module_digest(code.co_filename) if code is not None else f"{module}.{getattr(function, '__qualname__', '')}"


def clear():
    """Forget the programs of this process (the files on disk stay)."""
    with _LOCK:
        _MEMORY.clear()
