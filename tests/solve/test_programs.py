"""The solver's compiled programs (jaxnet.solve.programs): what identifies a program, and reuse in memory.

The round trip through the disk, and a damaged file, are tested through the command line in a fresh process
(tests/test_cli.py::test_compiled_programs_are_kept_on_disk_and_reused)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.solve import programs


@jax.jit
def _scaled(x, s):
    return s * jnp.sin(x)


def test_a_program_is_identified_by_its_arguments_shapes_and_static_options_not_their_values():
    x = np.zeros(4)
    base = programs.key("p", (("model", ("a", 1)),), (x, 1.0))
    assert programs.key("p", (("model", ("a", 1)),), (np.ones(4), 2.5)) == base  # other values: same program
    others = [programs.key("q", (("model", ("a", 1)),), (x, 1.0)),  # another program
              programs.key("p", (("model", ("a", 2)),), (x, 1.0)),  # another option of a term
              programs.key("p", (("model", ("a", 1)),), (np.zeros(5), 1.0)),  # another size
              programs.key("p", (("model", ("a", 1)),), (np.zeros(4, np.int64), 1.0)),  # another dtype
              programs.key("p", (("model", ("a", 1)),), (x, np.float64(1.0))),  # a strongly typed scalar
              programs.key("p", (("model", ("a", 1)),), ((x,), 1.0))]  # another structure
    assert len({base, *others}) == 1 + len(others)


def test_the_sources_digest_changes_with_any_source_file(tmp_path):
    (tmp_path / "terms").mkdir()
    (tmp_path / "terms" / "tension.py").write_text("EA = 1.0\n")
    (tmp_path / "assemble.py").write_text("pass\n")
    before = programs.sources_digest(tmp_path)
    assert programs.sources_digest(tmp_path) == before
    (tmp_path / "terms" / "tension.py").write_text("EA = 2.0\n")
    assert programs.sources_digest(tmp_path) != before


def test_a_program_is_compiled_once_per_process_and_computes_what_the_function_does(monkeypatch):
    monkeypatch.setattr(programs, "directory", lambda: None)  # memory only
    programs.clear()
    x = np.linspace(0.0, 1.0, 7)
    assert programs.lookup("scaled", (x, 2.0)) is None
    program = programs.obtain("scaled", _scaled, (x, 2.0))
    assert programs.obtain("scaled", _scaled, (x + 1.0, 3.0)) is program  # same shapes: reused
    np.testing.assert_allclose(program(x + 1.0, 3.0), 3.0 * np.sin(x + 1.0), rtol=1e-15)
    assert programs.lookup("scaled", (np.zeros(8), 2.0)) is None  # another size is another program
    programs.clear()
    assert programs.lookup("scaled", (x, 2.0)) is None


_PROCESS = """
import sys, jax, jax.numpy as jnp, numpy as np
import jaxnet
from jaxnet.solve import programs
jax.config.update("jax_compilation_cache_dir", sys.argv[1])
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
scaled, x = jax.jit(lambda x, s: s * jnp.sin(x)), np.linspace(0.0, 1.0, 7)
if sys.argv[2] == "jax":  # compiled by JAX's own jit call: kept in JAX's cache only
    print(float(np.asarray(scaled(x, 3.0)).sum()))
else:
    program = programs.obtain("scaled", scaled, (x, 2.0))
    print(float(np.asarray(program(x, 3.0)).sum()))  # summed by numpy: no other program
"""


def _run_process(cache, mode):
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", _PROCESS, str(cache), mode], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    return float(out.stdout.split()[-1])


def test_a_program_is_kept_by_jaxnet_alone_and_the_next_process_loads_it(tmp_path):
    """jaxnet keeps its programs whole; JAX's own cache gets no second copy of them (its write would be
    on the solve's path). The next process loads the program and computes the same."""
    expected = 3.0 * np.sin(np.linspace(0.0, 1.0, 7)).sum()
    assert _run_process(tmp_path, "jaxnet") == pytest.approx(expected, rel=1e-14)
    # nothing in JAX's cache (on a GPU XLA keeps its autotuning results there, "xla_gpu_..._cache_dir": no program)
    assert [p.name for p in tmp_path.iterdir() if not p.name.startswith("xla_")] == [programs.SUBDIRECTORY]
    kept = list((tmp_path / programs.SUBDIRECTORY).iterdir())
    assert len(kept) == 1
    stamp = kept[0].stat().st_mtime_ns
    assert _run_process(tmp_path, "jaxnet") == pytest.approx(expected, rel=1e-14)
    assert [p.stat().st_mtime_ns for p in (tmp_path / programs.SUBDIRECTORY).iterdir()] == [stamp]  # loaded


