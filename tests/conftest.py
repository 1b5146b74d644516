"""Fixtures shared by the whole suite, and what keeps it hermetic.

Random numbers: a test that draws takes the ``rng`` fixture (or makes its own ``np.random.default_rng(SEED)``),
and helpers that draw take the generator as their first argument. No module holds a generator at module level:
one shared by a module's tests made what each test drew depend on which tests had drawn before it in the same
process (their order, a ``-k`` selection, how xdist spread the tests over its workers), so a test could pass in
the whole suite and fail alone, or the other way round.

Files: a test writes under its ``tmp_path`` only, and asserts nothing about that path's name (pytest numbers its
base folders from ``pytest-0`` on a machine that never ran it). What the tools write by themselves goes to
folders of this run, removed at its end: Hypothesis's files (:func:`pytest_configure`) and the command line's
default cache of compiled programs (``XDG_CACHE_HOME``), which a test of ``jaxnet run`` without ``--cache`` would
otherwise read from and write to in the user's home.

Order: ``python -m pytest --shuffle SEED`` runs the tests in an order drawn from SEED (the same in every xdist
worker, as xdist requires), to show that no test depends on another having run before it.
"""

import os
import pathlib
import shutil
import tempfile
import zlib

# One thread of XLA's CPU runtime and of MKL (PARDISO) per process: the suite runs one xdist worker per core, and a
# worker whose XLA and MKL each start a thread per core makes two cores run four to eight threads, which costs
# more than it gives on the suite's small programs. Set before JAX or MKL is loaded (test modules import them
# after this file); subprocesses of the tests inherit it; a value the user set is kept.
if "xla_cpu_multi_thread_eigen" not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") +
                               " --xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1").strip()
for _variable in ("MKL_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

_HYPOTHESIS_HOME = pytest.StashKey[pathlib.Path]()
_CACHE_HOME = pytest.StashKey[pathlib.Path]()


def seed_of(nodeid):
    """The seed of a test's generator: CRC-32 of its node id without the test file's folder
    (``tests/test_x.py::test_y[param]`` for ``tests/solve/test_x.py::test_y[param]``), the same in every process
    and run (Python's ``hash`` of a string is salted per process), and the same when a test file moves between
    the folders that mirror the package."""
    file, _, rest = nodeid.partition("::")
    return zlib.crc32(f"tests/{file.rsplit('/', 1)[-1]}::{rest}".encode())


@pytest.fixture
def rng(request):
    """The test's own ``numpy.random.Generator``, seeded from its node id (:func:`seed_of`): a test draws the same
    numbers whatever ran before it, alone or in the suite, on any xdist worker; each parametrisation of a test
    draws its own. Renaming a test (or its parameters' ids) changes its draws: a test must pass for any draw
    within the domain it documents, not for one lucky seed."""
    return np.random.default_rng(seed_of(request.node.nodeid))


def pytest_addoption(parser):
    parser.addoption("--shuffle", type=int, default=None, metavar="SEED",
                     help="run the tests in an order drawn from SEED (an integer), not in file order")


def pytest_collection_modifyitems(config, items):
    """With ``--shuffle SEED``, the collected tests in a random order drawn from SEED alone."""
    seed = config.getoption("--shuffle")
    if seed is not None:
        order = np.random.default_rng(seed).permutation(len(items))
        items[:] = [items[i] for i in order]


def pytest_configure(config):
    """``XDG_CACHE_HOME`` set to a folder of this process (the command line's default cache of compiled programs
    is under it). Hypothesis keeps files under ``.hypothesis/`` of the current directory (a cache of the constants it reads in
    the code under test, written while its plugin sorts the collected tests; its database where one is used): a
    temporary folder of this process instead, removed at the end, so that a run writes nothing into the checkout
    and reads nothing a previous run left there."""
    config.stash[_CACHE_HOME] = pathlib.Path(tempfile.mkdtemp(prefix="jaxnet-tests-cache-"))
    os.environ["XDG_CACHE_HOME"] = str(config.stash[_CACHE_HOME])
    try:
        from hypothesis import configuration
    except ImportError:  # not installed: no test uses it
        return
    config.stash[_HYPOTHESIS_HOME] = pathlib.Path(tempfile.mkdtemp(prefix="jaxnet-tests-hypothesis-"))
    configuration.set_hypothesis_home_dir(config.stash[_HYPOTHESIS_HOME])


def pytest_unconfigure(config):
    cache = config.stash.get(_CACHE_HOME, None)
    if cache is not None:
        shutil.rmtree(cache, ignore_errors=True)
    home = config.stash.get(_HYPOTHESIS_HOME, None)
    if home is not None:
        from hypothesis import configuration

        configuration.set_hypothesis_home_dir(None)
        shutil.rmtree(home, ignore_errors=True)
