"""Where the compiled NLP libraries go, which compiler makes them, what keys them, and what a
run is told when it cannot have one: on a one-variable NLP that compiles in about a second."""

import logging
import subprocess
import sys
import time
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from rhnc.control import nmpc_codegen
from rhnc.control.nmpc_codegen import (CACHE_ENV, CODEGEN_ENV, COMPILER_FLAGS, NATIVE_FLAGS, NLPLibrary, _compiler_identity,
                               _one_line, cache_dir, codegen_disabled_by_environment, compiler_flags, find_compiler,
                               library_key)

OPTIONS = {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes"}, "expand": True}


def tiny_nlp(weight: float = 1.0) -> dict:
    """min weight (x - p)^2 subject to -10 <= x <= 10 (the bounds given at the solve)."""
    x, p = ca.SX.sym("x"), ca.SX.sym("p")
    return {"x": x, "p": p, "f": weight * (x - p) ** 2, "g": x}


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))
    monkeypatch.delenv(CODEGEN_ENV, raising=False)
    monkeypatch.delenv("CC", raising=False)
    return tmp_path / "cache"


def script(folder: Path, name: str, body: str) -> Path:
    path = folder / name
    path.write_text("#!/bin/sh\n" + body)
    path.chmod(0o755)
    return path


def solve(solver) -> float:
    return float(solver(x0=0.0, p=3.0, lbg=-10.0, ubg=10.0)["x"])


