"""Screenshots of a view in headless Chromium, offline (for the tests and the README picture).

    python -m eos_svc.view.browser "file:///tmp/plan.html#cycle=70" shot.png

Chromium runs headless with software WebGL, a fresh profile and no network (every host name
resolves to nothing); ``--virtual-time-budget`` lets the page's timers run before the shot.
"""

from __future__ import annotations

import shutil
import subprocess
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
#: what takes the network away (loopback pages are still reachable: the live view's tests use
#: ``offline=False`` for localhost)
OFFLINE_FLAGS = ("--proxy-server=127.0.0.1:9", "--host-resolver-rules=MAP * ~NOTFOUND")


class BrowserError(EosError):
    """Chromium is missing or did not produce a screenshot."""


def find_chromium() -> str | None:
    """Path of a Chromium executable, or None."""
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


def screenshot_command(
    url: str,
    png: str | Path | None,
    profile: str | Path,
    *,
    size: tuple[int, int] = (1024, 768),
    budget_ms: int = 8000,
    offline: bool = True,
    chromium: str | None = None,
) -> list[str]:
    """The Chromium command line that writes a screenshot of ``url`` to ``png`` (None: that prints
    the page's DOM instead)."""
    exe = chromium or find_chromium()
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


def _run(cmd: list[str], url: str, timeout_s: float) -> subprocess.CompletedProcess[str]:
    try:
        return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s, check=False)
    except subprocess.TimeoutExpired as exc:
        raise BrowserError(f"Chromium took more than {timeout_s:g} s on {url}") from exc


def dump_dom(url: str, *, budget_ms: int = 8000, offline: bool = True, timeout_s: float = 120.0) -> str:
    """The page's DOM (HTML text) after ``budget_ms`` of virtual time.

    Raises:
        BrowserError: no Chromium, or it printed nothing.
    """
    with tempfile.TemporaryDirectory(prefix="eos-chromium-", ignore_cleanup_errors=True) as profile:
        cmd = screenshot_command(url, None, profile, budget_ms=budget_ms, offline=offline)
        proc = _run(cmd, url, timeout_s)
    if not proc.stdout.strip():
        raise BrowserError(f"Chromium printed no DOM (exit {proc.returncode}): {proc.stderr[-500:]}")
    return proc.stdout


def screenshot(
    url: str,
    png: str | Path,
    *,
    size: tuple[int, int] = (1024, 768),
    budget_ms: int = 8000,
    offline: bool = True,
    timeout_s: float = 120.0,
) -> Path:
    """Take a screenshot of ``url`` (a fresh profile each time); returns the PNG's path.

    Raises:
        BrowserError: no Chromium, it failed, or it wrote no picture.
    """
    out = Path(png).resolve()
    out.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory(prefix="eos-chromium-", ignore_cleanup_errors=True) as profile:
        cmd = screenshot_command(url, out, profile, size=size, budget_ms=budget_ms, offline=offline)
        proc = _run(cmd, url, timeout_s)
    if not out.exists():
        raise BrowserError(f"Chromium wrote no screenshot (exit {proc.returncode}): {proc.stderr[-500:]}")
    return out


def main(argv: list[str] | None = None) -> int:
    """``python -m eos_svc.view.browser URL PNG [WIDTH HEIGHT]``: one offline screenshot."""
    import sys

    args = sys.argv[1:] if argv is None else argv
    if len(args) not in (2, 4):
        print("usage: python -m eos_svc.view.browser URL PNG [WIDTH HEIGHT]", file=sys.stderr)
        return 2
    size = (int(args[2]), int(args[3])) if len(args) == 4 else (1024, 768)
    try:
        print(screenshot(args[0], args[1], size=size))
    except BrowserError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
