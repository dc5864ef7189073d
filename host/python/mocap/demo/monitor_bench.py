"""The live benchmark with the live view open: the simulated studio played live as by the
`live` benchmark, `mocap monitor` on mocapd's output and its page in headless Chromium; how often
the page updates, and the host's latency while it does."""

from __future__ import annotations

import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from mocap.demo import browser, play, score
from mocap.demo.run import start_monitor
from mocap.demo.studio import prepare
from mocap.errors import InputError

SETTLE_S = 2.0  # page rates are kept from this long after the take's start to 1 s before its end


def _watch(page, take: threading.Thread, start: float, seconds: float, screenshot: Path | None) -> list[list]:
    """The page's poses received and frames drawn per second, sampled each second while the take
    runs; a screenshot halfway through."""
    rates = []
    while take.is_alive():
        time.sleep(1.0)
        now = time.monotonic() - start
        if SETTLE_S <= now <= seconds - 1.0:
            rates.append(page.evaluate("[monitor.updateHz, monitor.renderHz]"))
        if screenshot is not None and now >= seconds / 2:
            page.screenshot(path=str(screenshot))
            screenshot = None
    return rates


def bench(seconds: float = 30.0, realtime: bool = True, screenshot: Path | None = None) -> dict:
    """{"bench": "monitor", ...}: page updates per second (min, median over the take), poses the
    page skipped, and the host's latency percentiles as the `live` line has them."""
    with tempfile.TemporaryDirectory() as folder:
        studio = prepare(Path(folder), seconds)
        started = start_monitor(studio, "127.0.0.1:0")
        if started is None:
            raise InputError("mocap monitor did not start (its error is above)")
        monitor, url = started
        out: dict = {}
        take = threading.Thread(target=lambda: out.update(run=play.play(studio, realtime=realtime)), daemon=True)
        try:
            with browser.page(url) as page:
                take.start()
                start = time.monotonic() + play.LEAD_S
                rates = _watch(page, take, start, seconds, screenshot)
                shown = page.evaluate("({frames: monitor.frames, skipped: monitor.skipped})")
        finally:
            take.join()
            monitor.terminate()
            monitor.wait(timeout=10)
        result = score.score(studio, out["run"])
    rates = np.array(rates, dtype=float).reshape(-1, 2)
    figures = {f"page_{name}_hz_{stat}": float(f(rates[:, k])) if len(rates) else None
               for k, name in enumerate(("update", "render")) for stat, f in (("min", np.min), ("median", np.median))}
    return {"bench": "monitor", "seconds": seconds, **figures, "page_frames": shown["frames"],
            "page_skipped": shown["skipped"], **{k: v for k, v in result.items() if k.startswith("latency_")},
            "frames": result["frames"], "dropped": result["dropped"],
            "host_realtime": out["run"].host_summary.get("realtime")}
