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
program = programs.obtain("scaled", jax.jit(lambda x, s: s * jnp.sin(x)), (np.linspace(0.0, 1.0, 7), 2.0))
print(float(program(np.linspace(0.0, 1.0, 7), 3.0).sum()))
"""


def test_a_program_jax_took_from_its_own_cache_is_not_kept_on_disk(tmp_path):
    """On CPU an executable JAX loaded from its persistent cache serialises without its kernels: kept on disk it
    would load in the next process and fail at its first call. Such a program serves its process only."""
    import subprocess
    import sys

    def run():
        out = subprocess.run([sys.executable, "-c", _PROCESS, str(tmp_path)], capture_output=True, text=True)
        assert out.returncode == 0, out.stderr[-2000:]
        return float(out.stdout.split()[-1])

    expected = 3.0 * np.sin(np.linspace(0.0, 1.0, 7)).sum()
    assert run() == pytest.approx(expected, rel=1e-14)  # compiled afresh: kept by JAX and by jaxnet
    kept = tmp_path / programs.SUBDIRECTORY
    assert len(list(kept.iterdir())) == 1
    for path in kept.iterdir():
        path.unlink()
    assert run() == pytest.approx(expected, rel=1e-14)  # JAX's cache answers: not kept
    assert list(kept.iterdir()) == []
    assert run() == pytest.approx(expected, rel=1e-14)  # and the next process is still right
