"""The NMPC's nonlinear program compiled to C once per machine, cached, and loaded by every run.

CasADi evaluates the NLP's functions (objective, constraints, their gradient, Jacobian and
the Hessian of the Lagrangian) in its virtual machine unless they are compiled.  Here they
are generated to C (``CodeGenerator``), compiled into a shared library with the machine's C
compiler and handed to ``nlpsol`` as that library (same iterates, same solution).

What is compiled is the *compact* form of the NLP (``NMPCProblem.compact_nlp``): one
control interval's function (model step, stage cost, clearances) mapped over the horizon,
so that the C holds one interval's code and its derivatives, called in a loop.  The fully
inlined form that CasADi interprets fastest was tried first: its library (10 MB of C, 4 MB
of straight-line machine code for N_c = 15) was faster than the interpreter only while hot
in the cache, and slower in closed loop, where every control step starts cold.  The compact
library is about a tenth of that (1.6 MB of C, under 1 MB of code); figures in
``docs/nmpc-performance.md``.  Compiling (-O3 for this processor) still takes some 15 s
of processor time, so it is done once and kept:

* **Where.** ``$RHNC_NMPC_CACHE`` if set, else ``$XDG_CACHE_HOME/rhnc-cosim/nmpc``, else
  ``~/.cache/rhnc-cosim/nmpc``.  One ``nlp_<solver>_<key>.so`` per problem; delete the
  folder to clear the cache.
* **Key.** SHA-256 of the NLP's serialized expression graph (``Function.serialize``: the
  dynamics, horizon, weights, scaling, slots, so everything the generated C is made
  from), the NLP solver plugin, the CasADi version, the compiler (path and
  ``--version``) and its flags (with ``-march=native``, also the processor's model and
  feature flags: such a library runs only on processors like the one that built it).
  The same problem in another run, a batch worker or the watchdog's forked solver
  process finds the same file; a changed weight or horizon gets a file of its own.  The key is taken from the expression graph rather than from the
  generated C because generating the C costs seconds on every start, and serializing the
  graph a few ms; the C is a function of the graph and the CasADi version.
* **Concurrency.** The build holds an exclusive lock (``<name>.lock``, ``fcntl``) so that
  two processes starting together compile once; the library is written under a temporary
  name and renamed into place, so a reader never sees half a file.
* **Fallback.** Without a C compiler (``$CC`` if set, else ``cc``, ``gcc`` or ``clang`` on
  the ``PATH``), when the compiler fails, or with ``RHNC_NMPC_CODEGEN=0``, the interpreted
  functions remain (the same solutions, slower) and a warning says so; the run's summary
  reports ``codegen: interpreted`` and why.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import logging
import os
import platform
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import casadi as ca

LOG = logging.getLogger(__name__)

#: environment variable naming the cache directory
CACHE_ENV = "RHNC_NMPC_CACHE"
#: environment variable that turns code generation off (``0``, ``off``, ``false``, ``no``)
CODEGEN_ENV = "RHNC_NMPC_CODEGEN"
#: compiler flags.  -O3 with the machine's own instruction set (``NATIVE_FLAGS``, when the
#: compiler takes them) made the Hessian of the Lagrangian 19 % and the constraint Jacobian
#: 17 % faster than -O1 and a closed-loop step (one target, fatrop) 0.3 ms (15 %) cheaper;
#: -O2 or -O3 alone were no faster than -O1 (docs/nmpc-performance.md).  The compact NLP
#: then compiles in about 15 s instead of 8 s, once per machine.
COMPILER_FLAGS = ("-O3", "-fPIC", "-shared")
#: the instruction set of the machine that compiles (vector and fused multiply-add
#: instructions); the library then runs only on processors like it, so the processor's
#: identity is part of the cache key (a cache folder shared by different machines keeps
#: one library per processor type)
NATIVE_FLAGS = ("-march=native",)
#: bump when the way libraries are made changes, so that old files are not reused
RECIPE_VERSION = "2"
_OFF = {"0", "off", "false", "no"}


def cache_dir() -> Path:
    """Directory of the compiled NLP libraries (see the module docstring)."""
    override = os.environ.get(CACHE_ENV)
    if override:
        return Path(override).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "rhnc-cosim" / "nmpc"


def find_compiler() -> str | None:
    """The C compiler to use: ``$CC`` when set (None if it does not exist), else cc, gcc or clang."""
    named = os.environ.get("CC")
    if named:
        return shutil.which(named)
    for candidate in ("cc", "gcc", "clang"):
        found = shutil.which(candidate)
        if found:
            return found
    return None


def codegen_disabled_by_environment() -> bool:
    """True when ``RHNC_NMPC_CODEGEN`` turns code generation off."""
    return os.environ.get(CODEGEN_ENV, "").strip().lower() in _OFF


@functools.lru_cache(maxsize=8)
def compiler_flags(compiler: str) -> tuple[str, ...]:
    """``COMPILER_FLAGS`` plus ``NATIVE_FLAGS`` when ``compiler`` accepts them (checked once)."""
    try:
        probe = subprocess.run([compiler, *NATIVE_FLAGS, "-x", "c", "-fsyntax-only", "-"], input="int f(void);\n",
                               capture_output=True, text=True, timeout=30, check=False)
        native = probe.returncode == 0
    except (OSError, subprocess.SubprocessError):
        native = False
    return (*COMPILER_FLAGS, *NATIVE_FLAGS) if native else COMPILER_FLAGS


def processor_identity() -> str:
    """What the native instruction set depends on: the processor's model and feature flags."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as stream:
            first = stream.read().split("\n\n", 1)[0]
    except OSError:
        return f"{platform.machine()}|{platform.processor()}"
    wanted = ("model name", "flags", "features", "cpu model", "isa")
    return "|".join(line.split(":", 1)[1].strip() for line in first.splitlines()
                    if ":" in line and line.split(":", 1)[0].strip().lower() in wanted)


