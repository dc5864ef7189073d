"""The IMU node's firmware run in qemu-system-arm, for the QEMU tests and the benchmark.

- :class:`Qemu`: one QEMU process (a board image), always killed when it leaves its
  ``with`` block or when Python exits; optional QMP socket and serial lines.
- :class:`Qmp`: the QEMU Machine Protocol (set a sensor model's properties, resume).
- :func:`slcan_bus`: python-can's SLCAN bus on a UART that QEMU serves over TCP.
- :func:`run_filter`: the orientation filter on samples in the mps2-an386 image (a
  Cortex-M4F) under ``-icount shift=0``, giving its quaternions and its instructions
  per sample (firmware/boards/mps2_an386/README.md has the method).

The images are built by ``cmake --build build --target firmware_boards``; they are found
in ``$MOCAP_FIRMWARE_BOARDS`` or else ``build/firmware/boards`` of the repository.
"""

from __future__ import annotations

import atexit
import json
import os
import select
import shutil
import socket
import struct
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mocap.paths import REPO

QEMU_BINARY = "qemu-system-arm"
FILTER_INPUT_MAGIC = 0x31554D49  # "IMU1", firmware/boards/mps2_an386/filter_runner.c
FILTER_INPUT_9D = 1

_running: set[subprocess.Popen] = set()


def _kill_all() -> None:
    for process in list(_running):
        _kill(process)


atexit.register(_kill_all)


def _kill(process: subprocess.Popen) -> None:
    if process.poll() is None:
        process.kill()
    process.wait()
    _running.discard(process)


def qemu_available() -> bool:
    """True when qemu-system-arm is installed."""
    return shutil.which(QEMU_BINARY) is not None


def boards_dir() -> Path:
    """The build folder of the board images."""
    return Path(os.environ.get("MOCAP_FIRMWARE_BOARDS", REPO / "build" / "firmware" / "boards"))


def board_image(board: str, name: str) -> Path:
    """The .elf image `name` of `board`; FileNotFoundError when it was not built."""
    path = boards_dir() / board / f"{name}.elf"
    if not path.is_file():
        raise FileNotFoundError(f"{path} is absent: build it with `cmake --build build --target firmware_boards`")
    return path


