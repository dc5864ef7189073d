"""The monitor's page in a real browser: Debian's Chromium, headless, driven by Playwright (its
test and its benchmark). WebGL runs on SwiftShader, Chromium's CPU renderer, as on a host
without a GPU."""

from __future__ import annotations

import contextlib
import shutil
from collections.abc import Iterator
from pathlib import Path

from mocap.errors import DataMissingError

CHROMIUM = Path(shutil.which("chromium") or "/usr/bin/chromium")
FLAGS = ["--enable-unsafe-swiftshader", "--use-angle=swiftshader", "--ignore-gpu-blocklist", "--disable-gpu-compositing"]


@contextlib.contextmanager
def page(url: str, width: int = 1280, height: int = 720) -> Iterator[object]:
    """A Playwright page showing `url` (sync API); the browser closes with the block."""
    if not CHROMIUM.exists():
        raise DataMissingError(f"{CHROMIUM} is missing: `make setup` installs Debian's chromium")
    from playwright.sync_api import sync_playwright  # only the page's test and benchmark need it

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=FLAGS)
        try:
            shown = browser.new_page(viewport={"width": width, "height": height})
            shown.goto(url)
            yield shown
        finally:
            browser.close()
