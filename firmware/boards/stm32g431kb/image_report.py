#!/usr/bin/env python3
"""Checks the production node's image and writes its flash and RAM use (size.json).

Run after the link (CMakeLists.txt does):
  image_report.py --elf node_stm32g431kb.elf --map node_stm32g431kb.map --out size.json
Flash = every allocated section in flash plus .data's initial values; RAM = .stack +
.data + .bss (no heap). Checks, each failing the build: the vector table (118 words at
the start of flash, initial stack pointer = the stack's top, reset and every handler odd
(Thumb) in flash, the board's interrupts in their slots, the default handler everywhere
else), the stack at the bottom of RAM under its guard, every section inside its region,
and no heap or printf pulled in. Also a summary of the link map by component and a static
estimate of the worst stack depth (stack_estimate.py).
"""

import argparse
import json
import os
import re
import struct
import subprocess
import sys
import tempfile

import stack_estimate

FLASH = (0x08000000, 126 * 1024)
RAM = (0x20000000, 22 * 1024)
VECTOR_WORDS = 16 + 102
CORE_RESERVED = (7, 8, 9, 10, 13)
CORE_FAULTS = (2, 3, 4, 5, 6)  # NMI, HardFault, MemManage, BusFault, UsageFault
BOARD_IRQS = {21: "board_fdcan1_it0_isr", 28: "board_tim2_isr"}
FORBIDDEN = ("malloc", "_sbrk", "printf", "_printf_r", "_vfprintf_r")
ISR_ROOTS = ("board_tim2_isr", "board_fdcan1_it0_isr")
FP_EXCEPTION_FRAME_BYTES = 26 * 4 + 4  # extended frame (FPU in use) + alignment
SECTION = re.compile(
    r"^\s*\[\s*\d+\]\s+(\S+)\s+(\S+)\s+([0-9a-f]+)\s+[0-9a-f]+\s+([0-9a-f]+)\s+\S+\s+(\S*)")


def inside(region, address, size=0):
    return region[0] <= address and address + size <= region[0] + region[1]


def tool(prefix, name, *args):
    return subprocess.run([prefix + name, *args], check=True, capture_output=True,
                          text=True).stdout


def sections(prefix, elf):
    """Allocated sections: name -> (address, size, has file contents)."""
    found = {}
    for line in tool(prefix, "readelf", "-S", "-W", elf).splitlines():
        match = SECTION.match(line)
        if match and "A" in match.group(5):
            found[match.group(1)] = (int(match.group(3), 16), int(match.group(4), 16),
                                     match.group(2) != "NOBITS")
    return found


def symbols(prefix, elf):
    table = {}
    for line in tool(prefix, "nm", elf).splitlines():
        parts = line.split()
        if len(parts) == 3:
            table[parts[2]] = int(parts[0], 16)
    return table