def free_tcp_port() -> int:
    """A TCP port free on 127.0.0.1 now (the kernel's choice). Another process may take it
    before QEMU binds it: :class:`Qemu` then fails to start and callers retry."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


class QemuError(RuntimeError):
    pass


class Qemu:
    """One qemu-system-arm process running `image` on `machine`.

    `args` are added to the command line (devices, serial ports, -icount ...). With
    `qmp=True` the machine starts paused (-S) with a QMP socket: call :meth:`qmp`, set
    properties, then ``qmp.command("cont")``. With `stdio=True` the first serial port is
    the process's stdin/stdout (:meth:`send_line`, :meth:`read_line`). Semihosting is on:
    exit codes, files relative to `cwd` (a temporary folder by default), and its console
    (SYS_WRITE0) collected in a file that :meth:`wait` returns.
    """

    def __init__(
        self,
        machine: str,
        image: Path,
        args: tuple[str, ...] | list[str] = (),
        *,
        qmp: bool = False,
        stdio: bool = False,
        cwd: Path | None = None,
    ) -> None:
        self._own_dir = tempfile.TemporaryDirectory(prefix="mocap-qemu-")
        own = Path(self._own_dir.name)
        self.cwd = Path(cwd) if cwd is not None else own
        self.qmp_path = own / "qmp.sock" if qmp else None
        self._console_path = own / "console.txt"
        self._stderr_path = own / "stderr.txt"
        command = [QEMU_BINARY, "-M", machine, "-kernel", str(image), "-display", "none", "-monitor", "none",
                   "-chardev", f"file,id=semihosting,path={self._console_path}",
                   "-semihosting-config", "enable=on,target=native,chardev=semihosting"]
        if self.qmp_path is not None:
            command += ["-qmp", f"unix:{self.qmp_path},server=on,wait=off", "-S"]
        if stdio:
            command += ["-serial", "stdio"]
        command += list(args)
        self.command = command
        self._buffer = b""
        self._qmp: Qmp | None = None
        with open(self._stderr_path, "wb") as stderr:
            self.process = subprocess.Popen(
                command, cwd=self.cwd, stdin=subprocess.PIPE if stdio else subprocess.DEVNULL,
                stdout=subprocess.PIPE if stdio else subprocess.DEVNULL, stderr=stderr)
        _running.add(self.process)

    def __enter__(self) -> Qemu:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Kills QEMU (if still running) and removes its temporary files."""
        if self._qmp is not None:
            self._qmp.close()
            self._qmp = None
        _kill(self.process)
        for stream in (self.process.stdin, self.process.stdout):
            if stream is not None:
                stream.close()
        self._own_dir.cleanup()

    def qmp(self, timeout_s: float = 5.0) -> Qmp:
        """The QMP connection (connected and negotiated on first use)."""
        if self.qmp_path is None:
            raise QemuError("QEMU was started without qmp=True")
        if self._qmp is None:
            self._qmp = Qmp.connect(self.qmp_path, timeout_s, self.process)
        return self._qmp

    def send_line(self, line: str) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write(line.encode() + b"\n")
        self.process.stdin.flush()

    def read_line(self, timeout_s: float = 5.0) -> str:
        """The next line the firmware wrote on the stdio serial port."""
        assert self.process.stdout is not None
        deadline = time.monotonic() + timeout_s
        fd = self.process.stdout.fileno()
        while b"\n" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"no line from the firmware within {timeout_s} s ({self._buffer!r})")
            ready, _, _ = select.select([fd], [], [], left)
            if ready:
                chunk = os.read(fd, 4096)
                if not chunk:
                    raise QemuError(f"QEMU ended: {self.stderr_text()}")
                self._buffer += chunk
        line, self._buffer = self._buffer.split(b"\n", 1)
        return line.decode(errors="replace").rstrip("\r")

    def wait(self, timeout_s: float) -> tuple[int, str]:
        """Waits for the run to end; its exit code and what it wrote on semihosting's
        console. TimeoutError (QEMU killed) when it runs longer than `timeout_s`."""
        try:
            code = self.process.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            _kill(self.process)
            raise TimeoutError(f"QEMU ran longer than {timeout_s} s: {' '.join(self.command)}") from None
        _running.discard(self.process)
        return code, self._console_path.read_text(errors="replace") if self._console_path.exists() else ""

    def stderr_text(self) -> str:
        """What QEMU wrote on its standard error so far."""
        return self._stderr_path.read_text(errors="replace")


class Qmp:
    """A QMP client on QEMU's unix socket: JSON commands, asynchronous events skipped."""

    def __init__(self, sock: socket.socket) -> None:
        self._socket = sock
        self._file = sock.makefile("rwb")

    @classmethod
    def connect(cls, path: Path, timeout_s: float, process: subprocess.Popen) -> Qmp:
        deadline = time.monotonic() + timeout_s
        while True:
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            try:
                sock.connect(str(path))
                break
            except (FileNotFoundError, ConnectionRefusedError):
                sock.close()
                if process.poll() is not None or time.monotonic() > deadline:
                    raise QemuError(f"no QMP socket at {path} (QEMU exit code {process.poll()})") from None
                time.sleep(0.01)
        sock.settimeout(timeout_s)
        qmp = cls(sock)
        greeting = qmp._receive()
        if "QMP" not in greeting:
            raise QemuError(f"not a QMP greeting: {greeting}")
        qmp.command("qmp_capabilities")
        return qmp

    def _receive(self) -> dict:
        line = self._file.readline()
        if not line:
            raise QemuError("QMP connection closed")
        return json.loads(line)

    def command(self, name: str, **arguments: object) -> object:
        """Runs `name`; its "return" value, or QemuError with QEMU's error text."""
        message: dict[str, object] = {"execute": name}
        if arguments:
            message["arguments"] = arguments
        self._file.write(json.dumps(message).encode() + b"\n")
        self._file.flush()
        while True:
            reply = self._receive()
            if "return" in reply:
                return reply["return"]
            if "error" in reply:
                raise QemuError(f"QMP {name}: {reply['error'].get('desc', reply['error'])}")

    def set_property(self, path: str, name: str, value: object) -> None:
        self.command("qom-set", path=path, property=name, value=value)

    def get_property(self, path: str, name: str) -> object:
        return self.command("qom-get", path=path, property=name)

    def close(self) -> None:
        self._file.close()
        self._socket.close()


