"""`mocap bench --only batch`: the same takes solved one after another in this process and as a
batch on a LocalCluster of two workers — Pose2Sim's two batch-demo trials (from their videos:
detection is one more step of their tasks) and simulated takes — both timed in one run, and
the two runs' joint positions compared."""

from __future__ import annotations

import io
import tempfile
import time
from pathlib import Path

from mocap.batch import inputs, runner, task
from mocap.io.demo_data import BATCH_TRIALS, fetch_batch
from mocap.sim import take_out

SIMULATED = 8  # takes of the demo motion, seconds each below: a batch is many takes (its fixed costs shared)
SECONDS = 4.0


def bench(workers: int = 2, simulated: int = SIMULATED, seconds: float = SECONDS) -> dict:
    trials = fetch_batch()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for k in range(simulated):
            take_out.run(tmp / f"simulated_{k}", seconds=seconds, preset="hq13", seed=k)
        takes = inputs.inputs([trials / t for t in BATCH_TRIALS] + [tmp / f"simulated_{k}" for k in range(simulated)])
        started = time.monotonic()
        serial = [task.run(take, tmp / "serial", task.Options()) for take in takes]
        serial_s = time.monotonic() - started
        started = time.monotonic()
        batch = runner.run(takes, tmp / "batch", task.Options(), workers=workers, progress=io.StringIO())
        batch_s = time.monotonic() - started
        same = all((tmp / "serial" / t.name / "joints.csv").read_bytes() == (tmp / "batch" / t.name / "joints.csv")
                   .read_bytes() for t in takes)
    return {"bench": "batch", "takes": len(takes), "real_trials_from_videos": len(BATCH_TRIALS),
            "simulated_takes": simulated, "simulated_seconds": seconds, "workers": workers,
            "failed": [r["name"] for r in serial + batch if r["status"] != "ok"],
            "serial_s": round(serial_s, 2), "batch_s": round(batch_s, 2), "speedup": round(serial_s / batch_s, 2),
            "joints_identical": same,
            "per_take_s": {r["name"]: r.get("seconds") for r in serial}}
