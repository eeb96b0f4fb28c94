"""Loading a hand from a URDF and its description (Pinocchio model + coal collision geometry),
Pinocchio's C-level URDF warnings kept on the model (:attr:`HandModel.load_warnings`), not printed.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path

import pinocchio as pin

from .assets import data_file
from .description import HandDescription
from .errors import UrdfLoadError
from .hand_model import HandModel

__all__ = ["HAND3X3_URDF", "capture_stderr", "load_hand"]

#: The three-finger hand's URDF (from the installed package's data, or the checkout's urdf/).
HAND3X3_URDF: Path = data_file("hand3x3.urdf")


@contextlib.contextmanager
def capture_stderr() -> Iterator[io.StringIO]:
    """Capture C-level and Python stderr (Pinocchio prints URDF warnings there)."""
    buf = io.StringIO()
    try:
        fd = sys.stderr.fileno()
    except (AttributeError, io.UnsupportedOperation, ValueError):
        with contextlib.redirect_stderr(buf):
            yield buf
        return
    import tempfile

    sys.stderr.flush()
    saved = os.dup(fd)
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), fd)
        try:
            with contextlib.redirect_stderr(buf):
                yield buf
        finally:
            sys.stderr.flush()
            os.dup2(saved, fd)
            os.close(saved)
            tmp.seek(0)
            buf.write(tmp.read().decode(errors="replace"))


def load_hand(
    urdf_path: str | os.PathLike[str] = HAND3X3_URDF,
    description: HandDescription | None = None,
    package_dirs: Sequence[str | os.PathLike[str]] = (),
) -> HandModel:
    """Load a hand from a URDF and its description (default: :meth:`HandDescription.hand3x3`);
    ``package_dirs`` resolve ``package://`` mesh URIs. Raises :class:`UrdfLoadError` (missing
    or unparsable file), :class:`HandDescriptionError` or :class:`UnknownNameError` (the
    description does not match the URDF)."""
    path = Path(urdf_path)
    if not path.is_file():
        raise UrdfLoadError("urdf_path", f"no such file: {path}")
    desc = description if description is not None else HandDescription.hand3x3()
    dirs = [str(Path(p)) for p in package_dirs]
    try:
        with capture_stderr() as err:
            model = pin.buildModelFromUrdf(str(path))
            gmodel = pin.buildGeomFromUrdf(model, str(path), pin.COLLISION, package_dirs=dirs)
    except Exception as exc:  # Pinocchio raises ValueError/RuntimeError with a parser message
        raise UrdfLoadError("urdf_path", f"Pinocchio cannot load {path}: {exc}") from exc
    warnings = err.getvalue().strip()
    return HandModel(model, gmodel, desc, urdf_path=path, load_warnings=warnings)