def slcan_bus(port: int, timeout_s: float = 5.0, process: subprocess.Popen | None = None):
    """python-can's SLCAN bus on QEMU's TCP serial port `port` (`-serial
    tcp:127.0.0.1:PORT,server=on,wait=off`), 1 Mbit/s; retried until QEMU listens."""
    import can  # python-can: only the SLCAN tests need it

    deadline = time.monotonic() + timeout_s
    while True:
        try:
            return can.Bus(interface="slcan", channel=f"socket://127.0.0.1:{port}", bitrate=1000000,
                           sleep_after_open=0.0)
        except can.CanInitializationError:
            if (process is not None and process.poll() is not None) or time.monotonic() > deadline:
                raise
            time.sleep(0.02)


def start_slcan_node(image: Path, log_path: Path, args: tuple[str, ...] | list[str] = (),
                     setup=None, attempts: int = 3):
    """The QEMU node (lm3s6965evb) of start_slcan_qemu, its UART0 opened as an SLCAN bus
    here. Returns (Qemu, can.BusABC); close both."""
    qemu, port = start_slcan_qemu(image, log_path, args, setup, attempts)
    return qemu, slcan_bus(port, process=qemu.process)


def start_slcan_qemu(image: Path, log_path: Path, args: tuple[str, ...] | list[str] = (),
                     setup=None, attempts: int = 3) -> tuple[Qemu, int]:
    """The QEMU node (lm3s6965evb) running: UART0 served on a free TCP port (for an SLCAN
    client: `slcan:socket://127.0.0.1:PORT`), UART1 (the firmware's log) written to
    `log_path`. `setup(qmp)` runs while the machine is still paused (set sensor models).
    Returns (Qemu, port); close the Qemu. A port taken between its choice and QEMU's bind
    makes QEMU exit: retried."""
    for attempt in range(attempts):
        port = free_tcp_port()
        serial = ["-serial", f"tcp:127.0.0.1:{port},server=on,wait=off", "-serial", f"file:{log_path}"]
        qemu = Qemu("lm3s6965evb", image, [*serial, *args], qmp=True)
        try:
            qmp = qemu.qmp()  # QMP answers once the serial ports listen
            if setup is not None:
                setup(qmp)
            qmp.command("cont")
            return qemu, port
        except Exception as error:
            failed_early = qemu.process.poll() is not None
            stderr = qemu.stderr_text()
            qemu.close()
            if not failed_early or attempt + 1 == attempts:
                raise QemuError(f"the QEMU node did not start: {stderr}") from error
    raise AssertionError("unreachable")


