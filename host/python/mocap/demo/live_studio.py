"""The simulated studio's processes held one by one, for the crash drills and the soak
(mocap.demo.drill, mocap.demo.soak): mocapd, one camera box per camera, the IMU hub (beside
its simulated sensor nodes) and the recorder, each killed (SIGKILL) and started again by name
as systemd would (a box started again captures from then on: `--from-open`); a watcher thread collects mocapd's PoseFrame and Health with their arrival
times, and a drill waits on what it sees (`wait`), never on the clock alone."""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable
from pathlib import Path

import zmq

from mocap import processes
from mocap.demo import play
from mocap.demo.studio import Studio
from mocap.errors import InputError
from mocap.net import transport, wire

STOP_TIMEOUT_S = 10.0


@dataclasses.dataclass
class Arrived:
    time_ns: int  # arrival at the watcher
    message: object  # wire.PoseFrame or wire.Health


class LiveStudio:
    """The studio's processes for a take starting `lead_s` after start(); `record`: a
    recorder records every stream into that file for `record_s` (default: the take and the
    lead); `realtime`: mocapd asks for SCHED_FIFO at play.REALTIME_PRIORITY, as a deployed host.
    Use as a context manager: every process it started ends with it."""

    def __init__(self, studio: Studio, lead_s: float = play.LEAD_S, record: Path | None = None,
                 record_s: float | None = None, camera_args: dict[str, list[str]] | None = None,
                 realtime: bool = False, pin_host: bool = False) -> None:
        self.studio, self.lead_s, self.record, self.realtime = studio, lead_s, record, realtime
        # pin_host: mocapd alone on the last core, every other process (this one's threads started
        # from then on too) on the others, as systemd's CPUAffinity= would on a deployed host
        self.cores = processes.host_and_edge_cores() if pin_host else None
        self.record_s = record_s if record_s is not None else lead_s + float(studio.frame_times[-1]) + 2.0
        self.camera_args = camera_args or {}  # extra arguments of a camera's box
        self.processes: dict[str, subprocess.Popen] = {}
        self.commands: dict[str, list[str]] = {}
        self.arrived: list[Arrived] = []
        self.start_ns = 0
        self._changed = threading.Condition()
        self._stopping = threading.Event()
        self._watcher: threading.Thread | None = None
        self._nodes: subprocess.Popen | None = None
        self._caller_cores: set[int] | None = None

    def start(self) -> None:
        """Starts mocapd, the boxes, the nodes and hub, the recorder and the watcher."""
        self.start_ns = time.time_ns() + int(self.lead_s * 1e9)
        priority = ["--realtime", str(play.REALTIME_PRIORITY)] if self.realtime else []
        self.commands["mocapd"] = [str(play.MOCAPD), str(self.studio.session), "--quiet", *priority]
        for c, camera in enumerate(self.studio.camera_ids):
            self.commands[camera] = [*play.camera_box_command(self.studio, c, self.start_ns), "--from-open",
                                     *self.camera_args.get(camera, [])]
        if self.cores:
            self._caller_cores = os.sched_getaffinity(0)  # given back at stop()
            os.sched_setaffinity(0, self.cores[1])  # this thread, and the watcher it starts
        self._nodes, port = play.start_sim_nodes(self.studio, self.start_ns)
        if self.cores:
            processes.pin(self._nodes.pid, self.cores[1])
        self.commands["hub"] = play.imu_hub_command(self.studio, port)
        if self.record:
            self.commands["recorder"] = play.recorder_command(self.studio, self.record, self.record_s - 2.0)
        for name in self.commands:
            self.restart(name)
        self._watcher = threading.Thread(target=self._watch, name="live-studio-watcher", daemon=True)
        self._watcher.start()

    def restart(self, name: str) -> int:
        """Starts process `name` (again) with its command; the time it was started (ns)."""
        started = time.time_ns()
        cores = None if self.cores is None else {self.cores[0]} if name == "mocapd" else self.cores[1]
        self.processes[name] = subprocess.Popen(self.commands[name], stdout=subprocess.DEVNULL,
                                                preexec_fn=(lambda: os.sched_setaffinity(0, cores)) if cores else None)
        return started

    def kill(self, name: str) -> int:
        """SIGKILL to process `name`, reaped; the time it was sent (ns)."""
        process = self.processes[name]
        sent = time.time_ns()
        process.send_signal(signal.SIGKILL)
        process.wait(timeout=STOP_TIMEOUT_S)
        return sent

    def pids(self) -> dict[str, int]:
        """The pid of every process of the studio still running, by name ("nodes": the sensor nodes)."""
        out = {n: p.pid for n, p in self.processes.items() if p.poll() is None}
        if self._nodes is not None and self._nodes.poll() is None:
            out["nodes"] = self._nodes.pid
        return out

    def scheduled_realtime(self, name: str) -> bool | None:
        """Whether process `name` runs under SCHED_FIFO now; None once it ended."""
        try:
            return os.sched_getscheduler(self.processes[name].pid) == os.SCHED_FIFO
        except (KeyError, ProcessLookupError):
            return None

    def cores_of(self, name: str) -> list[int] | None:
        """The cores process `name` may run on now; None once it ended."""
        try:
            return sorted(os.sched_getaffinity(self.processes[name].pid))
        except (KeyError, ProcessLookupError):
            return None

    def take_s(self, t_ns: int) -> float:
        return (t_ns - self.start_ns) * 1e-9

    def wait(self, found: Callable[[list[Arrived]], object], timeout_s: float, what: str) -> object:
        """Until found(arrived so far) is truthy (checked at every arrival); its value.
        InputError naming `what` after timeout_s."""
        deadline = time.monotonic() + timeout_s
        with self._changed:
            while not (value := found(self.arrived)):
                left = deadline - time.monotonic()
                if left <= 0:
                    raise InputError(f"not seen within {timeout_s:.1f} s: {what}")
                self._changed.wait(left)
        return value

    def poses(self) -> list[Arrived]:
        with self._changed:
            return [a for a in self.arrived if isinstance(a.message, wire.PoseFrame)]

    def healths(self) -> list[Arrived]:
        with self._changed:
            return [a for a in self.arrived if isinstance(a.message, wire.Health)]

    def _watch(self) -> None:
        sub = transport.subscriber(zmq.Context.instance(), [self.studio.endpoints["host"]])
        try:
            while not self._stopping.is_set():
                if not sub.poll(100):
                    continue
                try:
                    message = wire.decode(sub.recv_multipart())
                except wire.WireError:
                    continue
                if isinstance(message, (wire.PoseFrame, wire.Health)):
                    with self._changed:
                        self.arrived.append(Arrived(time.time_ns(), message))
                        self._changed.notify_all()
        finally:
            sub.close(linger=0)

    def stop(self) -> None:
        """Stops every process — the edge and mocapd, then the sensor nodes (the hub never sees
        its bus go away), then the recorder with SIGINT (its file closed whole) — and the watcher."""
        recorder = self.processes.get("recorder")
        order = [[p for p in self.processes.values() if p is not recorder], [self._nodes], [recorder]]
        for group in order:
            group = [p for p in group if p is not None]
            for process in group:
                if process.poll() is None:
                    process.send_signal(signal.SIGINT if process is recorder else signal.SIGTERM)
            for process in group:
                try:
                    process.wait(timeout=STOP_TIMEOUT_S)
                except subprocess.TimeoutExpired:
                    os.kill(process.pid, signal.SIGKILL)
                    process.wait()
        self._stopping.set()
        if self._watcher is not None:
            self._watcher.join(timeout=STOP_TIMEOUT_S)
        if self._caller_cores is not None:
            os.sched_setaffinity(0, self._caller_cores)

    def __enter__(self) -> LiveStudio:
        try:
            self.start()
        except BaseException:
            self.stop()
            raise
        return self

    def __exit__(self, *_) -> None:
        self.stop()