# -- the cache folder, the compiler, the switch --------------------------------------------------
def test_the_cache_folder_is_the_variable_else_the_xdg_cache_else_the_home_cache(monkeypatch, tmp_path):
    monkeypatch.setenv(CACHE_ENV, "~/nlp-cache")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cache_dir() == tmp_path / "home" / "nlp-cache"
    monkeypatch.delenv(CACHE_ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "xdg" / "rhnc-cosim" / "nmpc"
    monkeypatch.setenv("XDG_CACHE_HOME", "")
    assert cache_dir() == tmp_path / "home" / ".cache" / "rhnc-cosim" / "nmpc"


def test_the_compiler_is_cc_when_set_else_the_first_of_cc_gcc_clang(monkeypatch, tmp_path):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    monkeypatch.setenv("PATH", str(bin_dir))
    monkeypatch.delenv("CC", raising=False)
    assert find_compiler() is None
    clang = script(bin_dir, "clang", "exit 0\n")
    assert find_compiler() == str(clang)
    gcc = script(bin_dir, "gcc", "exit 0\n")
    assert find_compiler() == str(gcc)
    cc = script(bin_dir, "cc", "exit 0\n")
    assert find_compiler() == str(cc)
    monkeypatch.setenv("CC", "clang")
    assert find_compiler() == str(clang)
    monkeypatch.setenv("CC", "tcc")
    assert find_compiler() is None


@pytest.mark.parametrize("value, off", [("0", True), (" Off ", True), ("FALSE", True), ("no", True), ("1", False),
                                        ("", False), ("yes", False)])
def test_the_environment_switches_code_generation_off(monkeypatch, value, off):
    monkeypatch.setenv(CODEGEN_ENV, value)
    assert codegen_disabled_by_environment() is off


def test_unset_the_environment_leaves_code_generation_on(monkeypatch):
    monkeypatch.delenv(CODEGEN_ENV, raising=False)
    assert codegen_disabled_by_environment() is False


# -- what keys a library ---------------------------------------------------------------------------
def test_a_compiler_is_identified_by_its_path_and_first_version_line(tmp_path):
    compiler = script(tmp_path, "cc", '[ "$1" = "--version" ] && echo "cc 1.2.3" && echo "second line"\n')
    assert _compiler_identity(str(compiler)) == f"{compiler}|cc 1.2.3"
    complaining = script(tmp_path, "complaining-cc", "echo 'cc 4.5'\nexit 1\n")  # a version, and a failure
    assert _compiler_identity(str(complaining)) == f"{complaining}|cc 4.5"
    silent = script(tmp_path, "silent-cc", "exit 0\n")
    assert _compiler_identity(str(silent)) == f"{silent}|"
    assert _compiler_identity(str(tmp_path / "missing")) == f"{tmp_path / 'missing'}|"


def test_a_compiler_hanging_on_its_version_is_given_up_on(monkeypatch):
    def hangs(command, **options):
        assert options.get("timeout") is not None, "no time limit: a hanging compiler hangs the run"
        raise subprocess.TimeoutExpired(command, options["timeout"])

    monkeypatch.setattr(subprocess, "run", hangs)
    assert _compiler_identity("/usr/bin/cc") == "/usr/bin/cc|"


def test_the_key_follows_the_problem_the_solver_and_the_compiler(tmp_path):
    one = script(tmp_path, "cc-1", "echo 'cc 1'\n")
    two = script(tmp_path, "cc-2", "echo 'cc 2'\n")
    key = library_key(tiny_nlp(), "ipopt", str(one))
    assert len(key) == 64 and key == library_key(tiny_nlp(), "ipopt", str(one))
    assert library_key(tiny_nlp(2.0), "ipopt", str(one)) != key
    assert library_key(tiny_nlp(), "fatrop", str(one)) != key
    assert library_key(tiny_nlp(), "ipopt", str(two)) != key
    # the solver's options decide which derivatives are compiled: they are part of the key
    assert library_key(tiny_nlp(), "ipopt", str(one), {"ipopt.hessian_approximation": "limited-memory"}) != key
    assert library_key(tiny_nlp(), "ipopt", str(one), {}) == key
    # the same options in another order, or with numpy numbers, give one key
    assert (library_key(tiny_nlp(), "ipopt", str(one), {"a": 1, "b": {"c": "d"}})
            == library_key(tiny_nlp(), "ipopt", str(one), {"b": {"c": "d"}, "a": 1}))
    assert library_key(tiny_nlp(), "ipopt", str(one), {"ipopt.max_iter": np.int64(200)}) != key


def test_the_native_instruction_set_is_used_only_where_the_compiler_takes_it(tmp_path):
    takes = script(tmp_path, "cc-native", "exit 0\n")
    refuses = script(tmp_path, "cc-portable", 'for a in "$@"; do [ "$a" = "-march=native" ] && exit 1; done\nexit 0\n')
    assert compiler_flags(str(takes)) == (*COMPILER_FLAGS, *NATIVE_FLAGS)
    assert compiler_flags(str(refuses)) == COMPILER_FLAGS
    assert compiler_flags(str(tmp_path / "missing")) == COMPILER_FLAGS


def test_a_compiler_hanging_on_the_native_probe_gets_the_portable_flags(monkeypatch):
    def hangs(command, **options):
        assert options.get("timeout") is not None, "no time limit: a hanging compiler hangs the run"
        raise subprocess.TimeoutExpired(command, options["timeout"])

    monkeypatch.setattr(subprocess, "run", hangs)
    assert compiler_flags("/hanging/cc") == COMPILER_FLAGS


def test_a_library_for_the_native_instruction_set_is_keyed_by_the_processor(tmp_path, monkeypatch):
    native = script(tmp_path, "cc-native", "echo 'cc 1'\n")
    portable = script(tmp_path, "cc-portable", 'for a in "$@"; do [ "$a" = "-march=native" ] && exit 1; done\n'
                                               "echo 'cc 1'\n")
    keys = {}
    for processor in ("model A|avx2 fma", "model B|sse2"):
        monkeypatch.setattr(nmpc_codegen, "processor_identity", lambda processor=processor: processor)
        keys[processor] = (library_key(tiny_nlp(), "fatrop", str(native)),
                           library_key(tiny_nlp(), "fatrop", str(portable)))
    (native_a, portable_a), (native_b, portable_b) = keys.values()
    assert native_a != native_b, "a library built for one processor's instructions was offered to another"
    assert portable_a == portable_b, "a portable library was keyed by the processor (needless rebuilds)"


def test_the_processor_identity_names_model_and_features():
    identity = nmpc_codegen.processor_identity()
    assert identity and identity == nmpc_codegen.processor_identity()


@pytest.mark.parametrize("cpuinfo, identity", [
    # x86: the first processor's model and flags, not its number, vendor or speed, nor the second's
    ("processor\t: 0\nvendor_id\t: GenuineIntel\nmodel name\t: Intel(R) Xeon(R) CPU @ 2.20GHz\ncpu MHz\t\t: 2200.1\n"
     "flags\t\t: fpu sse2 avx2\n\nprocessor\t: 1\nmodel name\t: Other\nflags\t\t: fpu\n",
     "Intel(R) Xeon(R) CPU @ 2.20GHz|fpu sse2 avx2"),
    # ARM names its flags "Features"; a value may hold a colon
    ("processor\t: 0\nBogoMIPS\t: 50.00\nFeatures\t: fp asimd sve\nCPU model\t: Neoverse: V1\n",
     "fp asimd sve|Neoverse: V1"),
    ("hart\t\t: 0\nisa\t\t: rv64imafdc_zicsr\nmmu\t\t: sv39\n", "rv64imafdc_zicsr"),
])
def test_the_processor_identity_reads_the_first_processors_model_and_feature_lines(monkeypatch, cpuinfo, identity):
    import io

    def fake_open(path, *args, **kwargs):
        assert path == "/proc/cpuinfo"
        return io.StringIO(cpuinfo)

    monkeypatch.setattr(nmpc_codegen, "open", fake_open, raising=False)
    assert nmpc_codegen.processor_identity() == identity


# -- building, loading, falling back -------------------------------------------------------------------
def test_a_library_is_built_once_named_by_solver_and_key_and_solves_as_interpreted(cache):
    builds = NLPLibrary.builds
    started = time.perf_counter()
    library = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS)
    assert 0.0 < library.build_time_s <= time.perf_counter() - started
    assert library.mode == "compiled" and NLPLibrary.builds == builds + 1
    key = library_key(tiny_nlp(), "ipopt", find_compiler(), OPTIONS)
    assert library.path == cache / f"nlp_ipopt_{key[:24]}.so" and library.path.is_file()
    assert library.build_time_s > 0.0 and library.reason == ""
    assert library.summary() == {"codegen": "compiled", "codegen_library": str(library.path),
                                 "codegen_build_s": library.build_time_s, "codegen_note": None}
    assert sorted(p.name for p in cache.iterdir()) == sorted([library.path.name, f"{library.path.stem}.lock"])
    again = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS)
    assert NLPLibrary.builds == builds + 1 and again.path == library.path and again.build_time_s is None
    interpreted = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS, enabled=False)
    assert solve(library.solver("a")) == pytest.approx(3.0) == solve(interpreted.solver("b"))
    # other options for one solver (here no iteration allowed): the same compiled functions under them
    stopped = library.solver("c", {**OPTIONS, "ipopt": {"print_level": 0, "sb": "yes", "max_iter": 0}})
    solve(stopped)
    assert stopped.stats()["return_status"] == "Maximum_Iterations_Exceeded"