def test_a_program_jax_took_from_its_own_cache_is_not_kept_on_disk(tmp_path):
    """On CPU an executable JAX loaded from its persistent cache serialises without its kernels: kept on disk it
    would load in the next process and fail at its first call. Such a program serves its process only."""
    expected = 3.0 * np.sin(np.linspace(0.0, 1.0, 7)).sum()
    assert _run_process(tmp_path, "jax") == pytest.approx(expected, rel=1e-14)  # now in JAX's cache
    assert len(list(tmp_path.iterdir())) >= 1
    assert _run_process(tmp_path, "jaxnet") == pytest.approx(expected, rel=1e-14)  # JAX's cache answers
    assert not (tmp_path / programs.SUBDIRECTORY).exists() or list((tmp_path / programs.SUBDIRECTORY).iterdir()) == []
    assert _run_process(tmp_path, "jaxnet") == pytest.approx(expected, rel=1e-14)  # and the next process is right


def test_jit_compiles_with_the_package_options(monkeypatch):
    """:func:`programs.jit` hands :data:`programs.COMPILER_OPTIONS` to XLA when it compiles for the CPU, a
    caller's own options on top, and none to another backend (a GPU refuses the CPU's options). An option
    XLA refuses (its name unknown to this jax: jax 0.11.2 no longer knows ``xla_cpu_use_fusion_emitters``) is
    left out with a warning that names it -- which also shows that the options reach XLA -- and the others
    are kept."""
    import jax
    import jax.numpy as jnp

    x = np.linspace(0.0, 1.0, 5)
    np.testing.assert_allclose(programs.jit(jnp.sin)(x), np.sin(x), rtol=1e-15)
    assert programs.compiler_options("cpu") == programs.COMPILER_OPTIONS
    assert programs.compiler_options("gpu") == {} and programs.compiler_options("tpu") == {}
    monkeypatch.setattr(programs, "COMPILER_OPTIONS", {"xla_no_such_option": True,
                                                       "xla_cpu_use_fusion_emitters": False})
    if jax.default_backend() == "cpu":
        with pytest.warns(RuntimeWarning, match=r"refuses the option\(s\) \['xla_no_such_option'\]"):
            np.testing.assert_allclose(programs.jit(lambda v: jnp.cos(v))(x), np.cos(x), rtol=1e-15)
    assert programs.compiler_options("cpu") == {"xla_cpu_use_fusion_emitters": False}
    # the caller's options are merged over the package's: a valid override does not bring the bad one back
    monkeypatch.setattr(programs, "COMPILER_OPTIONS", {"xla_cpu_use_fusion_emitters": False})
    override = {"xla_cpu_use_fusion_emitters": True} if jax.default_backend() == "cpu" else {}
    np.testing.assert_allclose(programs.jit(lambda v: jnp.tan(v), compiler_options=override)(x),
                               np.tan(x), rtol=1e-15)


def test_package_programs_are_made_for_the_backend_of_their_first_call(monkeypatch):
    """A program declared with :func:`programs.jit` takes its options when first called, not when declared
    (the package declares its programs at import, before a user may choose JAX's platform); its jax.jit
    attributes (``trace``, ``lower``) are there."""
    import jax
    import jax.numpy as jnp

    declared = programs.jit(lambda v: 2.0 * v)  # declared under the package's options,
    monkeypatch.setattr(programs, "COMPILER_OPTIONS", {"xla_option_set_after_declaring": True})
    x = np.arange(3.0)
    if jax.default_backend() == "cpu":  # made at its first call: under the options of then
        with pytest.warns(RuntimeWarning, match="xla_option_set_after_declaring"):
            np.testing.assert_allclose(declared(x), 2.0 * x)
    assert declared.trace(x).lower().compile()(x).tolist() == [0.0, 2.0, 4.0]
    assert programs.jit(jnp.sin).__name__ == "sin"


def test_the_package_compiles_through_programs_jit():
    """Every program of the package is made by :func:`programs.jit` (so with its compiler options), except
    those that run inside a caller's traced function (XLA refuses options there), each marked so on the
    line above its ``jax.jit``."""
    import pathlib

    root = pathlib.Path(programs.__file__).resolve().parents[1]
    offenders = []
    for path in root.rglob("*.py"):
        lines = path.read_text().splitlines()
        offenders += [f"{path.relative_to(root)}:{k + 1}" for k, line in enumerate(lines)
                      if "jax.jit(" in line and path.name != "programs.py" and "plain jax.jit" not in lines[k - 1]]
    assert offenders == []
