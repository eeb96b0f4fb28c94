"""Packaging beyond what pyproject.toml can say: the data files go into the wheel.

The repository keeps the hand at ``urdf/hand3x3.urdf`` (top level). ``package_dir`` maps that
directory onto the data package ``eos_svc.data`` when the wheel is built, so an installed
``eos_svc`` finds the file through :mod:`importlib.resources` (see
``eos_svc/kinematics/assets.py``); there is one copy of the file in git. Every other non-Python
file under ``eos_svc/`` (templates, schemas ...) is package data as it is.
"""

from pathlib import Path

from setuptools import find_packages, setup


def package_files(package: str) -> list[str]:
    """Every non-Python file under ``package``'s directory, relative to it (caches excluded)."""
    root = Path(package)
    return sorted(
        p.relative_to(root).as_posix()
        for p in root.rglob("*")
        if p.is_file() and p.suffix not in (".py", ".pyc") and "__pycache__" not in p.parts
    )


setup(
    packages=[*find_packages(include=["eos_svc", "eos_svc.*"]), "eos_svc.data"],
    package_dir={"eos_svc.data": "urdf"},
    package_data={"eos_svc": package_files("eos_svc"), "eos_svc.data": ["*.urdf"]},
)
