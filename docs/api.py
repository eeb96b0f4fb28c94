"""Build the API reference from the docstrings: ``make docs`` (or ``python docs/api.py OUT``).

Every public module of ``eos_svc`` (no ``_private`` module, no ``__main__``) is rendered by pdoc
into ``OUT`` (default ``build/api``, not kept in git). pdoc reports what it cannot render — an
annotation it cannot resolve, a module that fails to import — as warnings: each one is printed
and the build fails (exit 1), so the reference stays whole.
"""

from __future__ import annotations

import pkgutil
import sys
import warnings
from pathlib import Path

import pdoc

import eos_svc


def public_modules() -> list[str]:
    """What to hand pdoc so that it renders ``eos_svc`` and every public submodule once.

    pdoc walks a package's submodules itself, except those its ``__all__`` leaves out (the
    package root and ``eos_svc.kinematics`` export names, not modules): those are named here.
    """
    names = ["eos_svc"]
    for info in pkgutil.walk_packages(eos_svc.__path__, prefix="eos_svc."):
        if any(part.startswith("_") for part in info.name.split(".")):
            continue
        parent = sys.modules[info.name.rpartition(".")[0]]
        listed = getattr(parent, "__all__", None)
        if listed is not None and info.name.rpartition(".")[2] not in listed:
            names.append(info.name)
    return names


#: pdoc finds a class's fields in its source; a TypedDict in the functional form (needed when a
#: key is a Python keyword, as the board's ``shape["class"]``) has none, so pdoc says it assumes
#: the fields are declared where the class is — which they are. Only these warnings are dropped.
FUNCTIONAL_TYPEDDICTS = ("eos_svc.schema.board_entries.ShapeEntry.",)


def _benign(w: warnings.WarningMessage) -> bool:
    return any(str(w.message).startswith(f"Cannot determine where {name}") for name in FUNCTIONAL_TYPEDDICTS)


def main(argv: list[str]) -> int:
    out = Path(argv[0]) if argv else Path("build/api")
    modules = public_modules()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pdoc.render.configure(docformat="google")
        pdoc.pdoc(*modules, output_directory=out)
    problems = [w for w in caught if issubclass(w.category, UserWarning) and not _benign(w)]
    for w in problems:
        print(f"pdoc warning: {w.message}", file=sys.stderr)
    pages = len(list(out.rglob("*.html"))) - 1  # one per module, and the index
    print(
        f"API reference of {pages} modules: {out / 'index.html'}"
        + (f"; {len(problems)} warning(s)" if problems else ", no warnings")
    )
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
