"""Runs the fuzz targets (docs/reliability.md, "Fuzzing") and prints one JSON line per target:
target, seconds, executions, crashes, hangs (timeouts), ooms, corpus size.

    python scripts/fuzz.py --build build-fuzz [--seconds N] [--only NAME ...] [--check]

C and C++ targets are the libFuzzer binaries of the fuzz build (host/fuzz, firmware/fuzz); the
Python targets are atheris scripts (tests/fuzz/). Each run starts from the committed seeds
(tests/fuzz/corpus/<target>/) and the inputs earlier runs found (.cache/fuzz/corpus/<target>/,
where new ones are written); a crashing, hanging or memory-hungry input is written to
.cache/fuzz/findings/<target>/. --runs bounds a Python target's inputs (the C/C++ targets run
for --seconds). --check: exit 1 when any target found something.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CPP = {"fuzz_wire": "host/fuzz", "fuzz_session": "host/fuzz", "fuzz_calibration": "host/fuzz",
       "fuzz_can_protocol": "firmware/fuzz", "fuzz_node_commands": "firmware/fuzz", "fuzz_slcan": "firmware/fuzz"}
PYTHON = ("fuzz_hub_frames", "fuzz_hub_config", "fuzz_take", "fuzz_bvh", "fuzz_vmc")
# Memory caps of one process (docs/reliability.md): a C/C++ target's whole process and any one
# allocation; a Python target's process (atheris has no allocation hook without a sanitizer).
RSS_LIMIT_MB, MALLOC_LIMIT_MB, PYTHON_RSS_LIMIT_MB = 2048, 256, 3072
TIMEOUT_S = 10  # one input taking longer is a hang
FINDING = re.compile(r"^(crash|timeout|oom|leak|slow-unit)-")


def command(target: str, build: Path, seconds: int, runs: int, work: Path, findings: Path) -> list[str]:
    seeds = ROOT / "tests/fuzz/corpus" / target
    common = [f"-timeout={TIMEOUT_S}", f"-artifact_prefix={findings}/", "-print_final_stats=1",
              str(work), str(seeds)]
    if target in CPP:
        binary = build / CPP[target] / target
        return [str(binary), f"-max_total_time={seconds}", f"-rss_limit_mb={RSS_LIMIT_MB}",
                f"-malloc_limit_mb={MALLOC_LIMIT_MB}", *common]
    script = ROOT / "tests/fuzz" / f"{target}.py"
    budget = [f"-runs={runs}"] if runs else [f"-max_total_time={seconds}"]
    return [sys.executable, str(script), *budget, f"-rss_limit_mb={PYTHON_RSS_LIMIT_MB}", *common]


def run(target: str, build: Path, seconds: int, runs: int) -> dict:
    work = ROOT / ".cache/fuzz/corpus" / target
    findings = ROOT / ".cache/fuzz/findings" / target
    work.mkdir(parents=True, exist_ok=True)
    findings.mkdir(parents=True, exist_ok=True)
    before = {p.name for p in findings.iterdir()}
    start = time.monotonic()
    scratch = tempfile.mkdtemp(prefix=f"mocap_{target}_")  # the target's temporary files, removed after
    env = {**os.environ, "ASAN_OPTIONS": "detect_leaks=1:allocator_may_return_null=0",
           "UBSAN_OPTIONS": "print_stacktrace=1:halt_on_error=1", "TMPDIR": scratch}
    try:
        proc = subprocess.run(command(target, build, seconds, runs, work, findings), cwd=ROOT, env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, errors="replace")
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    elapsed = time.monotonic() - start
    new = sorted(p.name for p in findings.iterdir() if p.name not in before and FINDING.match(p.name))
    log = findings / "last_run.log"
    log.write_text(proc.stdout)
    executions = re.findall(r"stat::number_of_executed_units:\s*(\d+)", proc.stdout)
    count = lambda kind: sum(n.startswith(kind) for n in new)  # noqa: E731
    crashes = count("crash") + count("leak")
    if proc.returncode != 0 and not new:  # a failure that wrote no input (e.g. a broken fixture)
        crashes += 1
    return {"target": target, "seconds": round(elapsed, 1),
            "executions": int(executions[-1]) if executions else 0,
            "crashes": crashes, "hangs": count("timeout") + count("slow-unit"), "ooms": count("oom"),
            "corpus": sum(1 for _ in work.iterdir()) + sum(1 for _ in (ROOT / "tests/fuzz/corpus" / target).iterdir()),
            "findings": [str(findings / n) for n in new], "log": str(log)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", type=Path, default=ROOT / "build-fuzz")
    parser.add_argument("--seconds", type=int, default=60, help="per target")
    parser.add_argument("--runs", type=int, default=0, help="inputs per Python target (0: --seconds)")
    parser.add_argument("--only", nargs="*", help="targets (default: all)")
    parser.add_argument("--check", action="store_true", help="exit 1 when a target found something")
    args = parser.parse_args()
    targets = args.only or [*CPP, *PYTHON]
    unknown = [t for t in targets if t not in CPP and t not in PYTHON]
    if unknown:
        parser.error(f"unknown target {unknown[0]}: {', '.join([*CPP, *PYTHON])}")
    found = False
    for target in targets:
        result = run(target, args.build.resolve(), args.seconds, args.runs)
        print(json.dumps(result), flush=True)
        found |= bool(result["crashes"] or result["hangs"] or result["ooms"])
        if found and args.check:
            sys.stderr.write(Path(result["log"]).read_text()[-6000:])
    return 1 if found and args.check else 0


if __name__ == "__main__":
    sys.exit(main())