def test_the_cache_folder_is_made_with_its_parents(tmp_path, monkeypatch):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "a" / "b" / "nmpc"))
    monkeypatch.delenv(CODEGEN_ENV, raising=False)
    library = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS)
    assert library.mode == "compiled" and library.path.parent == tmp_path / "a" / "b" / "nmpc"


def test_a_library_built_by_another_process_meanwhile_is_not_rebuilt(cache, monkeypatch):
    first = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS)
    builds = NLPLibrary.builds
    calls = []
    original = Path.is_file

    def missing_once(path):  # the first look misses it, as if another process were still writing it
        if path == first.path and not calls:
            calls.append(path)
            return False
        return original(path)

    monkeypatch.setattr(Path, "is_file", missing_once)
    second = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS)
    assert calls and second.mode == "compiled" and NLPLibrary.builds == builds and second.build_time_s is None


def test_a_broken_library_in_the_cache_falls_back_to_interpreted(cache, caplog):
    first = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS)
    first.path.write_bytes(b"not a shared library")
    with caplog.at_level(logging.WARNING, logger="rhnc.control.nmpc_codegen"):
        second = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS)
    assert second.mode == "interpreted" and second.path is None and second.build_time_s is None
    assert second.reason.startswith("compiling the NLP failed (")
    assert "the NLP's functions stay interpreted" in caplog.text
    assert solve(second.solver("s")) == pytest.approx(3.0)


def test_a_library_that_does_not_load_after_its_build_counts_as_no_build(cache, tmp_path, monkeypatch):
    writes_junk = script(tmp_path, "junk-cc", 'while [ $# -gt 0 ]; do [ "$1" = "-o" ] && echo junk > "$2"; shift; done\n')
    monkeypatch.setenv("CC", str(writes_junk))
    library = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS)
    assert library.mode == "interpreted" and library.reason.startswith("compiling the NLP failed (")
    assert library.build_time_s is None and library.summary()["codegen_build_s"] is None


def test_the_keys_parts_are_kept_apart():
    # without a separator, plugin "ipopt" + compiler "x/cc" would read as plugin "ipoptx" + compiler "/cc"
    assert library_key(tiny_nlp(), "ipopt", "x/cc") != library_key(tiny_nlp(), "ipoptx", "/cc")


def test_a_failing_compiler_is_quoted_and_leaves_no_file(cache, tmp_path, monkeypatch):
    broken = script(tmp_path, "broken-cc", "echo 'cc 9'\necho 'error: no space left' >&2\nexit 3\n")
    monkeypatch.setenv("CC", str(broken))
    library = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS)
    assert library.mode == "interpreted" and library.build_time_s is None
    assert library.reason == "compiling the NLP failed (compiler exit 3: error: no space left)"
    assert library.summary()["codegen_note"] == library.reason
    assert [p.suffix for p in cache.iterdir()] == [".lock"]