def _compiler_identity(compiler: str) -> str:
    try:
        result = subprocess.run([compiler, "--version"], capture_output=True, text=True, timeout=30, check=False)
        first = result.stdout.splitlines()[0] if result.stdout else ""
    except (OSError, subprocess.SubprocessError):
        first = ""
    return f"{compiler}|{first}"


def library_key(nlp: dict, plugin: str, compiler: str, options: dict | None = None) -> str:
    """Content hash of what the compiled library is made from (see the module docstring):
    the solver's options too, since they decide which derivatives are generated (a
    limited-memory Hessian needs no ``nlp_hess_l``; a library built without it must not
    serve a solver asking for the exact Hessian)."""
    oracle = ca.Function("nlp", [nlp["x"], nlp["p"]], [nlp["f"], nlp["g"]], ["x", "p"], ["f", "g"])
    digest = hashlib.sha256()
    settings = json.dumps(options or {}, sort_keys=True, default=repr)
    flags = compiler_flags(compiler)
    machine = processor_identity() if set(NATIVE_FLAGS) <= set(flags) else ""
    for part in (RECIPE_VERSION, ca.__version__, plugin, _compiler_identity(compiler), " ".join(flags), machine,
                 settings):
        digest.update(part.encode())
        digest.update(b"\0")
    digest.update(oracle.serialize().encode())
    return digest.hexdigest()


@contextlib.contextmanager
def _exclusive(lock_path: Path):
    """Hold an exclusive lock on ``lock_path`` (no-op where ``fcntl`` is missing)."""
    try:
        import fcntl
    except ImportError:  # Windows: the atomic rename still keeps readers safe
        yield
        return
    with open(lock_path, "a+") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


