"""The solver's compiled programs (jaxnet.solve.programs): what identifies a program, and reuse in memory.

The round trip through the disk, and a damaged file, are tested through the command line in a fresh process
(tests/test_cli.py::test_compiled_programs_are_kept_on_disk_and_reused)."""

import jax
import jax.numpy as jnp
import numpy as np

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
