"""The installed package's version (``pyproject.toml``), as ``jaxnet --version`` and ``result.json`` give it.

A module of its own, which imports nothing of jaxnet, so that any layer may read it (the figures of a result,
the command line) without importing the package's public names.
"""

from importlib import metadata

try:
    __version__ = metadata.version("jaxnet")
except metadata.PackageNotFoundError:  # run from a source tree that was not installed
    __version__ = "0+unknown"