@dataclass
class FilterRun:
    """The filter run in QEMU on one recording."""

    quaternions: np.ndarray  # (N, 4) float32, w x y z, sensor -> ENU
    samples: int
    chunk_samples: int  # samples per timed loop
    filter_ticks: int  # SysTick ticks in the filter's loops
    empty_ticks: int  # SysTick ticks in the same loops with empty functions
    calibration_ticks: int  # SysTick ticks of the calibration loop
    calibration_instructions: int  # instructions of the calibration loop

    @property
    def instructions_per_tick(self) -> float:
        return self.calibration_instructions / self.calibration_ticks

    @property
    def instructions_per_sample(self) -> float:
        """The filter's instructions per sample (update and quaternion read-out)."""
        return (self.filter_ticks - self.empty_ticks) * self.instructions_per_tick / self.samples

    @property
    def resolution_instructions_per_sample(self) -> float:
        """Worst case of the tick quantisation: one tick of each of the two loops per
        chunk, per sample."""
        chunks = -(-self.samples // self.chunk_samples)
        return 2.0 * self.instructions_per_tick * chunks / self.samples


def _filter_input(gyr_rads: np.ndarray, acc_mps2: np.ndarray, mag_ut: np.ndarray | None,
                  sample_period_s: float) -> bytes:
    samples = len(gyr_rads)
    mag = np.zeros((samples, 3), np.float32) if mag_ut is None else mag_ut
    rows = np.hstack([gyr_rads, acc_mps2, mag]).astype("<f4")
    flags = 0 if mag_ut is None else FILTER_INPUT_9D
    header = struct.pack("<IIfI", FILTER_INPUT_MAGIC, samples, sample_period_s, flags)
    return header + rows.tobytes()


def run_filter(gyr_rads: np.ndarray, acc_mps2: np.ndarray, mag_ut: np.ndarray | None,
               sample_period_s: float, timeout_s: float = 60.0) -> FilterRun:
    """The node's filter in the mps2-an386 image (Cortex-M4F, -icount shift=0) on these
    samples (sensor frame; mag_ut None: 6D). Its quaternions and instruction counts."""
    image = board_image("mps2_an386", "mps2_an386_filter")
    with tempfile.TemporaryDirectory(prefix="mocap-filter-") as folder:
        work = Path(folder)
        (work / "imu_in.bin").write_bytes(_filter_input(gyr_rads, acc_mps2, mag_ut, sample_period_s))
        with Qemu("mps2-an386", image, ["-icount", "shift=0", "-serial", "null"], cwd=work) as qemu:
            code, out = qemu.wait(timeout_s)
            if code != 0:
                raise QemuError(f"filter image exit code {code}: {out}{qemu.stderr_text()}")
        fields = _report_fields(out, "filter")
        quaternions = np.fromfile(work / "imu_out.bin", dtype="<f4").reshape(-1, 4)
    if len(quaternions) != len(gyr_rads):
        raise QemuError(f"{len(quaternions)} quaternions for {len(gyr_rads)} samples")
    return FilterRun(quaternions=quaternions, samples=fields["samples"], chunk_samples=fields["chunk_samples"],
                     filter_ticks=fields["filter_ticks"],
                     empty_ticks=fields["empty_ticks"], calibration_ticks=fields["calibration_ticks"],
                     calibration_instructions=fields["calibration_instructions"])


def _report_fields(text: str, tag: str) -> dict[str, int]:
    for line in text.splitlines():
        words = line.split()
        if words and words[0] == tag:
            return {key: int(value) for key, value in (word.split("=", 1) for word in words[1:])}
    raise QemuError(f"no `{tag}` report in the output: {text!r}")


def filter_instructions_per_sample(gyr_rads: np.ndarray, acc_mps2: np.ndarray, mag_ut: np.ndarray,
                                   sample_period_s: float) -> dict[str, float]:
    """The filter's cost on the production CPU's core (Cortex-M4F in QEMU, -icount
    shift=0), instructions per sample: {"9d": ..., "6d": ..., "resolution": ...}."""
    nine = run_filter(gyr_rads, acc_mps2, mag_ut, sample_period_s)
    six = run_filter(gyr_rads, acc_mps2, None, sample_period_s)
    return {"9d": nine.instructions_per_sample, "6d": six.instructions_per_sample,
            "resolution": max(nine.resolution_instructions_per_sample, six.resolution_instructions_per_sample)}
