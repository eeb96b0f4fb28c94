"""Data files the package loads: the three-finger hand's URDF, from the installed data package
``eos_svc.data`` or, in a source checkout, the repository's ``urdf/``.
"""

from __future__ import annotations

import atexit
import contextlib
import importlib.resources
from pathlib import Path

__all__ = ["DATA_PACKAGE", "data_file"]

#: the package that holds the data files in an installed eos_svc
DATA_PACKAGE = "eos_svc.data"
#: where the same files are in a source checkout (the repository's top-level ``urdf/``)
CHECKOUT_DATA_DIR = Path(__file__).resolve().parents[2] / "urdf"

_extracted = contextlib.ExitStack()  # files extracted from a zipped install, removed at exit
atexit.register(_extracted.close)


def data_file(name: str) -> Path:
    """A file system path to data file ``name`` (e.g. ``"hand3x3.urdf"``).

    Looked up through :mod:`importlib.resources` in :data:`DATA_PACKAGE`; when the package is
    not installed (a source checkout), in :data:`CHECKOUT_DATA_DIR`. A file inside a zipped
    install is extracted to a temporary file kept until the interpreter exits (Pinocchio reads
    paths). Returns the path whether or not it exists: the loaders report a missing file.
    """
    try:
        resource = importlib.resources.files(DATA_PACKAGE).joinpath(name)
    except ModuleNotFoundError:
        return CHECKOUT_DATA_DIR / name
    if not resource.is_file():
        return CHECKOUT_DATA_DIR / name
    if isinstance(resource, Path):
        return resource
    return Path(_extracted.enter_context(importlib.resources.as_file(resource)))
