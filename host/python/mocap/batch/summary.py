"""The batch's summary: a table of its takes (printed, and OUT/summary.md) and OUT/summary.json."""

from __future__ import annotations

import json
from pathlib import Path

COLUMNS = ("take", "status", "frames", "IMUs", "frames ok", "joints vs truth (cm)", "bones vs truth (deg)",
           "seconds", "note")


def _row(r: dict) -> list[str]:
    truth = r.get("truth", {})
    ok = r["status"] == "ok"
    note = "solved before (same inputs, options and code)" if r.get("skipped") else r.get("error", "")
    return [r["name"], r["status"], str(r.get("frames", "-")), str(r.get("imus_used", "-")),
            f"{100 * r['frames_ok']:.0f}%" if ok and "frames_ok" in r else "-",
            f"{truth['joint_centres_pos_cm']:.2f}" if "joint_centres_pos_cm" in truth else "-",
            f"{truth['ori_error_offset_removed_deg']:.2f}" if "ori_error_offset_removed_deg" in truth else "-",
            f"{r['seconds']:.1f}" if "seconds" in r else "-", note.replace("|", "/").replace("\n", " ")]


def table(results: list[dict]) -> str:
    """A Markdown table, one row per take."""
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    return "\n".join(lines + ["| " + " | ".join(_row(r)) + " |" for r in results]) + "\n"


def write(out: Path, results: list[dict], wall_s: float) -> dict:
    """OUT/summary.json (every result) and OUT/summary.md (the table); the totals."""
    totals = {"takes": len(results), "ok": sum(r["status"] == "ok" for r in results),
              "failed": sum(r["status"] != "ok" for r in results),
              "skipped": sum(bool(r.get("skipped")) for r in results), "wall_s": round(wall_s, 3)}
    (out / "summary.json").write_text(json.dumps({**totals, "results": results}, indent=1))
    (out / "summary.md").write_text(table(results))
    return totals