@pytest.mark.parametrize("enabled, environment, reason", [
    (False, None, "code generation off in the settings"),
    (True, "off", f"code generation off by {CODEGEN_ENV}"),
])
def test_code_generation_switched_off_says_so_without_a_warning(cache, monkeypatch, caplog, enabled, environment,
                                                               reason):
    if environment:
        monkeypatch.setenv(CODEGEN_ENV, environment)
    with caplog.at_level(logging.WARNING, logger="rhnc.control.nmpc_codegen"):
        library = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS, enabled=enabled)
    assert library.mode == "interpreted" and library.reason == reason and not caplog.records
    assert library.summary() == {"codegen": "interpreted", "codegen_library": None, "codegen_build_s": None,
                                 "codegen_note": reason}
    assert not cache.exists()


def test_a_missing_compiler_named_by_cc_is_quoted(cache, monkeypatch, caplog):
    monkeypatch.setenv("CC", "/nonexistent/cc")
    with caplog.at_level(logging.WARNING, logger="rhnc.control.nmpc_codegen"):
        library = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS)
    assert library.reason == "no C compiler found ($CC = /nonexistent/cc)"
    assert caplog.records[0].getMessage() == ("NMPC: no C compiler found ($CC = /nonexistent/cc); the NLP's "
                                             "functions stay interpreted (slower solves)")
    monkeypatch.delenv("CC")
    monkeypatch.setattr(nmpc_codegen, "find_compiler", lambda: None)
    assert NLPLibrary(tiny_nlp(), "ipopt", OPTIONS).reason == "no C compiler found"


def test_a_compact_form_is_what_gets_compiled_and_the_expressions_what_get_interpreted(cache):
    compact = tiny_nlp(2.0)  # another graph of the same problem's optimum
    library = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS, compact_nlp=compact)
    assert library.nlp["f"] is not compact["f"] and library.compact_nlp is compact
    assert library.path.name == f"nlp_ipopt_{library_key(compact, 'ipopt', find_compiler(), OPTIONS)[:24]}.so"


def test_an_error_is_told_in_one_line():
    failed = subprocess.CalledProcessError(2, ["cc"], stderr="\n  first: bad\nsecond\n")
    assert _one_line(failed) == "compiler exit 2: first: bad"
    assert _one_line(subprocess.CalledProcessError(2, ["cc"], stderr=None)) == "compiler exit 2: "
    assert _one_line(OSError("  disk full\nmore")) == "disk full"
    assert _one_line(RuntimeError("   ")) == "RuntimeError"


@pytest.mark.skipif(sys.platform == "win32", reason="fcntl")
def test_the_build_lock_is_released(cache, tmp_path):
    import fcntl

    library = NLPLibrary(tiny_nlp(), "ipopt", OPTIONS)
    with open(cache / f"{library.path.stem}.lock", "a+") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)  # would raise if still held
        fcntl.flock(handle, fcntl.LOCK_UN)


def mapped_nlp(intervals: int) -> dict:
    """A compact form: one interval's function mapped over ``intervals`` variables."""
    x, p = ca.MX.sym("x"), ca.MX.sym("p")
    interval = ca.Function("interval", [x, p], [ca.sin(x) * ca.exp(x * p) + x ** 4 * ca.cos(p)])
    xs, ps = ca.MX.sym("xs", 1, intervals), ca.MX.sym("ps")
    return {"x": xs.T, "p": ps, "f": ca.sum2(interval.map(intervals)(xs, ca.repmat(ps, 1, intervals))), "g": xs.T}


def test_the_mapped_interval_function_is_compiled_once_not_once_per_interval(cache):
    few = NLPLibrary(mapped_nlp(5), "ipopt", OPTIONS)
    many = NLPLibrary(mapped_nlp(80), "ipopt", OPTIONS)
    assert few.mode == many.mode == "compiled"
    # inlined per interval (expanded), 80 intervals make a library about four times as large
    assert many.path.stat().st_size < 1.5 * few.path.stat().st_size


def test_only_the_derivatives_the_solver_options_ask_for_are_compiled(cache):
    import ctypes

    limited_memory = {**OPTIONS, "ipopt": {**OPTIONS["ipopt"], "hessian_approximation": "limited-memory"}}
    exact = ctypes.CDLL(str(NLPLibrary(tiny_nlp(), "ipopt", OPTIONS).path))
    # (another problem: the key does not follow the options, a library is named by its problem)
    quasi_newton = ctypes.CDLL(str(NLPLibrary(tiny_nlp(2.0), "ipopt", limited_memory).path))
    assert hasattr(exact, "nlp_hess_l") and hasattr(exact, "nlp_grad_f")
    assert hasattr(quasi_newton, "nlp_grad_f") and not hasattr(quasi_newton, "nlp_hess_l")
