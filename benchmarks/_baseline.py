"""Load ``eos_svc.kinematics`` as it was at an earlier git revision, for before/after timings
measured in the same run (the machine is shared and noisy: only same-run ratios mean much).

    kin = load_kinematics("9a82297")      # a package with the old hand, scene, rolling, ep1 ...
    kin.load_hand(), kin.rolling.RollingQP, kin.ep1.run_ep1, ...
"""

from __future__ import annotations

import atexit
import importlib
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]


def load_kinematics(rev: str) -> ModuleType:
    """The ``eos_svc.kinematics`` package of git revision ``rev``, imported under a private name
    (its submodules ``ep1``, ``rolling`` ... loaded too)."""
    listing = subprocess.run(
        ["git", "-C", str(ROOT), "ls-tree", "--name-only", rev, "eos_svc/kinematics/"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    tmp = Path(tempfile.mkdtemp(prefix="eos_baseline_"))
    atexit.register(shutil.rmtree, tmp, True)
    name = "eos_baseline_" + re.sub(r"\W", "_", rev)
    pkg = tmp / "src" / name
    pkg.mkdir(parents=True)
    subs = []
    for f in listing:
        if f.endswith(".py"):
            text = subprocess.run(
                ["git", "-C", str(ROOT), "show", f"{rev}:{f}"], capture_output=True, check=True
            ).stdout
            # its absolute imports of its own package point at the private copy
            text = re.sub(rb"\beos_svc\.kinematics\b", name.encode(), text)
            (pkg / Path(f).name).write_bytes(text)
            subs.append(Path(f).stem)
    # hand.py finds the URDF at parents[2] / "urdf" of its own file
    (tmp / "urdf").symlink_to(ROOT / "urdf")
    sys.path.insert(0, str(tmp / "src"))
    mod = importlib.import_module(name)
    for sub in subs:
        if sub != "__init__":
            setattr(mod, sub, importlib.import_module(f"{name}.{sub}"))
    return mod
