"""Data files the package loads: the three-finger hand's URDF, from the installed data package
``eos_svc.data`` or, in a source checkout, the repository's ``urdf/``.
"""

from __future__ import annotations

import importlib.resources
from pathlib import Path

__all__ = ["DATA_PACKAGE", "data_file"]

#: the package that holds the data files in an installed eos_svc
DATA_PACKAGE = "eos_svc.data"
#: where the same files are in a source checkout (the repository's top-level ``urdf/``)
CHECKOUT_DATA_DIR = Path(__file__).resolve().parents[2] / "urdf"


def data_file(name: str) -> Path:
    """A file system path to data file ``name`` (e.g. ``"hand3x3.urdf"``): in :data:`DATA_PACKAGE`
    when it is installed (as files: Pinocchio reads paths), else in :data:`CHECKOUT_DATA_DIR`.
    Returns the path whether or not it exists: the loaders report a missing file."""
    try:
        resource = importlib.resources.files(DATA_PACKAGE).joinpath(name)
    except ModuleNotFoundError:
        return CHECKOUT_DATA_DIR / name
    return resource if isinstance(resource, Path) and resource.is_file() else CHECKOUT_DATA_DIR / name
