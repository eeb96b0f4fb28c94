"""Packaging beyond what pyproject.toml can say: the hand's URDF goes into the wheel.

The repository keeps the hand at ``urdf/hand3x3.urdf`` (top level). ``package_dir`` maps that
directory onto the data package ``eos_svc.data`` when the wheel is built, so an installed
``eos_svc`` finds the file through :mod:`importlib.resources` (see
``eos_svc/kinematics/assets.py``); there is one copy of the file in git.
"""

from setuptools import find_packages, setup

setup(
    packages=[*find_packages(include=["eos_svc", "eos_svc.*"]), "eos_svc.data"],
    package_dir={"eos_svc.data": "urdf"},
    package_data={"eos_svc.data": ["*.urdf"]},
)
