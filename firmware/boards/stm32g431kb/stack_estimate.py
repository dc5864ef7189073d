"""Worst-case stack depth of an ARM Thumb image, from its disassembly (objdump -d).

Each function's frame is what its own instructions reserve: `push`/`stmdb sp!` (4 bytes a
register), `vpush`/`vstmdb sp!` (4 bytes an s register, 8 a d register) and
`sub sp, #N`. Its depth is its frame plus the deepest function it calls with `bl`, or the
depth of a function it tail-calls with `b`/`b.w` (after its frame is gone). Indirect calls
(`blx rN`) reach the functions the caller names (the bus_t callbacks, for the node). A
frame sized at run time (`sub sp, rN`) or a recursion makes the estimate unbounded: both
are reported, not hidden. An estimate, not a proof: a call the disassembly does not show
(a function pointer not named) is missed.
"""

import re
import subprocess
from dataclasses import dataclass, field

FUNCTION = re.compile(r"^([0-9a-f]+) <([^>]+)>:$")
INSTRUCTION = re.compile(r"^\s*[0-9a-f]+:\s+(\S+)\s*(.*)$")
TARGET = re.compile(r"<([^>+]+)(?:\+0x[0-9a-f]+)?>")
REGISTER_LIST = re.compile(r"\{([^}]*)\}")
SUB_SP = re.compile(r"^sp,\s*(?:sp,\s*)?#(\d+)")
SUB_SP_REGISTER = re.compile(r"^sp,\s*(?:sp,\s*)?r\d+")
BRANCH = re.compile(r"^b(?:eq|ne|cs|cc|hs|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le|al)?(?:\.[nw])?$")


@dataclass
class Function:
    frame_bytes: int = 0
    calls: set = field(default_factory=set)
    tail_calls: set = field(default_factory=set)
    indirect: bool = False
    dynamic_frame: bool = False


def _register_count(text: str) -> tuple[int, str]:
    """Registers in a list such as {r4, r5, lr} or {d8-d11}: count and kind (r, s, d)."""
    match = REGISTER_LIST.search(text)
    if not match:
        return 0, "r"
    count, kind = 0, "r"
    for item in (part.strip() for part in match.group(1).split(",")):
        if "-" in item:
            first, last = item.split("-")
            kind = first[0]
            count += int(last[1:]) - int(first[1:]) + 1
        elif item:
            kind = item[0] if item[0] in "sd" else kind
            count += 1
    return count, kind


def _account(function: Function, mnemonic: str, operands: str, names: set) -> None:
    base = mnemonic.split(".")[0]
    if base == "push" or (base == "stmdb" and operands.startswith("sp!")):
        function.frame_bytes += 4 * _register_count(operands)[0]
    elif base == "vpush" or (base == "vstmdb" and operands.startswith("sp!")):
        count, kind = _register_count(operands)
        function.frame_bytes += count * (8 if kind == "d" else 4)
    elif base in ("sub", "subw") and SUB_SP.match(operands):
        function.frame_bytes += int(SUB_SP.match(operands).group(1))
    elif base in ("sub", "subw") and SUB_SP_REGISTER.match(operands):
        function.dynamic_frame = True
    elif base == "bl":
        target = TARGET.search(operands)
        if target:
            function.calls.add(target.group(1))
    elif base == "blx":
        function.indirect = True
    elif BRANCH.match(mnemonic):
        target = TARGET.search(operands)
        if target and target.group(1) in names:
            function.tail_calls.add(target.group(1))


def parse(disassembly: str) -> dict:
    names = {m.group(2) for m in map(FUNCTION.match, disassembly.splitlines()) if m}
    functions, current = {}, None
    for line in disassembly.splitlines():
        header = FUNCTION.match(line)
        if header:
            current = functions.setdefault(header.group(2), Function())
            continue
        instruction = INSTRUCTION.match(line)
        if current is not None and instruction:
            _account(current, instruction.group(1), instruction.group(2).strip(), names)
    for name, function in functions.items():
        function.tail_calls.discard(name)  # a loop's branch back to its own start
    return functions


def depth(functions: dict, root: str, indirect_targets: list) -> tuple[int, list, list]:
    """Deepest stack from `root`: bytes, the path, and what made it unbounded."""
    memo, problems = {}, []

    def visit(name: str, active: tuple) -> tuple[int, list]:
        if name in active:
            problems.append(f"recursion through {name}")
            return 0, [name]
        if name in memo:
            return memo[name]
        function = functions.get(name)
        if function is None:
            return 0, [name]
        if function.dynamic_frame:
            problems.append(f"frame sized at run time in {name}")
        callees = set(function.calls) | (set(indirect_targets) if function.indirect else set())
        best = (0, [])
        for callee in sorted(callees):
            best = max(best, visit(callee, active + (name,)), key=lambda found: found[0])
        result = (function.frame_bytes + best[0], [name] + best[1])
        for callee in sorted(function.tail_calls):
            tail = visit(callee, active + (name,))
            if tail[0] > result[0]:
                result = (tail[0], [name] + tail[1])
        memo[name] = result
        return result

    bytes_, path = visit(root, ())
    return bytes_, path, sorted(set(problems))


def disassemble(objdump: str, elf: str) -> str:
    return subprocess.run([objdump, "-d", "--no-show-raw-insn", elf], check=True,
                          capture_output=True, text=True).stdout