def vector_words(prefix, elf):
    with tempfile.TemporaryDirectory() as scratch:
        path = os.path.join(scratch, "vectors.bin")
        tool(prefix, "objcopy", "-O", "binary", "--only-section=.isr_vector", elf, path)
        with open(path, "rb") as handle:
            data = handle.read()
    return list(struct.unpack(f"<{len(data) // 4}I", data[: len(data) // 4 * 4]))


def check_vectors(words, table):
    problems = []
    if len(words) != VECTOR_WORDS:
        return [f"vector table has {len(words)} words, the G431 needs {VECTOR_WORDS}"]
    if words[0] != table.get("g4_stack_top") or not inside(RAM, words[0] - 1) or words[0] % 8:
        problems.append(f"initial stack pointer {words[0]:#x} is not the stack's top")
    if words[1] != table.get("g4_reset_handler", -2) | 1:
        problems.append(f"reset vector {words[1]:#x} is not g4_reset_handler | 1 (Thumb)")
    for index in range(1, VECTOR_WORDS):
        word = words[index]
        if index in CORE_RESERVED:
            if word:
                problems.append(f"reserved vector {index} is {word:#x}, not 0")
        elif word % 2 == 0 or not inside(FLASH, word - 1):
            problems.append(f"vector {index} = {word:#x} is not an odd flash address")
    for index in CORE_FAULTS:
        if words[index] != table.get("g4_fault_handler", -2) | 1:
            problems.append(f"core vector {index} does not reset through g4_fault_handler")
    default = table.get("g4_default_handler", -2) | 1
    for irq in range(VECTOR_WORDS - 16):
        expected = table.get(BOARD_IRQS[irq], -2) | 1 if irq in BOARD_IRQS else default
        if words[16 + irq] != expected:
            problems.append(f"IRQ {irq} vector {words[16 + irq]:#x}, expected {expected:#x}")
    return problems


def check_layout(found, table, stack_bytes):
    problems = []
    for name, (address, size, _) in found.items():
        if not (inside(FLASH, address, size) or inside(RAM, address, size)):
            problems.append(f"section {name} at {address:#x}+{size} is outside flash and RAM")
    if found.get(".isr_vector", (None,))[0] != FLASH[0]:
        problems.append(".isr_vector does not start the flash")
    bottom, top = table.get("g4_stack_bottom"), table.get("g4_stack_top")
    if bottom != RAM[0] or bottom % 32:
        problems.append(f"stack bottom {bottom} is not RAM's start (32-byte aligned guard)")
    elif top - bottom != stack_bytes:
        problems.append(f"stack is {top - bottom} bytes, {stack_bytes} requested")
    problems += [f"{name} is linked in (no heap, no printf)" for name in FORBIDDEN if name in table]
    return problems


def memory_use(found):
    flash = sum(size for address, size, _ in found.values() if inside(FLASH, address))
    ram = sum(size for address, size, _ in found.values() if inside(RAM, address))
    flash += sum(size for address, size, loaded in found.values()
                 if inside(RAM, address) and loaded)  # .data's initial values
    return flash, ram


def component(path):
    if "stm32g431kb_board.dir" in path or "node_stm32g431kb.dir" in path:
        return "board"
    for library, name in (("libnode_core_cortex_m4f.a", "node_core"), ("libc_nano.a", "libc_nano"),
                          ("libm.a", "libm"), ("libgcc.a", "libgcc")):
        if library in path:
            return name
    return "other"


def map_summary(map_path):
    """Bytes of flash and RAM per component and per object, from the link map."""
    per_component, per_object, output, pending = {}, {}, "", None
    entry = re.compile(r"^ (\.\S+)?\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$")
    with open(map_path, encoding="utf-8", errors="replace") as handle:
        text = handle.read()
    text = text.split("Linker script and memory map", 1)[-1]
    for line in text.splitlines():
        if re.match(r"^\.\S+", line):
            output = line.split()[0]
            continue
        if re.match(r"^ \.\S+$", line):
            pending = line.strip()
            continue
        match = entry.match(line)
        if not match or (match.group(1) is None and pending is None):
            pending = None
            continue
        pending = None
        address, size, path = int(match.group(2), 16), int(match.group(3), 16), match.group(4)
        ram = size if inside(RAM, address) else 0
        flash = size if inside(FLASH, address) or (ram and output == ".data") else 0
        if not flash and not ram:
            continue
        name = component(path)
        obj = re.sub(r"^.*\((.*)\)$", r"\1", path).rsplit("/", 1)[-1]
        for table, key in ((per_component, name), (per_object, f"{name}:{obj}")):
            totals = table.setdefault(key, {"flash": 0, "ram": 0})
            totals["flash"] += flash
            totals["ram"] += ram
    largest = sorted(per_object.items(), key=lambda item: -item[1]["flash"] - item[1]["ram"])
    return per_component, [{"object": key, **value} for key, value in largest[:12]]


def stack_report(prefix, elf, stack_bytes):
    functions = stack_estimate.parse(stack_estimate.disassemble(prefix + "objdump", elf))
    callbacks = ["g4_i2c_read", "g4_i2c_write", "g4_i2c_delay_us", "g4_i2c_now_us"]
    thread = stack_estimate.depth(functions, "board_main", callbacks)
    isrs = [stack_estimate.depth(functions, root, callbacks) for root in ISR_ROOTS]
    isr = max(isrs, key=lambda found: found[0])
    # Thread, one interrupt (both have one priority: no nesting), and a fault's stacking.
    worst = thread[0] + FP_EXCEPTION_FRAME_BYTES + isr[0] + FP_EXCEPTION_FRAME_BYTES
    return {"thread_bytes": thread[0], "thread_path": thread[1],
            "interrupt_bytes": isr[0], "interrupt_path": isr[1],
            "exception_frame_bytes": FP_EXCEPTION_FRAME_BYTES,
            "worst_case_bytes": worst, "reserved_bytes": stack_bytes,
            "usable_bytes": stack_bytes - 32, "indirect_targets_assumed": callbacks,
            "unbounded_because": sorted(set(thread[2] + isr[2]))}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elf", required=True)
    parser.add_argument("--map", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--tool-prefix", default="arm-none-eabi-")
    parser.add_argument("--flash-budget", type=int, default=65536)
    parser.add_argument("--ram-budget", type=int, default=16384)
    args = parser.parse_args()
    found, table = sections(args.tool_prefix, args.elf), symbols(args.tool_prefix, args.elf)
    stack_bytes = found.get(".stack", (0, 0, False))[1]
    problems = check_vectors(vector_words(args.tool_prefix, args.elf), table)
    problems += check_layout(found, table, stack_bytes)
    flash, ram = memory_use(found)
    per_component, largest = map_summary(args.map)
    stack = stack_report(args.tool_prefix, args.elf, stack_bytes)
    if stack["worst_case_bytes"] > stack["usable_bytes"] and not stack["unbounded_because"]:
        problems.append(f"stack estimate {stack['worst_case_bytes']} B exceeds the "
                        f"{stack['usable_bytes']} usable bytes")
    report = {"board": "stm32g431kb", "part": "STM32G431KBU6",
              "flash_bytes": flash, "ram_bytes": ram,
              "flash_budget_bytes": args.flash_budget, "ram_budget_bytes": args.ram_budget,
              "within_budget": flash <= args.flash_budget and ram <= args.ram_budget,
              "sections": {name: size for name, (_, size, _) in sorted(found.items())},
              "by_component": per_component, "largest_objects": largest, "stack": stack,
              "checks_passed": not problems, "problems": problems}
    with open(args.out, "w", encoding="utf-8") as handle:
        json.dump(report, handle, indent=2)
        handle.write("\n")
    print(tool(args.tool_prefix, "size", args.elf).rstrip())
    print(f"stm32g431kb: flash {flash} B (budget {args.flash_budget}), RAM {ram} B "
          f"(budget {args.ram_budget}; stack {stack_bytes}, worst-case estimate "
          f"{stack['worst_case_bytes']}) -> {args.out}")
    for name, totals in sorted(per_component.items()):
        print(f"  {name:<10} flash {totals['flash']:>6} B  RAM {totals['ram']:>6} B")
    for problem in problems:
        print(f"stm32g431kb: CHECK FAILED: {problem}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
