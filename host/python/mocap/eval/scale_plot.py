"""The scale benchmark's figure (`mocap bench --only scale --plot PNG`): the per-frame solve's
median and p99 against the number of cameras, beside the line a cost proportional to the
cameras would follow from the 8-camera figure."""

from __future__ import annotations

from pathlib import Path


def plot(result: dict, png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = {int(n): r for n, r in result["cameras"].items()}
    n = sorted(rows)
    fig, ax = plt.subplots(figsize=(6, 4), dpi=100)
    ax.plot(n, [rows[k]["median_ms"] for k in n], "o-", label="median")
    ax.plot(n, [rows[k]["p99_ms"] for k in n], "s--", label="p99")
    ax.plot(n, [rows[8]["median_ms"] * k / 8 for k in n], ":", color="grey", label="proportional to the cameras")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xticks(n, [str(k) for k in n])
    ax.set_xlabel("cameras (33 keypoints each, 13 IMUs)")
    ax.set_ylabel("solve per frame, ms (one core)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(png)
    plt.close(fig)
