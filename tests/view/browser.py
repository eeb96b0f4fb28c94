"""Screenshots of a view in headless Chromium, offline (for the tests and the README picture).

    python tests/view/browser.py "file:///tmp/plan.html#cycle=70" shot.png [WIDTH HEIGHT]

Chromium runs headless with software WebGL, a fresh profile and no network (every host name
resolves to nothing); ``--virtual-time-budget`` lets the page's timers run before the shot.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from eos_svc.errors import EosError

#: executables tried in turn
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome")

#: flags: headless, software GL, nothing in the background, no network
FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--use-angle=swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-default-apps",
    "--no-first-run",
    "--mute-audio",
    "--hide-scrollbars",
)
#: what takes the network away (the live view's tests use ``offline=False`` for localhost)
OFFLINE_FLAGS = ("--proxy-server=127.0.0.1:9", "--host-resolver-rules=MAP * ~NOTFOUND")


class BrowserError(EosError):
    """Chromium is missing or did not produce a screenshot."""


def find_chromium() -> str | None:
    """Path of a Chromium executable, or None."""
    return next((path for name in CHROMIUM_NAMES if (path := shutil.which(name))), None)


def screenshot_command(
    url: str,
    png: str | Path | None,
    profile: str | Path,
    *,
    size: tuple[int, int] = (1024, 768),
    budget_ms: int = 8000,
    offline: bool = True,
) -> list[str]:
    """The Chromium command line that writes a screenshot of ``url`` to ``png`` (None: that prints
    the page's DOM instead)."""
    exe = find_chromium()
    if exe is None:
        raise BrowserError(f"no Chromium found (tried {', '.join(CHROMIUM_NAMES)}); apt-get install chromium")
    return [
        exe,
        *FLAGS,
        *(OFFLINE_FLAGS if offline else ()),
        f"--user-data-dir={profile}",
        f"--window-size={size[0]},{size[1]}",
        f"--virtual-time-budget={budget_ms}",
        "--dump-dom" if png is None else f"--screenshot={png}",
        url,
    ]


def _run(url: str, png: Path | None, size: tuple[int, int], budget_ms: int, offline: bool) -> str:
    """Run Chromium on ``url`` with a fresh profile (at most 120 s); its standard output."""
    with tempfile.TemporaryDirectory(prefix="eos-chromium-", ignore_cleanup_errors=True) as profile:
        cmd = screenshot_command(url, png, profile, size=size, budget_ms=budget_ms, offline=offline)
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120.0, check=False)
        except subprocess.TimeoutExpired as exc:
            raise BrowserError(f"Chromium took more than 120 s on {url}") from exc
    if (png is None and not proc.stdout.strip()) or (png is not None and not png.exists()):
        raise BrowserError(f"Chromium wrote nothing (exit {proc.returncode}): {proc.stderr[-500:]}")
    return proc.stdout


def dump_dom(url: str, *, budget_ms: int = 8000, offline: bool = True) -> str:
    """The page's DOM (HTML text) after ``budget_ms`` of virtual time (BrowserError: none)."""
    return _run(url, None, (1024, 768), budget_ms, offline)


def screenshot(
    url: str,
    png: str | Path,
    *,
    size: tuple[int, int] = (1024, 768),
    budget_ms: int = 8000,
    offline: bool = True,
) -> Path:
    """Take a screenshot of ``url``; returns the PNG's path (BrowserError: no picture)."""
    out = Path(png).resolve()
    out.unlink(missing_ok=True)
    _run(url, out, size, budget_ms, offline)
    return out


if __name__ == "__main__":
    args = sys.argv[1:]
    if len(args) not in (2, 4):
        sys.exit("usage: python tests/view/browser.py URL PNG [WIDTH HEIGHT]")
    print(screenshot(args[0], args[1], size=(int(args[2]), int(args[3])) if len(args) == 4 else (1024, 768)))