class NLPLibrary:
    """The NLP for ``nlpsol``: a compiled, cached library when possible, else the expressions.

    Parameters
    ----------
    nlp : dict
        CasADi NLP (``x``, ``f``, ``g``, ``p``) of SX expressions: what is interpreted.
    plugin : str
        NLP solver plugin (``"fatrop"``, ``"ipopt"``, ...): its derivative functions are
        generated.
    options : dict
        ``nlpsol`` options of the solvers made from this library (``expand`` is dropped
        when the library is compiled: its functions are already numeric code).
    enabled : bool
        False: use the interpreted functions without trying to compile.
    compact_nlp : dict, optional
        The same NLP in the form to compile (an MX graph mapping one interval's function,
        see the module docstring); default ``nlp``.

    Attributes
    ----------
    mode : str
        ``"compiled"`` or ``"interpreted"``.
    path : pathlib.Path or None
        The shared library used (compiled mode).
    build_time_s : float or None
        Time spent generating and compiling [s] when this process built the library; None
        when it was loaded from the cache (or not compiled).
    reason : str
        Why the functions are interpreted ("" when compiled).
    """

    #: libraries compiled by this process (the tests count them)
    builds = 0

    def __init__(self, nlp: dict, plugin: str, options: dict, enabled: bool = True,
                 compact_nlp: dict | None = None) -> None:
        self.nlp = nlp
        self.compact_nlp = nlp if compact_nlp is None else compact_nlp
        self.plugin = plugin
        self.options = dict(options)
        self.mode = "interpreted"
        self.path: Path | None = None
        self.build_time_s: float | None = None
        self.reason = ""
        if not enabled:
            self.reason = "code generation off in the settings"
        elif codegen_disabled_by_environment():
            self.reason = f"code generation off by {CODEGEN_ENV}"
        else:
            compiler = find_compiler()
            if compiler is None:
                self.reason = "no C compiler found" + (f" ($CC = {os.environ['CC']})" if os.environ.get("CC") else "")
            else:
                self._prepare(compiler)
        if self.mode == "interpreted" and enabled and not codegen_disabled_by_environment():
            LOG.warning("NMPC: %s; the NLP's functions stay interpreted (slower solves)", self.reason)

    def _prepare(self, compiler: str) -> None:
        directory = cache_dir()
        try:
            directory.mkdir(parents=True, exist_ok=True)
            key = library_key(self.compact_nlp, self.plugin, compiler, self.options)
            path = directory / f"nlp_{self.plugin}_{key[:24]}.so"
            if not path.is_file():
                with _exclusive(directory / f"{path.stem}.lock"):
                    if not path.is_file():  # another process may have built it meanwhile
                        self.build_time_s = self._build(compiler, path)
            self._load_check(path)
        except (OSError, RuntimeError, subprocess.CalledProcessError) as error:
            self.reason = f"compiling the NLP failed ({_one_line(error)})"
            self.build_time_s = None
            return
        self.mode, self.path = "compiled", path

    def _build(self, compiler: str, path: Path) -> float:
        """Generate the C of the NLP's functions and compile it to ``path`` (atomically)."""
        start = time.perf_counter()
        LOG.info("NMPC: compiling the NLP for %s into %s (once per machine; under a minute)", self.plugin, path)
        # not expanded: expanding would inline the mapped interval function again
        options = {**self.options, "expand": False}
        symbolic = ca.nlpsol("rhnc_codegen", self.plugin, self.compact_nlp, options)
        with tempfile.TemporaryDirectory(prefix="rhnc-nlp-") as work:
            generator = ca.CodeGenerator(path.stem, {})
            generator.add(symbolic.oracle())
            for name in symbolic.get_function():
                generator.add(symbolic.get_function(name))
            source = generator.generate(work + os.sep)
            partial = path.with_name(f".{path.stem}.{os.getpid()}.tmp.so")
            try:
                subprocess.run([compiler, *compiler_flags(compiler), "-o", str(partial), source], check=True,
                               capture_output=True, text=True)
                os.replace(partial, path)
            finally:
                with contextlib.suppress(FileNotFoundError):
                    partial.unlink()
        NLPLibrary.builds += 1
        elapsed = time.perf_counter() - start
        LOG.info("NMPC: compiled %s in %.1f s", path.name, elapsed)
        return elapsed

    def _load_check(self, path: Path) -> None:
        """Load the library once so that a broken file fails here, not at the first solve."""
        self._compiled_solver("rhnc_codegen_check", path)

    def _compiled_solver(self, name: str, path: Path, options: dict | None = None) -> ca.Function:
        options = {key: value for key, value in (options or self.options).items() if key != "expand"}
        return ca.nlpsol(name, self.plugin, str(path), options)

    def solver(self, name: str, options: dict | None = None) -> ca.Function:
        """A fresh ``nlpsol`` on this NLP (compiled library or expressions).

        ``options`` replaces the library's ``nlpsol`` options for this solver (e.g. another
        iteration limit); the compiled functions do not depend on them.
        """
        if self.path is not None:
            return self._compiled_solver(name, self.path, options)
        return ca.nlpsol(name, self.plugin, self.nlp, options or self.options)

    def summary(self) -> dict:
        """``codegen`` (compiled|interpreted), the library's path, build time if built now, reason."""
        return {
            "codegen": self.mode,
            "codegen_library": str(self.path) if self.path is not None else None,
            "codegen_build_s": self.build_time_s,
            "codegen_note": self.reason or None,
        }


def _one_line(error: BaseException) -> str:
    if isinstance(error, subprocess.CalledProcessError):
        text = (error.stderr or "").strip().splitlines()
        return f"compiler exit {error.returncode}: {text[0] if text else ''}"
    return str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
